#include "accelbench/accel/kdtree/kdtree.h"

#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "accelbench/base/param_table.h"

namespace accelbench {

namespace {

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<KdTree::Config>& kdtree_params() {
    using C = KdTree::Config;
    static const ParamTable<C> rows = {
        enum_param("build", &C::build, KdTree::kBuildNames,
                   "nlogn: events sorted once, split in linear time (Wald & Havran 2006); pbrt: edges sorted at "
                   "every node. Both give the same tree"),
        float_param("isect_cost", &C::isect_cost, 1e-4, 1e4, "SAH cost of one ray/triangle test C_I"),
        float_param("traversal_cost", &C::traversal_cost, 1e-4, 1e4, "SAH cost of one traversal step C_T"),
        float_param("empty_bonus", &C::empty_bonus, 0, 1, "b_e: fraction of the cost forgiven when one child is empty"),
        int_param("max_prims", &C::max_prims, 0, KdNode::kMaxIndex,
                  "nodes with at most this many primitives become leaves"),
        auto_int_param("max_depth", &C::max_depth, 0, KdTree::kMaxDepthLimit,
                       "deepest level; auto = round(8 + 1.3 log2 N)"),
        bool_param("mailbox", &C::mailbox,
                   "test a triangle once per ray even when several leaves the ray visits hold it (the same "
                   "answers; prim_tests then counts the tests made)"),
        threads_param("threads", &C::threads, 256,
                      "build threads (0 = all cores); the tree is the same for every value"),
    };
    return rows;
}

}  // namespace

AcceleratorInfo KdTree::info() {
    return {.name = "kdtree",
            .description =
                "SAH kd-tree after pbrt-v3 (report section 4): 8-byte nodes, edge-event SAH, front-to-back traversal",
            .params = kdtree_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<KdTree>(p); },
            .label = fixed_label("kd-tree"),
            // A given max_depth; the default's depends on the scene.
            .depth_limit = [](const ParamSet& p) -> std::optional<uint64_t> {
                const std::optional<int> depth = Config::from(p).max_depth;
                return depth ? std::optional<uint64_t>(uint64_t(*depth)) : std::nullopt;
            }};
}

KdTree::Config KdTree::Config::from(const ParamSet& p) { return kdtree_params().from(p); }

KdTree::KdTree(const ParamSet& params) : KdTree(Config::from(params)) {}

KdTree::KdTree(const Config& config) : config_(config), threads_(config.threads) {
    if (config_.max_depth && (*config_.max_depth < 0 || *config_.max_depth > kMaxDepthLimit))
        throw std::invalid_argument("kdtree: max_depth " + std::to_string(*config_.max_depth) + " is outside [0, " +
                                    std::to_string(kMaxDepthLimit) + "]");
    if (config_.max_prims < 0) throw std::invalid_argument("kdtree: max_prims must be >= 0");
    if (!(config_.isect_cost > 0) || !(config_.traversal_cost > 0) || !(config_.empty_bonus >= 0) ||
        !(config_.empty_bonus <= 1))
        throw std::invalid_argument("kdtree: costs must be > 0 and empty_bonus in [0, 1]");
}

int KdTree::default_max_depth(size_t prim_count) {
    if (prim_count <= 1) return 8;
    return int(std::lround(8.0 + 1.3 * std::log2(double(prim_count))));
}

}  // namespace accelbench
