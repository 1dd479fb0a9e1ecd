// tinybvh 1.6.7 (Jacco Bikker, github.com/jbikker/tinybvh, MIT; ../shared/peers/tinybvh,
// unmodified) as accelbench structures: its layouts BVH (binary, SAH), BVH4_CPU and
// BVH8_CPU, each with its two builders (`default`: BuildDefault, binned SAH; `hq`: BuildHQ,
// SBVH spatial splits) and its threaded build switch, off by default so that the
// comparison with single-threaded builds is fair (tinybvh threads builds of 50k triangles
// and more unless told not to: BVH::threadedBuild).
#define TINYBVH_IMPLEMENTATION
#include <tiny_bvh.h>

#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "peer_plugin.h"

namespace {

using tinybvh::bvhvec3;
using tinybvh::bvhvec4;
using tinybvh::bvhvec4slice;

enum Builder { kDefault, kHq };

struct Params {
    Builder builder = kDefault;
    bool threaded_build = false;
};

Params read_params(const accelbench_param_value* p) {
    return {std::strcmp(p[0].enum_value, "hq") == 0 ? kHq : kDefault, p[1].bool_value != 0};
}

// The binary BVH itself, or the BVH a wide layout is converted from: where the threading
// switch is.
tinybvh::BVH& builder_bvh(tinybvh::BVH& b) { return b; }
tinybvh::BVH& builder_bvh(tinybvh::BVH4_CPU& b) { return b.bvh4.bvh; }
tinybvh::BVH& builder_bvh(tinybvh::BVH8_CPU& b) { return b.bvh8.bvh; }

// One structure of one layout. tinybvh keeps a slice of the vertices it was built over, so
// they are kept here, as the 16-byte vertices it reads.
template <class Layout>
struct Structure {
    Params params;
    std::vector<bvhvec4> vertices;
    Layout bvh;
};

// A tinybvh ray for ours: tinybvh has no tmin, so the origin moves to tmin (0 for camera
// rays: unchanged) and the distances are measured from there; the direction is not
// normalized (tinybvh's constructor would), so t stays in the units of ours.
struct PeerRay {
    tinybvh::Ray ray;
    float tmin, tmax;
};

PeerRay peer_ray(const accelbench_ray& r) {
    PeerRay p;
    p.tmin = r.tmin > 0 && std::isfinite(r.tmin) ? r.tmin : 0.0f;
    const bvhvec3 d(r.dir[0], r.dir[1], r.dir[2]);
    p.ray.O = bvhvec3(r.org[0] + p.tmin * d.x, r.org[1] + p.tmin * d.y, r.org[2] + p.tmin * d.z);
    p.ray.D = d;
    p.ray.rD = bvhvec3(tinybvh::tinybvh_safercp(d.x), tinybvh::tinybvh_safercp(d.y), tinybvh::tinybvh_safercp(d.z));
    p.ray.mask = RAY_MASK_INTERSECT_ALL;
    p.ray.instIdx = 0;
    p.tmax = r.tmax - p.tmin;
    p.ray.hit.t = p.tmax;
    p.ray.hit.u = p.ray.hit.v = 0;
    p.ray.hit.prim = ACCELBENCH_INVALID_PRIM;
    return p;
}

template <class Layout>
accelbench_structure* create(const accelbench_param_value* params, uint32_t, char* error, size_t error_size) {
    auto* s = new (std::nothrow) Structure<Layout>;
    if (!s) std::snprintf(error, error_size, "out of memory");
    else s->params = read_params(params);
    return reinterpret_cast<accelbench_structure*>(s);
}

template <class Layout>
Structure<Layout>& self(accelbench_structure* s) {
    return *reinterpret_cast<Structure<Layout>*>(s);
}
template <class Layout>
const Structure<Layout>& self(const accelbench_structure* s) {
    return *reinterpret_cast<const Structure<Layout>*>(s);
}

template <class Layout>
int build(accelbench_structure* handle, const accelbench_scene* scene, char* error, size_t error_size) {
    return peer_plugin::guarded(error, error_size, [&] {
        Structure<Layout>& s = self<Layout>(handle);
        s.vertices.resize(scene->vertex_count);
        for (uint64_t i = 0; i < scene->vertex_count; ++i)
            s.vertices[i] = bvhvec4(scene->vertices[3 * i], scene->vertices[3 * i + 1], scene->vertices[3 * i + 2], 0);
        if (scene->triangle_count == 0) return;  // nothing to build: every ray misses
        builder_bvh(s.bvh).threadedBuild = s.params.threaded_build;
        const bvhvec4slice slice(s.vertices.data(), uint32_t(s.vertices.size()), sizeof(bvhvec4));
        const uint32_t prims = uint32_t(scene->triangle_count);
        if (s.params.builder == kHq) {
            s.bvh.BuildHQ(slice, scene->indices, prims);
        } else if constexpr (std::is_same_v<Layout, tinybvh::BVH>) {
            // BVH::BuildDefault's choice (protected there): the AVX binned builder where compiled in.
#if defined(BVH_USEAVX)
            s.bvh.BuildAVX(slice, scene->indices, prims);
#else
            s.bvh.Build(slice, scene->indices, prims);
#endif
        } else {
            s.bvh.Build(slice, scene->indices, prims);  // BuildDefault, then the conversion to the layout
        }
    });
}

template <class Layout>
void closest_hits(const accelbench_structure* handle, const accelbench_ray* rays, accelbench_hit* hits, uint64_t count,
                  accelbench_ray_counters*) {
    const Structure<Layout>& s = self<Layout>(handle);
    for (uint64_t i = 0; i < count; ++i) {
        hits[i] = peer_plugin::miss();
        if (s.vertices.empty() || !peer_plugin::traceable(rays[i])) continue;
        PeerRay p = peer_ray(rays[i]);
        if (!(p.tmax > 0)) continue;
        s.bvh.Intersect(p.ray);
        if (p.ray.hit.t < p.tmax && p.ray.hit.prim != ACCELBENCH_INVALID_PRIM)
            hits[i] = {p.ray.hit.prim, p.ray.hit.t + p.tmin, p.ray.hit.u, p.ray.hit.v};
    }
}

template <class Layout>
void any_hits(const accelbench_structure* handle, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
              accelbench_ray_counters*) {
    const Structure<Layout>& s = self<Layout>(handle);
    for (uint64_t i = 0; i < count; ++i) {
        occluded[i] = 0;
        if (s.vertices.empty() || !peer_plugin::traceable(rays[i])) continue;
        const PeerRay p = peer_ray(rays[i]);
        if (p.tmax > 0) occluded[i] = s.bvh.IsOccluded(p.ray) ? 1 : 0;
    }
}

template <class Layout>
void build_stats(const accelbench_structure* handle, accelbench_build_stats* stats) {
    const Structure<Layout>& s = self<Layout>(handle);
    *stats = accelbench_unknown_build_stats();
    if constexpr (std::is_same_v<Layout, tinybvh::BVH>) {
        if (s.vertices.empty() || s.bvh.usedNodes == 0) return;
        stats->nodes = uint64_t(s.bvh.NodeCount());
        stats->leaves = uint64_t(s.bvh.LeafCount());
        stats->memory_bytes =
            uint64_t(s.bvh.usedNodes) * sizeof(tinybvh::BVH::BVHNode) + uint64_t(s.bvh.idxCount) * sizeof(uint32_t);
    } else {
        stats->memory_bytes = uint64_t(s.bvh.usedBlocks) * 16;  // its 16-byte blocks of nodes and triangles
    }
}

template <class Layout>
void destroy(accelbench_structure* handle) {
    delete &self<Layout>(handle);
}

const accelbench_param_desc kParams[] = {
    {"builder", ACCELBENCH_PARAM_ENUM, "default", 0, 0, "default|hq",
     "default: BuildDefault (binned SAH); hq: BuildHQ (SBVH, spatial splits)"},
    {"threaded_build", ACCELBENCH_PARAM_BOOL, "false", 0, 1, nullptr,
     "let tinybvh thread the build (it does from 50k triangles)"},
};

template <class Layout>
constexpr accelbench_structure_desc describe(const char* name, const char* label, const char* description) {
    return {name,
            label,
            description,
            kParams,
            2,
            0,
            create<Layout>,
            build<Layout>,
            closest_hits<Layout>,
            any_hits<Layout>,
            build_stats<Layout>,
            destroy<Layout>};
}

const accelbench_structure_desc kStructures[] = {
    describe<tinybvh::BVH>("tinybvh_bvh", "tinybvh BVH", "tinybvh 1.6.7, layout BVH: binary, 32-byte nodes"),
    describe<tinybvh::BVH4_CPU>("tinybvh_bvh4", "tinybvh BVH4_CPU",
                                "tinybvh 1.6.7, layout BVH4_CPU: 4-wide, SSE traversal"),
    describe<tinybvh::BVH8_CPU>("tinybvh_bvh8", "tinybvh BVH8_CPU",
                                "tinybvh 1.6.7, layout BVH8_CPU: 8-wide, AVX2 traversal"),
};

#define PEER_TEXT(x) #x
#define PEER_VERSION(major, minor, sub) "tinybvh " PEER_TEXT(major) "." PEER_TEXT(minor) "." PEER_TEXT(sub)
const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION,
                                   PEER_VERSION(TINY_BVH_VERSION_MAJOR, TINY_BVH_VERSION_MINOR, TINY_BVH_VERSION_SUB),
                                   kStructures, 3};

}  // namespace

extern "C" ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { return &kPlugin; }
