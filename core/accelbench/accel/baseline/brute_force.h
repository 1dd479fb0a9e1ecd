// Brute force: every ray tests every triangle — the report's O(N*P) starting point
// (section 1.2). It is the simplest correct answer and the floor every structure beats;
// it refuses large scenes unless forced, because a 640x480 image of a 100k-triangle
// model would take hours.
#pragma once

#include "accelbench/accel/accelerator.h"

namespace accelbench {

class BruteForce final : public AcceleratorBase<BruteForce> {
public:
    // The parameters: each member's initializer is its default; brute_force.cpp's table
    // declares them.
    struct Config {
        int64_t max_triangles = 20000;  // largest scene it builds without `force`
        bool force = false;             // build even above max_triangles
        static Config from(const ParamSet& params);
    };

    static AcceleratorInfo info();
    explicit BruteForce(const Config& config) : config_(config) {}

    void build(const Scene& scene) override;
    BuildStats build_stats() const override;

    template <class C>
    void intersect(const Ray& ray, Hit& hit, C& counters) const;
    template <class C>
    bool occluded(const Ray& ray, C& counters) const;

private:
    Config config_;
    const Scene* scene_ = nullptr;
};

}  // namespace accelbench
