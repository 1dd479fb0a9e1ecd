// Embree 3 as the baseline row: the production ray tracing kernels every other row is
// measured against, answering the same rays through rtcIntersect1 / rtcOccluded1.
#pragma once

#include <embree3/rtcore.h>

#include "accelbench/accel/accelerator.h"

namespace accelbench {

class EmbreeAccel final : public Accelerator {
public:
    static AcceleratorInfo info();
    explicit EmbreeAccel(const ParamSet& params);
    ~EmbreeAccel() override;
    EmbreeAccel(const EmbreeAccel&) = delete;
    EmbreeAccel& operator=(const EmbreeAccel&) = delete;

    void build(const Scene& scene) override;
    void closest_hits(std::span<const Ray> rays, std::span<Hit> hits,
                      std::span<RayStats> stats = {}) const override;
    void any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded,
                  std::span<RayStats> stats = {}) const override;
    // Embree does not expose node counts or per-ray statistics: those stay missing.
    BuildStats build_stats() const override;

    static std::string version();

private:
    RTCDevice device_ = nullptr;
    RTCScene scene_ = nullptr;
    RTCBuildQuality quality_;
    bool robust_;
    bool compact_;
};

}  // namespace accelbench
