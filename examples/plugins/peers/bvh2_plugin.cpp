// bvh v2 (Arsène Pérard-Gayot, github.com/madmann91/bvh, MIT; ../shared/peers/bvh-v2,
// unmodified) as an accelbench structure: its DefaultBuilder (quality low: binned SAH;
// medium: sweep SAH; high: sweep SAH and reinsertion) over its precomputed triangles, the
// traversal of its own example (src/bvh/v2/c_api and test/simple_example.cpp: SmallStack,
// the leaf test over PrecomputedTri). Single-threaded unless `threads` says otherwise.
#include <bvh/v2/bvh.h>
#include <bvh/v2/default_builder.h>
#include <bvh/v2/node.h>
#include <bvh/v2/ray.h>
#include <bvh/v2/stack.h>
#include <bvh/v2/thread_pool.h>
#include <bvh/v2/tri.h>
#include <bvh/v2/vec.h>

#include <cstring>
#include <new>
#include <optional>
#include <vector>

#include "peer_plugin.h"

namespace {

using Vec3 = bvh::v2::Vec<float, 3>;
using BBox = bvh::v2::BBox<float, 3>;
using Tri = bvh::v2::Tri<float, 3>;
using Node = bvh::v2::Node<float, 3>;
using Bvh = bvh::v2::Bvh<Node>;
using Ray = bvh::v2::Ray<float, 3>;
using PrecomputedTri = bvh::v2::PrecomputedTri<float>;
using Builder = bvh::v2::DefaultBuilder<Node>;

struct Structure {
    Builder::Quality quality = Builder::Quality::High;
    int64_t threads = 1;
    int64_t max_leaf_size = 8;
    bool robust = false;
    Bvh bvh;
    std::vector<PrecomputedTri> tris;  // in the BVH's primitive order
    std::vector<uint32_t> prim_ids;    // the scene's index of each
};

Structure& self(accelbench_structure* s) { return *reinterpret_cast<Structure*>(s); }
const Structure& self(const accelbench_structure* s) { return *reinterpret_cast<const Structure*>(s); }

accelbench_structure* create(const accelbench_param_value* p, uint32_t, char* error, size_t error_size) {
    auto* s = new (std::nothrow) Structure;
    if (!s) {
        std::snprintf(error, error_size, "out of memory");
        return nullptr;
    }
    s->quality = std::strcmp(p[0].enum_value, "low") == 0 ? Builder::Quality::Low
        : std::strcmp(p[0].enum_value, "medium") == 0     ? Builder::Quality::Medium
                                                          : Builder::Quality::High;
    s->threads = p[1].int_value;
    s->max_leaf_size = p[2].int_value;
    s->robust = p[3].bool_value != 0;
    return reinterpret_cast<accelbench_structure*>(s);
}

int build(accelbench_structure* handle, const accelbench_scene* scene, char* error, size_t error_size) {
    return peer_plugin::guarded(error, error_size, [&] {
        Structure& s = self(handle);
        const size_t n = scene->triangle_count;
        auto vertex = [&](uint32_t v) {
            return Vec3(scene->vertices[3 * v], scene->vertices[3 * v + 1], scene->vertices[3 * v + 2]);
        };
        std::vector<Tri> tris(n);
        std::vector<BBox> bboxes(n);
        std::vector<Vec3> centers(n);
        for (size_t i = 0; i < n; ++i) {
            tris[i] = Tri(vertex(scene->indices[3 * i]), vertex(scene->indices[3 * i + 1]),
                          vertex(scene->indices[3 * i + 2]));
            bboxes[i] = tris[i].get_bbox();
            centers[i] = tris[i].get_center();
        }
        if (n == 0) return;  // nothing to build: every ray misses
        Builder::Config config;
        config.quality = s.quality;
        config.max_leaf_size = size_t(s.max_leaf_size);
        if (s.threads > 1) {
            bvh::v2::ThreadPool pool(size_t(s.threads));
            s.bvh = Builder::build(pool, bboxes, centers, config);
        } else {
            s.bvh = Builder::build(bboxes, centers, config);
        }
        s.tris.resize(n);
        s.prim_ids.resize(n);
        for (size_t i = 0; i < n; ++i) {
            s.prim_ids[i] = uint32_t(s.bvh.prim_ids[i]);
            s.tris[i] = PrecomputedTri(tris[s.prim_ids[i]]);
        }
    });
}

// bvh v2 takes [tmin, tmax] closed; ours is [tmin, tmax): the float below tmax.
Ray peer_ray(const accelbench_ray& r) {
    return Ray(Vec3(r.org[0], r.org[1], r.org[2]), Vec3(r.dir[0], r.dir[1], r.dir[2]), r.tmin,
               std::nextafter(r.tmax, -INFINITY));
}

template <bool IsAnyHit>
std::optional<accelbench_hit> trace(const Structure& s, const accelbench_ray& r) {
    if (s.tris.empty() || !peer_plugin::traceable(r)) return std::nullopt;
    Ray ray = peer_ray(r);
    std::optional<accelbench_hit> found;
    bvh::v2::SmallStack<Bvh::Index, 64> stack;
    auto leaf = [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i)
            if (auto hit = s.tris[i].intersect(ray)) {
                auto [t, u, v] = *hit;
                found = accelbench_hit{s.prim_ids[i], t, u, v};
                ray.tmax = t;
                if (IsAnyHit) return true;
            }
        return IsAnyHit && found.has_value();
    };
    if (s.robust) s.bvh.intersect<IsAnyHit, true>(ray, s.bvh.get_root().index, stack, leaf);
    else s.bvh.intersect<IsAnyHit, false>(ray, s.bvh.get_root().index, stack, leaf);
    return found;
}

void closest_hits(const accelbench_structure* handle, const accelbench_ray* rays, accelbench_hit* hits, uint64_t count,
                  accelbench_ray_counters*) {
    const Structure& s = self(handle);
    for (uint64_t i = 0; i < count; ++i) hits[i] = trace<false>(s, rays[i]).value_or(peer_plugin::miss());
}

void any_hits(const accelbench_structure* handle, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
              accelbench_ray_counters*) {
    const Structure& s = self(handle);
    for (uint64_t i = 0; i < count; ++i) occluded[i] = trace<true>(s, rays[i]).has_value() ? 1 : 0;
}

void build_stats(const accelbench_structure* handle, accelbench_build_stats* stats) {
    const Structure& s = self(handle);
    *stats = accelbench_unknown_build_stats();
    if (s.tris.empty()) return;
    uint64_t leaves = 0;
    for (const Node& node : s.bvh.nodes) leaves += node.is_leaf() ? 1 : 0;
    stats->nodes = s.bvh.nodes.size();
    stats->leaves = leaves;
    stats->memory_bytes = s.bvh.nodes.size() * sizeof(Node) + s.bvh.prim_ids.size() * sizeof(size_t) +
        s.tris.size() * sizeof(PrecomputedTri) + s.prim_ids.size() * sizeof(uint32_t);
    stats->avg_leaf_size = double(s.tris.size()) / double(leaves);
}

void destroy(accelbench_structure* handle) { delete &self(handle); }

const accelbench_param_desc kParams[] = {
    {"quality", ACCELBENCH_PARAM_ENUM, "high", 0, 0, "low|medium|high",
     "DefaultBuilder's quality: binned SAH, sweep SAH, sweep SAH + reinsertion"},
    {"threads", ACCELBENCH_PARAM_INT, "1", 1, 1024, nullptr, "build threads (bvh v2's thread pool above 1)"},
    {"max_leaf_size", ACCELBENCH_PARAM_INT, "8", 1, 64, nullptr, "largest leaf the builder makes"},
    {"robust", ACCELBENCH_PARAM_BOOL, "false", 0, 1, nullptr, "bvh v2's robust ray/box test"},
};

const accelbench_structure_desc kStructures[] = {{
    "bvh2",
    "bvh v2",
    "bvh v2 (madmann91/bvh at ac41ab8): DefaultBuilder, binary BVH, PrecomputedTri",
    kParams,
    4,
    0,
    create,
    build,
    closest_hits,
    any_hits,
    build_stats,
    destroy,
}};

const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION, "bvh v2 ac41ab88", kStructures, 1};

}  // namespace

extern "C" ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { return &kPlugin; }
