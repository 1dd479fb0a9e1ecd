// A small seeded random generator whose streams are the same on every platform.
//
// Why our own: the std:: engines are portable but the std:: distributions are not (their
// algorithms are implementation-defined), so a scene or a jitter pattern drawn through
// them could differ between libstdc++ and libc++. Procedural scenes and stratified pixel
// samples must be identical everywhere for results to be comparable, so both draw from
// this generator only.
#pragma once

#include <cstdint>

#include "accelbench/base/geometry.h"

namespace accelbench {

// SplitMix64 (Steele, Lea, Flood 2014, "Fast splittable pseudorandom number
// generators"; the constants are those of java.util.SplittableRandom). One 64-bit word of
// state, every seed valid, good enough statistics for placing geometry and jittering
// samples.
class SplitMix64 {
public:
    explicit SplitMix64(uint64_t seed) : state_(seed) {}

    uint64_t next_u64() {
        uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }

    // Uniform in [0, 1): the top 24 bits, so every value is exactly representable.
    float uniform() { return float(next_u64() >> 40) * (1.0f / float(1u << 24)); }
    float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
    // Uniform integer in [0, n) for n > 0 (multiply-shift: no modulo bias worth noting at
    // the sizes used here).
    uint32_t below(uint32_t n) { return uint32_t(((next_u64() >> 32) * uint64_t(n)) >> 32); }

    // Uniform direction on the unit sphere (Archimedes: z uniform, angle uniform).
    Vec3 unit_vector() {
        const float z = uniform(-1.0f, 1.0f);
        const float phi = 6.28318531f * uniform();
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        return {r * std::cos(phi), r * std::sin(phi), z};
    }

private:
    uint64_t state_;
};

// Mixes several values into one well-spread seed, so that e.g. (image seed, pixel,
// sample) gives an independent stream per sample whatever order samples are drawn in.
inline uint64_t mix_seed(uint64_t a, uint64_t b) {
    SplitMix64 g(a ^ (b * 0xD1B54A32D192ED03ull));
    return g.next_u64();
}

}  // namespace accelbench
