// The wide BVH's node and leaf layout and the two tests its traversal is made of — all
// children of a node against one ray (slab test), and a packet of triangles against one ray
// (watertight test) — each in a vector form and a scalar form that answer bit for bit alike.
//
// Layout (Embree's BVH4/BVH8 nodes, tinybvh's BVH8_CPU): a node of W children stores the
// children's boxes structure-of-arrays — the W lower x planes together, then the W lower y,
// ... — so one vector load gives one plane of every child, and one slab test of 3 x 2
// subtract-multiply pairs covers all W children. A leaf's triangles are stored in packets of
// 4, vertex coordinates structure-of-arrays too, so one watertight test covers 4 triangles.
//
// Which vector code is compiled in is chosen at compile time from the target's extensions
// (the ACCELBENCH_ISA CMake option: -march=native or portable x86-64):
//   slab test, W = 8   AVX (one 8-lane test) if the target has it, else two 4-lane SSE halves
//   slab test, W = 4   SSE
//   triangle packet    SSE (4 lanes)
// and a target without SSE2 compiles only the scalar forms. The scalar forms are compiled
// always: they call the project's own intersect_box and intersect_triangle (geometry.h,
// triangle.h) per lane with the project's RayPrecomp and WatertightRay (WbvhScalarRay), so
// the test that compares the two forms (wbvh_test) checks the vector code, and its per-ray
// constants (WbvhVectorRay), against the project's scalar definitions.
//
// Why both forms agree exactly: the vector code performs the same IEEE operations in the same
// order as the scalar code (no FMA: CMakeLists.txt compiles with -ffp-contract=off, so GCC
// contracts neither the scalar a * b + c nor the intrinsics' vector one; no reciprocal
// approximations), and its min/max are the SSE MINPS/MAXPS,
// which return the second operand when either is NaN — the "new value wins only if the test
// is true" form intersect_box relies on for a ray lying in a slab's plane.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "accelbench/base/geometry.h"
#include "accelbench/base/triangle.h"

#if defined(__SSE2__)
#include <immintrin.h>
#define ACCELBENCH_WBVH_SSE 1
#endif
#if defined(__AVX__)
#define ACCELBENCH_WBVH_AVX 1
#endif

namespace accelbench {

// Whether the vector forms exist in this build (otherwise `kernel=simd` runs the scalar ones).
inline constexpr bool kWbvhHasVector =
#if defined(ACCELBENCH_WBVH_SSE)
    true;
#else
    false;
#endif

// The vector code compiled into the slab test of an 8-wide node: "avx", "sse" or "scalar".
inline constexpr const char* kWbvhWide8Isa =
#if defined(ACCELBENCH_WBVH_AVX)
    "avx";
#elif defined(ACCELBENCH_WBVH_SSE)
    "sse";
#else
        "scalar";
#endif

// A wide node: up to W children, packed at the front (an unused slot has child kInvalidId
// and an empty box, +inf lower / -inf upper, which no ray can hit).
template <int W>
struct alignas(64) WbvhNode {
    static_assert(W == 4 || W == 8);
    static constexpr int kWidth = W;

    // planes[axis][k] is child k's lower bound on axis, planes[3 + axis][k] its upper one.
    float planes[6][W];
    // Inner child: its node index. Leaf child: its first triangle packet.
    uint32_t child[W];
    // Leaf child: its number of triangles (> 0). Inner child and unused slot: 0.
    uint32_t count[W];

    uint32_t child_count() const {
        uint32_t n = 0;
        while (n < uint32_t(W) && child[n] != kInvalidId) ++n;
        return n;
    }
    Bounds3 child_bounds(int k) const {
        return {{planes[0][k], planes[1][k], planes[2][k]}, {planes[3][k], planes[4][k], planes[5][k]}};
    }
};
static_assert(sizeof(WbvhNode<4>) == 128 && sizeof(WbvhNode<8>) == 256, "two / four cache lines");

// Four triangles of one leaf; lanes past the leaf's count hold zeros and prim kInvalidId and
// are masked off by the test, never tested.
struct alignas(16) WbvhTriPacket {
    static constexpr int kLanes = 4;
    // The packets a leaf of n triangles takes (the last one part-used).
    static constexpr uint32_t packets_for(uint32_t n) { return (n + kLanes - 1) / kLanes; }
    float v[3][3][kLanes];  // [vertex][axis][lane]
    uint32_t prim[kLanes];  // triangle index in the scene
};
static_assert(sizeof(WbvhTriPacket) == 160);

// The per-ray constants of the scalar kernels: the project's own RayPrecomp and
// WatertightRay, as every other structure computes them.
struct WbvhScalarRay {
    bool valid;  // is_valid_ray(): invalid rays hit nothing
    RayPrecomp rp;
    WatertightRay wr;
    explicit WbvhScalarRay(const Ray& ray) : valid(is_valid_ray(ray)), rp(ray), wr(ray) {}
};

namespace detail {

// The watertight test's axis permutation (WatertightRay) for every outcome of its three
// comparisons: bit 0 |dx| >= |dy|, bit 1 |dx| >= |dz|, bit 2 |dy| >= |dz|, bits 3-5 the
// direction's sign bits. Entry: kx | ky << 2 | kz << 4.
constexpr uint8_t watertight_axes(int index) {
    const bool x_ge_y = index & 1, x_ge_z = index & 2, y_ge_z = index & 4;
    const int kz = (x_ge_y && x_ge_z) ? 0 : (y_ge_z ? 1 : 2);  // max_axis(|dir|)
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    // dir[kz] < 0: its sign bit, as dir[kz] is the largest component in magnitude of a
    // valid ray's non-zero direction (never -0.0).
    if ((index >> (3 + kz)) & 1) std::swap(kx, ky);
    return uint8_t(kx | ky << 2 | kz << 4);
}
struct WatertightAxesTable {
    uint8_t axes[64];
    constexpr WatertightAxesTable() : axes{} {
        for (int i = 0; i < 64; ++i) axes[i] = watertight_axes(i);
    }
};
inline constexpr WatertightAxesTable kWatertightAxes{};

}  // namespace detail

#if defined(ACCELBENCH_WBVH_SSE)
// The per-ray constants of the vector kernels: the values of is_valid_ray, RayPrecomp and
// WatertightRay, bit for bit (wbvh_test checks it), computed with a few vector operations
// instead of one component at a time: the ray's two halves (origin and tmin, direction and
// tmax) are two loads, the validity three compares, the reciprocals one division (1 / x is
// exactly safe_inverse(x): IEEE division gives an infinity of x's sign for x = +-0), the
// plane rows and the watertight permutation the sign and comparison bits of one movemask
// each, and sx, sy, sz one more division. Measured (callgrind, trace/stanford-bunny/wbvh8,
// the 640x480 primary + shadow rays): the scalar constructors and what GCC hoisted from them
// took 208 instructions of every closest-hit ray (43% of its traversal: six branchy validity
// tests done twice, six scalar divisions behind branches, the plane rows stored and
// reloaded) and 185 of every shadow ray; with this form 138, and the traversal 147.2M ->
// 116.8M instructions (closest hit), 61.5M -> 49.4M (any hit), the same counts. Timed
// interleaved with Embree (load ~7 on 2 cores): trace / Embree 1.21x -> 1.06x.
namespace detail {
template <int W>
struct SlabLanes {
    using type = __m128;
};
#if defined(ACCELBENCH_WBVH_AVX)
template <>
struct SlabLanes<8> {
    using type = __m256;
};
#endif
}  // namespace detail

template <int W>
struct WbvhVectorRay {
    // A broadcast: 8 lanes for the AVX test of 8-wide nodes, else 4.
    using Lanes = typename detail::SlabLanes<W>::type;
    static Lanes broadcast(__m128 x) {
        if constexpr (sizeof(Lanes) == 32) return _mm256_broadcastss_ps(x);
        else return _mm_shuffle_ps(x, x, 0);
    }

    bool valid = false;
    // The slab test's constants, each broadcast and kept here for use as a memory operand
    // (GCC otherwise keeps them in registers across the loop and spills the leaf test's):
    // org[a] and inv_dir[a] in every lane, and the byte offsets in WbvhNode<W>::planes of
    // the near plane rows of x, y, z then the far ones (kWbvhPlaneOffsets).
    Lanes org[3], inv_dir[3];
    const uint32_t* plane_offset = nullptr;
    int kx = 0, ky = 1, kz = 2;  // WatertightRay's permutation
    // What the packet test reads, likewise: sx, sy, sz and org[kx], org[ky], org[kz] each
    // broadcast to 4 lanes, and the byte offsets of the kx, ky, kz rows of a packet's vertex.
    // Made once per ray: otherwise GCC hoists the broadcasts and the 9 vertex row addresses
    // out of the traversal loop and spills them, for a leaf test fewer than one ray in three
    // reaches.
    __m128 shear[3];
    __m128 org_k[3];
    size_t row_offset[3];

    explicit WbvhVectorRay(const Ray& ray) {
        static_assert(sizeof(Ray) == 32 && offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16 &&
                      offsetof(Ray, tmax) == 28);
        const float* raw = reinterpret_cast<const float*>(&ray);
        const __m128 lo = _mm_loadu_ps(raw);      // org, tmin
        const __m128 hi = _mm_loadu_ps(raw + 4);  // dir, tmax
        // is_valid_ray: |org|, |dir| < kMaxCoordinate (false for NaN), tmin and tmax not NaN
        // (lane 3 of an ordered compare of the halves), a direction component != 0.
        const __m128 sign = _mm_set1_ps(-0.0f), limit = _mm_set1_ps(kMaxCoordinate);
        const __m128 abs_dir = _mm_andnot_ps(sign, hi);
        const uint32_t in_limit = uint32_t(
            _mm_movemask_ps(_mm_and_ps(_mm_cmplt_ps(_mm_andnot_ps(sign, lo), limit), _mm_cmplt_ps(abs_dir, limit))));
        const uint32_t ordered = uint32_t(_mm_movemask_ps(_mm_cmpord_ps(lo, hi)));
        const uint32_t nonzero = uint32_t(_mm_movemask_ps(_mm_cmpneq_ps(hi, _mm_setzero_ps())));
        valid = (in_limit & 7u) == 7u && (ordered & 8u) && (nonzero & 7u);
        if (!valid) return;
        const __m128 inv = _mm_div_ps(_mm_set1_ps(1.0f), hi);
        org[0] = broadcast(lo);
        org[1] = broadcast(_mm_shuffle_ps(lo, lo, 1));
        org[2] = broadcast(_mm_shuffle_ps(lo, lo, 2));
        inv_dir[0] = broadcast(inv);
        inv_dir[1] = broadcast(_mm_shuffle_ps(inv, inv, 1));
        inv_dir[2] = broadcast(_mm_shuffle_ps(inv, inv, 2));
        // RayPrecomp::near_is_upper: the reciprocal's sign bit (the direction's: 1 / -0 = -inf).
        const uint32_t negative = uint32_t(_mm_movemask_ps(inv)) & 7u;
        plane_offset = kPlaneOffsets.at[negative];
        // WatertightRay: kz = max_axis(|dir|) from |dx| >= |dy|, |dx| >= |dz|, |dy| >= |dz|.
        const __m128 first = _mm_shuffle_ps(abs_dir, abs_dir, _MM_SHUFFLE(3, 1, 0, 0));   // |dx| |dx| |dy|
        const __m128 second = _mm_shuffle_ps(abs_dir, abs_dir, _MM_SHUFFLE(3, 2, 2, 1));  // |dy| |dz| |dz|
        const uint32_t ge = uint32_t(_mm_movemask_ps(_mm_cmpge_ps(first, second))) & 7u;
        const uint32_t axes = detail::kWatertightAxes.axes[ge | negative << 3];
        kx = int(axes & 3u);
        ky = int((axes >> 2) & 3u);
        kz = int(axes >> 4);
        const float* dir = raw + 4;
        const __m128 s = _mm_div_ps(_mm_setr_ps(dir[kx], dir[ky], 1.0f, 1.0f), _mm_set1_ps(dir[kz]));
        shear[0] = _mm_shuffle_ps(s, s, _MM_SHUFFLE(0, 0, 0, 0));
        shear[1] = _mm_shuffle_ps(s, s, _MM_SHUFFLE(1, 1, 1, 1));
        shear[2] = _mm_shuffle_ps(s, s, _MM_SHUFFLE(2, 2, 2, 2));
        const int k[3] = {kx, ky, kz};
        for (int i = 0; i < 3; ++i) {
            org_k[i] = _mm_set1_ps(raw[k[i]]);
            row_offset[i] = size_t(k[i]) * sizeof(WbvhTriPacket::v[0][0]);
        }
    }

    // The byte offsets of the near and far plane rows for each combination of the
    // direction's sign bits (bit a: axis a travels toward -a, its upper plane met first).
    struct PlaneOffsets {
        uint32_t at[8][6];
        constexpr PlaneOffsets() : at{} {
            for (uint32_t s = 0; s < 8; ++s)
                for (uint32_t a = 0; a < 3; ++a) {
                    const uint32_t upper_first = (s >> a) & 1u;
                    at[s][a] = (a + 3 * upper_first) * W * uint32_t(sizeof(float));
                    at[s][3 + a] = (a + 3 - 3 * upper_first) * W * uint32_t(sizeof(float));
                }
        }
    };
    static constexpr PlaneOffsets kPlaneOffsets{};

    // The plane a slab test reads of `node`: row `slot` of plane_offset (0-2 near, 3-5 far)
    // from lane `offset` on.
    const float* plane(const WbvhNode<W>& node, int slot, int offset = 0) const {
        return reinterpret_cast<const float*>(reinterpret_cast<const char*>(node.planes) + plane_offset[slot]) + offset;
    }
};
#endif

// The ray constants a kernel uses: the vector form where it is compiled in.
template <int W, bool kVector>
using WbvhRay =
#if defined(ACCELBENCH_WBVH_SSE)
    std::conditional_t<kVector, WbvhVectorRay<W>, WbvhScalarRay>;
#else
    WbvhScalarRay;
#endif

// Tests the ray against every child box of `node` over [tmin, tmax], as intersect_box does
// (conservative: the far distance widened by 2 gamma(3), Ize 2013). Writes each child's
// entry distance to tnear[k] and returns the mask of children hit (bit k: child k). Unused
// slots never hit. The scalar form: intersect_box per child.
template <int W>
inline uint32_t wbvh_slab_test(const WbvhNode<W>& node, const WbvhScalarRay& r, float tmin, float tmax,
                               float (&tnear)[W]) {
    uint32_t mask = 0;
    for (int k = 0; k < W; ++k) {
        const BoxHit h = intersect_box(node.child_bounds(k), r.rp, tmin, tmax);
        tnear[k] = h.tnear;
        if (h.hit()) mask |= 1u << k;
    }
    return mask;
}

#if defined(ACCELBENCH_WBVH_SSE)
namespace detail {

// The hit mask of the widened test (tn <= tf + kBoxSlack |tf|), returned as the mask of
// the unwidened one (tn <= tf) whenever both are equal — nearly always: they differ only
// for a box the ray grazes within the slack (or tf = -inf). The unwidened mask is ready
// 7 cycles sooner (no abs, multiply, add), and the traversal's next node address depends
// on it: the comparison of the two is a branch the processor predicts, so the slack's
// latency leaves the node-to-node dependency chain while the answer stays the widened
// test's, bit for bit. The empty asm hides from GCC that no difference means equal masks
// (it would otherwise use `wide` for `fast` there, and the chain would wait for it again).
// Measured (trace/<model>/wbvh8): the masks differed at 10 of the bunny's 688,342
// closest-hit node tests; +4% instructions (166.2M -> 172.8M on the bunny) for a small,
// consistent gain in time, interleaved A/B under load ~8: dragon 1.37x/1.38x -> 1.34x/1.37x
// Embree, conference 1.10x/1.17x -> 1.07x/1.13x.
inline uint32_t widened_mask(uint32_t fast, uint32_t wide) {
    uint32_t differ = fast ^ wide;
    asm("" : "+r"(differ));
    if (differ != 0) [[unlikely]] {
        asm volatile("" : "+r"(wide));  // a branch, not a cmov (which would wait for `wide`)
        return wide;
    }
    return fast;
}

// The 4 lanes planes[.][offset, offset + 4) of intersect_box, in SSE. Returns the hit mask.
// (One 8-lane AVX chain for a 4-wide node was slower: docs/decisions.md.)
template <int W>
inline uint32_t slab_test_sse(const WbvhNode<W>& node, int offset, const WbvhVectorRay<W>& r, float tmin, float tmax,
                              float* tnear) {
    static_assert(sizeof(typename WbvhVectorRay<W>::Lanes) == 16);
    __m128 tn = _mm_set1_ps(tmin), tf = _mm_set1_ps(tmax);
    for (int a = 0; a < 3; ++a) {
        const __m128 o = r.org[a], inv = r.inv_dir[a];
        const __m128 n = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(r.plane(node, a, offset)), o), inv);
        const __m128 f = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(r.plane(node, 3 + a, offset)), o), inv);
        tn = _mm_max_ps(n, tn);  // n > tn ? n : tn, as intersect_box
        tf = _mm_min_ps(f, tf);  // f < tf ? f : tf
    }
    const __m128 abs_tf = _mm_andnot_ps(_mm_set1_ps(-0.0f), tf);
    const __m128 tf_wide = _mm_add_ps(tf, _mm_mul_ps(_mm_set1_ps(kBoxSlack), abs_tf));  // Ize 2013
    _mm_storeu_ps(tnear, tn);
    return widened_mask(uint32_t(_mm_movemask_ps(_mm_cmple_ps(tn, tf))),
                        uint32_t(_mm_movemask_ps(_mm_cmple_ps(tn, tf_wide))));
}

}  // namespace detail

// The vector form: one AVX test of 8 lanes, or 4-lane SSE tests.
template <int W>
inline uint32_t wbvh_slab_test(const WbvhNode<W>& node, const WbvhVectorRay<W>& r, float tmin, float tmax,
                               float (&tnear)[W]) {
#if defined(ACCELBENCH_WBVH_AVX)
    if constexpr (W == 8) {
        __m256 tn = _mm256_set1_ps(tmin), tf = _mm256_set1_ps(tmax);
        for (int a = 0; a < 3; ++a) {
            const __m256 o = r.org[a], inv = r.inv_dir[a];
            const __m256 n = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(r.plane(node, a)), o), inv);
            const __m256 f = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(r.plane(node, 3 + a)), o), inv);
            tn = _mm256_max_ps(n, tn);
            tf = _mm256_min_ps(f, tf);
        }
        const __m256 abs_tf = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), tf);
        const __m256 tf_wide = _mm256_add_ps(tf, _mm256_mul_ps(_mm256_set1_ps(kBoxSlack), abs_tf));
        _mm256_storeu_ps(tnear, tn);
        return detail::widened_mask(uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(tn, tf, _CMP_LE_OQ))),
                                    uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(tn, tf_wide, _CMP_LE_OQ))));
    } else
#endif
    {
        uint32_t mask = 0;
        for (int offset = 0; offset < W; offset += 4)
            mask |= detail::slab_test_sse(node, offset, r, tmin, tmax, tnear + offset) << offset;
        return mask;
    }
}
#endif

// Result of one packet test: lanes hit (bit k: lane k) and their distances and barycentrics.
struct WbvhPacketHits {
    uint32_t mask = 0;
    float t[WbvhTriPacket::kLanes], u[WbvhTriPacket::kLanes], v[WbvhTriPacket::kLanes];

    // The nearest lane hit (the lowest such lane among equal distances, as a test of the
    // lanes one after the other against a shrinking interval would keep); mask must be set.
    int nearest() const {
        uint32_t m = mask;
        int best = std::countr_zero(m);
        for (m &= m - 1; m; m &= m - 1) {
            const int k = std::countr_zero(m);
            if (t[k] < t[best]) best = k;
        }
        return best;
    }
};

// Tests the first `lanes` triangles of a packet against [tmin, tmax), each exactly as
// intersect_triangle (Woop et al. 2013) does — all of them against the same interval.
// kAnyHit names the query the test serves (the vector form returns early for closest-hit
// rays only); the answer is the same for both. The scalar form: intersect_triangle per lane.
template <bool kAnyHit = false>
inline WbvhPacketHits wbvh_packet_test(const WbvhTriPacket& p, int lanes, const WbvhScalarRay& r, float tmin,
                                       float tmax) {
    WbvhPacketHits out;
    for (int k = 0; k < lanes; ++k) {
        const Vec3 p0{p.v[0][0][k], p.v[0][1][k], p.v[0][2][k]};
        const Vec3 p1{p.v[1][0][k], p.v[1][1][k], p.v[1][2][k]};
        const Vec3 p2{p.v[2][0][k], p.v[2][1][k], p.v[2][2][k]};
        if (intersect_triangle(r.wr, p0, p1, p2, tmin, tmax, out.t[k], out.u[k], out.v[k])) out.mask |= 1u << k;
    }
    return out;
}

#if defined(ACCELBENCH_WBVH_SSE)
// The vector form, 4 lanes in SSE; `r` must be valid (the traversal answers invalid rays
// before any test). t, u, v are written for the lanes hit only, as the scalar form does:
// a packet no lane of which hits returns before the division (57% of the bunny's
// closest-hit packets hit, and the shadow rays' any-hit never reads t).
template <bool kAnyHit = false, int W>
inline WbvhPacketHits wbvh_packet_test(const WbvhTriPacket& p, int lanes, const WbvhVectorRay<W>& r, float tmin,
                                       float tmax) {
    WbvhPacketHits out;
    const uint32_t valid = (1u << lanes) - 1;
    const __m128 sx = r.shear[0], sy = r.shear[1], sz = r.shear[2];
    const __m128 okx = r.org_k[0], oky = r.org_k[1], okz = r.org_k[2];
    // Sheared vertex i (section 3 of the paper): x, y, z in ray space.
    __m128 sh[3][3];
    for (int i = 0; i < 3; ++i) {
        const char* vertex = reinterpret_cast<const char*>(p.v[i]);
        const __m128 dkx = _mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(vertex + r.row_offset[0])), okx);
        const __m128 dky = _mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(vertex + r.row_offset[1])), oky);
        const __m128 dkz = _mm_sub_ps(_mm_load_ps(reinterpret_cast<const float*>(vertex + r.row_offset[2])), okz);
        sh[i][0] = _mm_sub_ps(dkx, _mm_mul_ps(sx, dkz));
        sh[i][1] = _mm_sub_ps(dky, _mm_mul_ps(sy, dkz));
        sh[i][2] = _mm_mul_ps(sz, dkz);
    }
    const __m128 ax = sh[0][0], ay = sh[0][1], bx = sh[1][0], by = sh[1][1], cx = sh[2][0], cy = sh[2][1];
    const __m128 e0 = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
    const __m128 e1 = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
    const __m128 e2 = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
    const __m128 zero = _mm_setzero_ps();
    const uint32_t edge_zero = uint32_t(
        _mm_movemask_ps(_mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(e0, zero), _mm_cmpeq_ps(e1, zero)), _mm_cmpeq_ps(e2, zero))));
    // Outside (edge functions of both strict signs) from the sign bits: set in the OR of the
    // three (one is negative) and clear in their AND (not all are, so one is positive) — 5
    // operations for the 11 of six comparisons. Equal to the comparisons on every lane that
    // decides with it: the edge functions are never NaN (vertices and origins below
    // kMaxCoordinate keep every product and difference finite, geometry.h), a non-zero one
    // has its sign bit exactly when it is negative, and a lane with a zero one is in
    // edge_zero, whose lanes the mask leaves out and the double-precision end decides
    // whatever `outside` says (under DAZ a denormal compares equal to zero: edge_zero too).
    const uint32_t outside =
        uint32_t(_mm_movemask_ps(_mm_andnot_ps(_mm_and_ps(_mm_and_ps(e0, e1), e2), _mm_or_ps(_mm_or_ps(e0, e1), e2))));
    // Closest hit: a packet every valid lane of which is outside its edges (and on none) is
    // answered here, before the determinant, t and the representability tests — the answer
    // the code below would give (mask and slow lanes both empty). Measured, it pays on
    // closest-hit rays and costs the any-hit ones, for which it is left out (docs/decisions.md).
    if constexpr (!kAnyHit)
        if ((valid & (~outside | edge_zero)) == 0) return out;
    const __m128 det = _mm_add_ps(_mm_add_ps(e0, e1), e2);
    const __m128 ts =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(e0, sh[0][2]), _mm_mul_ps(e1, sh[1][2])), _mm_mul_ps(e2, sh[2][2]));
    const __m128 sign = _mm_set1_ps(-0.0f);
    const __m128 flt_min = _mm_set1_ps(std::numeric_limits<float>::min());
    const __m128 abs_ts = _mm_andnot_ps(sign, ts);
    const __m128 abs_det = _mm_andnot_ps(sign, det);
    const __m128 representable =
        _mm_and_ps(_mm_cmpge_ps(abs_det, flt_min),
                   _mm_and_ps(_mm_cmpge_ps(abs_ts, flt_min),
                              _mm_cmple_ps(abs_ts, _mm_set1_ps(std::numeric_limits<float>::max()))));
    const uint32_t unrepresentable = ~uint32_t(_mm_movemask_ps(representable)) & 0xfu;
    // t in [tmin, tmax) compared before dividing. The scalar test flips its inequalities for
    // a negative det (!(ts > tmin det) && ts > tmax det); here t_scaled takes det's sign
    // instead and is compared with |det|: tmin det = -(tmin |det|) exactly (a product's
    // sign is its operands' XOR, its magnitude rounds alike), so the two forms agree on
    // every lane the mask keeps (representable: det non-zero, t_scaled finite). NLT is the
    // scalar code's !(a < b).
    const __m128 ts_signed = _mm_xor_ps(ts, _mm_and_ps(sign, det));
    const __m128 in = _mm_and_ps(_mm_cmpnlt_ps(ts_signed, _mm_mul_ps(_mm_set1_ps(tmin), abs_det)),
                                 _mm_cmplt_ps(ts_signed, _mm_mul_ps(_mm_set1_ps(tmax), abs_det)));
    out.mask = valid & ~edge_zero & ~outside & ~unrepresentable & uint32_t(_mm_movemask_ps(in));
    // The scalar test's double-precision ends (triangle.h): an edge function exactly zero,
    // or, inside the edges, a determinant or t_scaled float cannot divide. Rare: per lane.
    uint32_t slow = valid & (edge_zero | (~outside & unrepresentable));
    if (out.mask == 0 && slow == 0) return out;
    if (out.mask) {
        // Lanes that do not hit divide 1 by 1, so no lane divides by zero.
        const __m128 one = _mm_set1_ps(1.0f);
        const __m128 hit_lanes = _mm_castsi128_ps(_mm_cmpgt_epi32(
            _mm_and_si128(_mm_set1_epi32(int(out.mask)), _mm_setr_epi32(1, 2, 4, 8)), _mm_setzero_si128()));
        const __m128 inv_det = _mm_div_ps(one, _mm_or_ps(_mm_and_ps(hit_lanes, det), _mm_andnot_ps(hit_lanes, one)));
        _mm_storeu_ps(out.t, _mm_mul_ps(ts, inv_det));
        _mm_storeu_ps(out.u, _mm_mul_ps(e1, inv_det));
        _mm_storeu_ps(out.v, _mm_mul_ps(e2, inv_det));
    }
    if (slow) {
        alignas(16) float s[3][3][4];
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) _mm_store_ps(s[i][j], sh[i][j]);
        for (; slow; slow &= slow - 1) {
            const int k = std::countr_zero(slow);
            if (detail::finish_in_double(s[0][0][k], s[0][1][k], s[1][0][k], s[1][1][k], s[2][0][k], s[2][1][k],
                                         s[0][2][k], s[1][2][k], s[2][2][k], tmin, tmax, out.t[k], out.u[k], out.v[k]))
                out.mask |= 1u << k;
        }
    }
    return out;
}
#endif

// A leaf's `count` triangles in consecutive packets from `p` (the wide BVH's leaves, and the
// binary BVH's with leaf_test=packet): each packet against the interval the packets before it
// left, so the closest hit is that of testing the triangles one after the other — the
// nearest, and of equally near ones the first. Closest hit (kAnyHit false): on a closer hit
// writes `hit` and shrinks tmax; returns whether there was one. Any hit: returns true at the
// first packet with a hit, leaving tmax and `hit` as they are. c.prim() per lane tested.
// `test(packet, lanes, tmax)` tests one packet (the ablations pass their own, on their
// own packets).
template <bool kAnyHit, class P, class Test, class C>
inline bool wbvh_leaf_packets(const P* p, uint32_t count, Test&& test, float& tmax, Hit& hit, C& c) {
    bool found = false;
    for (uint32_t done = 0; done < count; done += P::kLanes, ++p) {
        const int lanes = int(std::min<uint32_t>(P::kLanes, count - done));
        c.prim(uint64_t(lanes));
        const WbvhPacketHits h = test(*p, lanes, tmax);
        if (h.mask == 0) continue;
        if constexpr (kAnyHit) return true;
        const int k = h.nearest();
        tmax = h.t[k];
        hit = {p->prim[k], h.t[k], h.u[k], h.v[k]};
        found = true;
    }
    return found;
}

template <bool kAnyHit, class R, class C>
inline bool wbvh_leaf_test(const WbvhTriPacket* p, uint32_t count, const R& r, float tmin, float& tmax, Hit& hit,
                           C& c) {
    return wbvh_leaf_packets<kAnyHit>(
        p, count,
        [&](const WbvhTriPacket& packet, int lanes, float t_max) {
            return wbvh_packet_test<kAnyHit>(packet, lanes, r, tmin, t_max);
        },
        tmax, hit, c);
}

}  // namespace accelbench
