// tinybvh 1.6.7 (Jacco Bikker, github.com/jbikker/tinybvh, MIT; ../shared/peers/tinybvh,
// unmodified) as accelbench structures: its layouts BVH (binary, SAH), BVH4_CPU and
// BVH8_CPU, each with its two builders (`default`: BuildDefault, binned SAH; `hq`: BuildHQ,
// SBVH spatial splits) and its threaded build switch, off by default so that the
// comparison with single-threaded builds is fair (tinybvh threads builds of 50k triangles
// and more unless told not to: BVH::threadedBuild).
#define TINYBVH_IMPLEMENTATION
#include <tiny_bvh.h>

#include <algorithm>
#include <cmath>
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
    float dir_scale = 1;  // direction_scale() of the scene
};

// The power of two every ray direction is multiplied by before tinybvh sees it. The layout
// BVH tests triangles by Moeller-Trumbore (tiny_bvh.h, MOLLER_TRUMBORE_TEST) and rejects
// every determinant below 1e-6 in absolute value; the determinant grows with the triangle's
// area times |dir|, so in a scene of small extent every small triangle is refused (on the
// 871k-triangle dragon, 47,253 of 307,200 primary rays missed or hit a farther triangle).
// Scaling the direction by 2^k so that |dir| * diagonal^2 is about 2^20 makes that bound
// relative to the scene: only triangles below ~5e-13 of the diagonal squared are refused.
// A power of two is exact in floating point: every product of the traversal and the
// triangle tests scales by an exact power of two (the hits and barycentrics are the same
// bits; t comes back divided by 2^k, multiplied back exactly). Never below 1 (a scene
// larger than 2^10 has no such triangles to lose) nor above 2^40 (far from overflow).
// tinybvh's WATERTIGHT_TRITEST would avoid the bound, but 1.6.7's TriOccludes does not
// compile with it (its opacity-map code uses the Moeller-Trumbore test's u, v).
float direction_scale(const std::vector<bvhvec4>& vertices) {
    if (vertices.empty()) return 1;
    bvhvec3 lo = vertices[0], hi = vertices[0];
    for (const bvhvec4& v : vertices)
        lo = tinybvh::tinybvh_min(lo, bvhvec3(v)), hi = tinybvh::tinybvh_max(hi, bvhvec3(v));
    const float diagonal2 = tinybvh::tinybvh_dot(hi - lo, hi - lo);
    if (!(diagonal2 > 0)) return 1;
    const long k = std::lround(std::log2(double(1 << 20) / double(diagonal2)));
    return std::ldexp(1.0f, int(std::clamp(k, 0L, 40L)));
}

// A tinybvh ray for ours. tinybvh's rays have no tmin: it searches [0, t] from the
// origin. The ray starts at our origin (`from_tmin` false) and the plugin checks the hit
// against tmin itself; or, when tinybvh's nearest hit lies before tmin and it cannot look
// past it, at org + tmin * dir (`from_tmin` true, computed in double and rounded once),
// which is off our ray's line by that rounding. The direction is not normalized (tinybvh's
// constructor would) but scaled by `dir_scale`, so tinybvh's t is ours divided by it (and
// minus tmin from the moved origin).
struct PeerRay {
    tinybvh::Ray ray;
    float tmin, tmax;    // tinybvh's units: [tmin, tmax) is our [tmin, tmax)
    float scale, start;  // our t = tinybvh's t * scale + start

    float our_t() const { return ray.hit.t * scale + start; }
    bool found() const { return ray.hit.prim != ACCELBENCH_INVALID_PRIM && ray.hit.t < tmax; }
    bool before_tmin() const { return ray.hit.prim != ACCELBENCH_INVALID_PRIM && ray.hit.t < tmin; }
};

PeerRay peer_ray(const accelbench_ray& r, float dir_scale, bool from_tmin) {
    PeerRay p;
    p.scale = dir_scale;
    const float tmin = r.tmin > 0 && std::isfinite(r.tmin) ? r.tmin : 0.0f;
    p.start = from_tmin ? tmin : 0.0f;
    const bvhvec3 d(r.dir[0], r.dir[1], r.dir[2]);
    bvhvec3 o(r.org[0], r.org[1], r.org[2]);
    if (from_tmin)
        for (int k = 0; k < 3; ++k) o[k] = float(double(r.org[k]) + double(tmin) * double(r.dir[k]));
    p.ray.O = o;
    p.ray.D = d * dir_scale;
    p.ray.rD = tinybvh::tinybvh_safercp(p.ray.D);
    p.ray.mask = RAY_MASK_INTERSECT_ALL;
    p.ray.instIdx = 0;
    p.tmin = (tmin - p.start) / dir_scale;
    p.tmax = (r.tmax - p.start) / dir_scale;
    // tinybvh accepts hits at t itself: the float below tmax keeps [tmin, tmax) open
    p.ray.hit.t = std::nextafter(p.tmax, 0.0f);
    p.ray.hit.u = p.ray.hit.v = 0;
    p.ray.hit.prim = ACCELBENCH_INVALID_PRIM;
    return p;
}

// The nearest hit within [tmin, tmax): tinybvh's nearest from our origin, unless that lies
// before tmin (a ray leaving a surface, hitting it again), then from org + tmin * dir.
template <class Layout>
PeerRay nearest_hit(const Layout& bvh, const accelbench_ray& r, float dir_scale) {
    PeerRay p = peer_ray(r, dir_scale, false);
    if (!(p.tmax > p.tmin)) return p;  // an empty interval: a miss
    bvh.Intersect(p.ray);
    if (!p.before_tmin()) return p;
    p = peer_ray(r, dir_scale, true);
    bvh.Intersect(p.ray);
    return p;
}

// Whether anything lies within [tmin, tmax). tinybvh's any-hit test from our origin over
// [0, tmin) first. Where it finds nothing there, the test over [0, tmax) answers for
// [tmin, tmax); where it does (about half of the shadow rays: the surface they leave), the
// test from org + tmin * dir answers. The first test costs most of a shadow ray's trace,
// whose work lies near its origin (docs/decisions.md, the open peers' plugins).
template <class Layout>
bool occluded_within(const Layout& bvh, const accelbench_ray& r, float dir_scale) {
    PeerRay p = peer_ray(r, dir_scale, false);
    if (!(p.tmax > p.tmin)) return false;
    if (p.tmin > 0) {
        tinybvh::Ray before = p.ray;
        before.hit.t = std::nextafter(p.tmin, 0.0f);
        if (bvh.IsOccluded(before)) return bvh.IsOccluded(peer_ray(r, dir_scale, true).ray);
    }
    return bvh.IsOccluded(p.ray);
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
        s.dir_scale = direction_scale(s.vertices);
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
        const PeerRay p = nearest_hit(s.bvh, rays[i], s.dir_scale);
        if (p.found()) hits[i] = {p.ray.hit.prim, p.our_t(), p.ray.hit.u, p.ray.hit.v};
    }
}

template <class Layout>
void any_hits(const accelbench_structure* handle, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
              accelbench_ray_counters*) {
    const Structure<Layout>& s = self<Layout>(handle);
    for (uint64_t i = 0; i < count; ++i) {
        occluded[i] = 0;
        if (s.vertices.empty() || !peer_plugin::traceable(rays[i])) continue;
        occluded[i] = occluded_within(s.bvh, rays[i], s.dir_scale) ? 1 : 0;
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

// The price of tinybvh's rays having no tmin (peer_ray above) shows in the times of rays
// that leave a surface (the shadow set), so the descriptions, which `accelbench list`
// prints, name it.
#define PEER_TMIN_NOTE "; no tmin in tinybvh: a ray with tmin > 0 may take a second trace"
const accelbench_structure_desc kStructures[] = {
    describe<tinybvh::BVH>("tinybvh_bvh", "tinybvh BVH",
                           "tinybvh 1.6.7, layout BVH: binary, 32-byte nodes" PEER_TMIN_NOTE),
    describe<tinybvh::BVH4_CPU>("tinybvh_bvh4", "tinybvh BVH4_CPU",
                                "tinybvh 1.6.7, layout BVH4_CPU: 4-wide, SSE traversal" PEER_TMIN_NOTE),
    describe<tinybvh::BVH8_CPU>("tinybvh_bvh8", "tinybvh BVH8_CPU",
                                "tinybvh 1.6.7, layout BVH8_CPU: 8-wide, AVX2 traversal" PEER_TMIN_NOTE),
};

#define PEER_TEXT(x) #x
#define PEER_VERSION(major, minor, sub) "tinybvh " PEER_TEXT(major) "." PEER_TEXT(minor) "." PEER_TEXT(sub)
const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION,
                                   PEER_VERSION(TINY_BVH_VERSION_MAJOR, TINY_BVH_VERSION_MINOR, TINY_BVH_VERSION_SUB),
                                   kStructures, 3};

}  // namespace

extern "C" ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { return &kPlugin; }
