// Embree 3 as the baseline row: the production ray tracing kernels every other row is
// measured against, answering the same rays through rtcIntersect1 / rtcOccluded1.
#pragma once

#include <embree3/rtcore.h>

#include <string>

#include "accelbench/accel/accelerator.h"

namespace accelbench {

class EmbreeAccel final : public Accelerator {
public:
    // The parameters: each member's initializer is its default; embree_accel.cpp's table
    // declares them.
    struct Config {
        int threads = 1;                                     // device build threads (0: Embree's all cores)
        RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;  // RTC_BUILD_QUALITY_*
        bool robust = false;                                 // RTC_SCENE_FLAG_ROBUST: watertight, slower
        bool compact = false;                                // RTC_SCENE_FLAG_COMPACT: less memory
        // The device's max_isa: the best kernels Embree may pick, or none ("auto"). "avx2" is
        // the fair row beside our AVX2 code, and the one valgrind can run.
        std::string max_isa = "auto";
        static Config from(const ParamSet& params);
    };

    static AcceleratorInfo info();
    explicit EmbreeAccel(const Config& config);
    ~EmbreeAccel() override;
    EmbreeAccel(const EmbreeAccel&) = delete;
    EmbreeAccel& operator=(const EmbreeAccel&) = delete;

    void build(const Scene& scene) override;
    void closest_hits(std::span<const Ray> rays, std::span<Hit> hits, std::span<RayStats> stats = {}) const override;
    void any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded,
                  std::span<RayStats> stats = {}) const override;
    // Embree does not expose node counts or per-ray statistics: those stay missing.
    BuildStats build_stats() const override;

    static std::string version();
    // The instruction set of the kernels Embree runs on this machine, lower case ("sse2",
    // "sse4.2", "avx", "avx2", "avx512"): it picks at run time the best target that is both
    // compiled into the library and enabled on the CPU. Embree 3's API has no query for it,
    // so it is read once from a verbose device's report; "unknown" if that cannot be read.
    static std::string kernel_isa();
    // The kernels a device capped at `max_isa` runs ("auto": no cap), read likewise from
    // such a device's report.
    static std::string kernel_isa(const std::string& max_isa);

private:
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    Config config_;
};

}  // namespace accelbench
