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
// triangle.h) per lane, so the test that compares the two forms (wbvh_test) checks the
// vector code against the project's scalar definitions.
//
// Why both forms agree exactly: the vector code performs the same IEEE operations in the same
// order as the scalar code (no FMA: CMakeLists.txt compiles with -ffp-contract=off, so GCC
// contracts neither the scalar a * b + c nor the intrinsics' vector one; no reciprocal
// approximations), and its min/max are the SSE MINPS/MAXPS,
// which return the second operand when either is NaN — the "new value wins only if the test
// is true" form intersect_box relies on for a ray lying in a slab's plane.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

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
    float v[3][3][kLanes];  // [vertex][axis][lane]
    uint32_t prim[kLanes];  // triangle index in the scene
};
static_assert(sizeof(WbvhTriPacket) == 160);

// What the slab test needs of a ray beyond RayPrecomp: for each axis the row of `planes`
// the ray meets first (the upper plane when it travels toward -axis, by the sign bit of the
// reciprocal as RayPrecomp::near_is_upper) and the other one. Read from the reciprocal
// itself, not from near_is_upper: GCC loads two of those ints as one 8-byte word right after
// storing them one by one, a failed store forwarding that perf showed as 8% of traversal.
struct WbvhRayPlanes {
    int near_row[3], far_row[3];
    explicit WbvhRayPlanes(const RayPrecomp& rp) {
        for (int a = 0; a < 3; ++a) {
            const bool upper_first = std::signbit(rp.inv_dir[a]);
            near_row[a] = upper_first ? 3 + a : a;
            far_row[a] = upper_first ? a : 3 + a;
        }
    }
};

namespace detail {

#if defined(ACCELBENCH_WBVH_SSE)
// The 4 lanes planes[.][offset, offset + 4) of intersect_box, in SSE. Returns the hit mask.
template <int W>
inline uint32_t slab_test_sse(const WbvhNode<W>& node, int offset, const RayPrecomp& rp, const WbvhRayPlanes& rows,
                              float tmin, float tmax, float* tnear) {
    __m128 tn = _mm_set1_ps(tmin), tf = _mm_set1_ps(tmax);
    for (int a = 0; a < 3; ++a) {
        const __m128 o = _mm_set1_ps(rp.org[a]), inv = _mm_set1_ps(rp.inv_dir[a]);
        const __m128 n = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.planes[rows.near_row[a]] + offset), o), inv);
        const __m128 f = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node.planes[rows.far_row[a]] + offset), o), inv);
        tn = _mm_max_ps(n, tn);  // n > tn ? n : tn, as intersect_box
        tf = _mm_min_ps(f, tf);  // f < tf ? f : tf
    }
    const __m128 abs_tf = _mm_andnot_ps(_mm_set1_ps(-0.0f), tf);
    const __m128 tf_wide = _mm_add_ps(tf, _mm_mul_ps(_mm_set1_ps(kBoxSlack), abs_tf));  // Ize 2013
    _mm_storeu_ps(tnear, tn);
    return uint32_t(_mm_movemask_ps(_mm_cmple_ps(tn, tf_wide)));
}
#endif

}  // namespace detail

// Tests the ray against every child box of `node` over [tmin, tmax], as intersect_box does
// (conservative: the far distance widened by 2 gamma(3), Ize 2013). Writes each child's
// entry distance to tnear[k] and returns the mask of children hit (bit k: child k). Unused
// slots never hit.
template <bool kVector, int W>
inline uint32_t wbvh_slab_test(const WbvhNode<W>& node, const RayPrecomp& rp, const WbvhRayPlanes& rows, float tmin,
                               float tmax, float (&tnear)[W]) {
#if defined(ACCELBENCH_WBVH_SSE)
    if constexpr (kVector) {
#if defined(ACCELBENCH_WBVH_AVX)
        if constexpr (W == 8) {
            __m256 tn = _mm256_set1_ps(tmin), tf = _mm256_set1_ps(tmax);
            for (int a = 0; a < 3; ++a) {
                const __m256 o = _mm256_set1_ps(rp.org[a]), inv = _mm256_set1_ps(rp.inv_dir[a]);
                const __m256 n = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node.planes[rows.near_row[a]]), o), inv);
                const __m256 f = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node.planes[rows.far_row[a]]), o), inv);
                tn = _mm256_max_ps(n, tn);
                tf = _mm256_min_ps(f, tf);
            }
            const __m256 abs_tf = _mm256_andnot_ps(_mm256_set1_ps(-0.0f), tf);
            const __m256 tf_wide = _mm256_add_ps(tf, _mm256_mul_ps(_mm256_set1_ps(kBoxSlack), abs_tf));
            _mm256_storeu_ps(tnear, tn);
            return uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(tn, tf_wide, _CMP_LE_OQ)));
        }
#endif
        uint32_t mask = 0;
        for (int offset = 0; offset < W; offset += 4)
            mask |= detail::slab_test_sse(node, offset, rp, rows, tmin, tmax, tnear + offset) << offset;
        return mask;
    }
#endif
    (void)rows;
    uint32_t mask = 0;
    for (int k = 0; k < W; ++k) {
        const BoxHit h = intersect_box(node.child_bounds(k), rp, tmin, tmax);
        tnear[k] = h.tnear;
        if (h.hit()) mask |= 1u << k;
    }
    return mask;
}

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
template <bool kVector>
inline WbvhPacketHits wbvh_packet_test(const WbvhTriPacket& p, int lanes, const WatertightRay& r, float tmin,
                                       float tmax) {
    WbvhPacketHits out;
    if (!r.valid) return out;
    const uint32_t valid = (1u << lanes) - 1;
#if defined(ACCELBENCH_WBVH_SSE)
    if constexpr (kVector) {
        const int kx = r.kx, ky = r.ky, kz = r.kz;
        const __m128 sx = _mm_set1_ps(r.sx), sy = _mm_set1_ps(r.sy), sz = _mm_set1_ps(r.sz);
        const __m128 okx = _mm_set1_ps(r.org[kx]), oky = _mm_set1_ps(r.org[ky]), okz = _mm_set1_ps(r.org[kz]);
        // Sheared vertex i (section 3 of the paper): x, y, z in ray space.
        __m128 sh[3][3];
        for (int i = 0; i < 3; ++i) {
            const __m128 dkx = _mm_sub_ps(_mm_load_ps(p.v[i][kx]), okx);
            const __m128 dky = _mm_sub_ps(_mm_load_ps(p.v[i][ky]), oky);
            const __m128 dkz = _mm_sub_ps(_mm_load_ps(p.v[i][kz]), okz);
            sh[i][0] = _mm_sub_ps(dkx, _mm_mul_ps(sx, dkz));
            sh[i][1] = _mm_sub_ps(dky, _mm_mul_ps(sy, dkz));
            sh[i][2] = _mm_mul_ps(sz, dkz);
        }
        const __m128 ax = sh[0][0], ay = sh[0][1], bx = sh[1][0], by = sh[1][1], cx = sh[2][0], cy = sh[2][1];
        const __m128 e0 = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
        const __m128 e1 = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
        const __m128 e2 = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
        const __m128 zero = _mm_setzero_ps();
        const uint32_t edge_zero = uint32_t(_mm_movemask_ps(
            _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(e0, zero), _mm_cmpeq_ps(e1, zero)), _mm_cmpeq_ps(e2, zero))));
        const __m128 any_neg =
            _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(e0, zero), _mm_cmplt_ps(e1, zero)), _mm_cmplt_ps(e2, zero));
        const __m128 any_pos =
            _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(e0, zero), _mm_cmpgt_ps(e1, zero)), _mm_cmpgt_ps(e2, zero));
        const uint32_t outside = uint32_t(_mm_movemask_ps(_mm_and_ps(any_neg, any_pos)));
        const __m128 det = _mm_add_ps(_mm_add_ps(e0, e1), e2);
        const __m128 ts =
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(e0, sh[0][2]), _mm_mul_ps(e1, sh[1][2])), _mm_mul_ps(e2, sh[2][2]));
        const __m128 sign = _mm_set1_ps(-0.0f);
        const __m128 flt_min = _mm_set1_ps(std::numeric_limits<float>::min());
        const __m128 abs_ts = _mm_andnot_ps(sign, ts);
        const __m128 representable =
            _mm_and_ps(_mm_cmpge_ps(_mm_andnot_ps(sign, det), flt_min),
                       _mm_and_ps(_mm_cmpge_ps(abs_ts, flt_min),
                                  _mm_cmple_ps(abs_ts, _mm_set1_ps(std::numeric_limits<float>::max()))));
        const uint32_t unrepresentable = ~uint32_t(_mm_movemask_ps(representable)) & 0xfu;
        // t in [tmin, tmax) compared before dividing, the inequalities flipped with det's sign
        // (the negations written as NLT / NGT, exactly the scalar code's !(a < b)).
        const __m128 tmin_det = _mm_mul_ps(_mm_set1_ps(tmin), det), tmax_det = _mm_mul_ps(_mm_set1_ps(tmax), det);
        const __m128 in_pos = _mm_and_ps(_mm_cmpnlt_ps(ts, tmin_det), _mm_cmplt_ps(ts, tmax_det));
        const __m128 in_neg = _mm_and_ps(_mm_cmpngt_ps(ts, tmin_det), _mm_cmpgt_ps(ts, tmax_det));
        const __m128 det_pos = _mm_cmpgt_ps(det, zero);
        const __m128 in = _mm_or_ps(_mm_and_ps(det_pos, in_pos), _mm_andnot_ps(det_pos, in_neg));
        out.mask = valid & ~edge_zero & ~outside & ~unrepresentable & uint32_t(_mm_movemask_ps(in));
        // Lanes that do not hit divide 1 by 1, so no lane divides by zero.
        const __m128 one = _mm_set1_ps(1.0f);
        const __m128 hit_lanes = _mm_castsi128_ps(_mm_cmpgt_epi32(
            _mm_and_si128(_mm_set1_epi32(int(out.mask)), _mm_setr_epi32(1, 2, 4, 8)), _mm_setzero_si128()));
        const __m128 inv_det = _mm_div_ps(one, _mm_or_ps(_mm_and_ps(hit_lanes, det), _mm_andnot_ps(hit_lanes, one)));
        _mm_storeu_ps(out.t, _mm_mul_ps(ts, inv_det));
        _mm_storeu_ps(out.u, _mm_mul_ps(e1, inv_det));
        _mm_storeu_ps(out.v, _mm_mul_ps(e2, inv_det));
        // The scalar test's double-precision ends (triangle.h): an edge function exactly zero,
        // or, inside the edges, a determinant or t_scaled float cannot divide. Rare: per lane.
        uint32_t slow = valid & (edge_zero | (~outside & unrepresentable));
        if (slow) {
            alignas(16) float s[3][3][4];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) _mm_store_ps(s[i][j], sh[i][j]);
            for (; slow; slow &= slow - 1) {
                const int k = std::countr_zero(slow);
                if (detail::finish_in_double(s[0][0][k], s[0][1][k], s[1][0][k], s[1][1][k], s[2][0][k], s[2][1][k],
                                             s[0][2][k], s[1][2][k], s[2][2][k], tmin, tmax, out.t[k], out.u[k],
                                             out.v[k]))
                    out.mask |= 1u << k;
            }
        }
        return out;
    }
#endif
    for (int k = 0; k < lanes; ++k) {
        const Vec3 p0{p.v[0][0][k], p.v[0][1][k], p.v[0][2][k]};
        const Vec3 p1{p.v[1][0][k], p.v[1][1][k], p.v[1][2][k]};
        const Vec3 p2{p.v[2][0][k], p.v[2][1][k], p.v[2][2][k]};
        if (intersect_triangle(r, p0, p1, p2, tmin, tmax, out.t[k], out.u[k], out.v[k])) out.mask |= 1u << k;
    }
    (void)valid;
    return out;
}

}  // namespace accelbench
