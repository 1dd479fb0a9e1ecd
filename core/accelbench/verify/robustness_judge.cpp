// The judge: one case against one accelerator, every expectation applied the same way.
#include <cstring>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/verify/robustness_cases.h"

namespace accelbench {

JudgeOptions judge_options(const AcceleratorInfo& accelerator, const ParamSet& params) {
    JudgeOptions o;
    o.watertight = accelerator.watertight(params);
    o.depth_limit = accelerator.depth_limit(params);
    return o;
}

uint64_t case_memory_limit(const Scene& scene) { return 4096 * uint64_t(scene.triangle_count()) + (1u << 20); }

std::string CaseVerdict::counts() const {
    std::string s = "leaks=" + std::to_string(leaks) + " false_hits=" + std::to_string(false_hits) +
        " wrong_prims=" + std::to_string(wrong_prims) + " nan=" + std::to_string(nan_results) +
        " occlusion_mismatches=" + std::to_string(occlusion_mismatches) +
        " nondeterministic=" + std::to_string(nondeterministic);
    if (leaks_tolerated) s += " leaks_tolerated=" + std::to_string(leaks_tolerated);
    if (max_depth)
        s += " depth=" + std::to_string(*max_depth) + "/" + (depth_limit ? std::to_string(*depth_limit) : "-");
    s += " rays=" + std::to_string(rays);
    return s;
}

namespace {

bool same_hit(const Hit& a, const Hit& b) {
    return a.prim == b.prim && std::memcmp(&a.t, &b.t, sizeof a.t) == 0 && std::memcmp(&a.u, &b.u, sizeof a.u) == 0 &&
        std::memcmp(&a.v, &b.v, sizeof a.v) == 0;
}

}  // namespace

CaseVerdict judge_case(const RobustnessCase& c, const AcceleratorFactory& make, const JudgeOptions& options) {
    CaseVerdict v;
    v.case_id = c.id;
    v.rays = c.rays.size();
    if (c.expects_rejection()) {
        Scene copy = c.scene;
        try {
            copy.finalize();
            v.detail = "Scene::finalize() accepted the bad input";
        } catch (const std::exception& e) {
            const std::string message = e.what();
            v.pass = message.find(c.rejection_mentions) != std::string::npos;
            v.detail =
                (v.pass ? "rejected at load: " : "rejected without naming '" + c.rejection_mentions + "': ") + message;
        }
        return v;
    }
    std::unique_ptr<Accelerator> accel, rebuilt;
    try {
        accel = make();
        accel->build(c.scene);
        rebuilt = make();
        rebuilt->build(c.scene);
    } catch (const std::exception& e) {
        v.detail = std::string("build failed: ") + e.what();
        return v;
    }
    v.built = true;
    const BuildStats stats = accel->build_stats();
    v.max_depth = stats.max_depth;
    v.depth_limit = options.depth_limit.value_or(uint64_t(c.scene.triangle_count()) + 64);
    v.memory_bytes = stats.memory_bytes;
    v.memory_limit = case_memory_limit(c.scene);

    const size_t n = c.rays.size();
    std::vector<Hit> hits(n), again(n), other(n);
    std::vector<uint8_t> occluded(n);
    accel->closest_hits(c.rays, hits);
    accel->closest_hits(c.rays, again);
    rebuilt->closest_hits(c.rays, other);
    accel->any_hits(c.rays, occluded);
    for (size_t i = 0; i < n; ++i) {
        const Hit& h = hits[i];
        const RayExpectation& e = c.expect[i];
        const bool tolerated = e.watertight_only && !options.watertight;
        if (std::isnan(h.t) || std::isnan(h.u) || std::isnan(h.v)) ++v.nan_results;
        if (!same_hit(h, again[i]) || !same_hit(h, other[i])) ++v.nondeterministic;
        if (bool(occluded[i]) != h.found() && !tolerated) ++v.occlusion_mismatches;
        switch (e.kind) {
            case Expect::Any: break;
            case Expect::Miss:
                if (h.found()) ++v.false_hits;
                break;
            case Expect::Hit:
            case Expect::Prim:
                if (!h.found()) ++(tolerated ? v.leaks_tolerated : v.leaks);
                else if (e.kind == Expect::Prim && (h.prim < e.prim_lo || h.prim > e.prim_hi)) ++v.wrong_prims;
                break;
        }
    }
    if (!c.reference_hits.empty()) v.vs_reference = compare_hits(hits, c.reference_hits);

    std::vector<std::string> failures;
    auto require = [&](bool ok, const std::string& what) {
        if (!ok) failures.push_back(what);
    };
    require(v.leaks == 0, std::to_string(v.leaks) + " leaks");
    require(v.false_hits == 0, std::to_string(v.false_hits) + " false hits");
    require(v.wrong_prims == 0, std::to_string(v.wrong_prims) + " wrong primitives");
    require(v.nan_results == 0, std::to_string(v.nan_results) + " NaN results");
    require(v.occlusion_mismatches == 0, std::to_string(v.occlusion_mismatches) + " any-hit/closest-hit disagreements");
    require(v.nondeterministic == 0, std::to_string(v.nondeterministic) + " answers differing between runs");
    if (v.max_depth)
        require(*v.max_depth <= *v.depth_limit,
                "depth " + std::to_string(*v.max_depth) + " above the limit " + std::to_string(*v.depth_limit));
    if (v.memory_bytes)
        require(*v.memory_bytes <= *v.memory_limit,
                "memory " + std::to_string(*v.memory_bytes) + " bytes above " + std::to_string(*v.memory_limit));
    v.pass = failures.empty();
    for (const auto& f : failures) v.detail += (v.detail.empty() ? "" : ", ") + f;
    return v;
}

CaseVerdict judge_case(const RobustnessCase& c, const std::string& accelerator,
                       const std::map<std::string, std::string>& params) {
    ParamSet resolved;
    make_accelerator(accelerator, params, &resolved);  // validates now, so errors are not taken for build failures
    return judge_case(
        c, [&] { return make_accelerator(accelerator, params); },
        judge_options(*find_accelerator(accelerator), resolved));
}

}  // namespace accelbench
