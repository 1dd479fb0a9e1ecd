// The wide BVH's two ablations: the tests Embree's default answers with, which give up the
// guarantees of wbvh_simd.h's tests for speed. They exist to put a number on that price
// (`leaf_test=moeller`, `node_test=fma`); the defaults stay watertight and conservative.
//
//   leaf_test=moeller  Möller & Trumbore 1997 ("Fast, minimum storage ray/triangle
//                      intersection") in float on triangles precomputed at build, as Embree's
//                      Triangle4 (v0, e1 = v0 - v1, e2 = v2 - v0, n = e1 x e2; Embree 3,
//                      kernels/geometry/triangle_intersector_moeller.h). Not watertight: a ray
//                      through a shared edge or vertex may miss both triangles.
//   node_test=fma      the slab distances as one fused multiply-add, plane * (1 / d) - o / d,
//                      with no widening of the far distance (Embree's non-robust node test,
//                      kernels/bvh/node_intersector1.h). Not conservative: rounding may cut off
//                      a box the ray touches.
//
// Each in a scalar form and a vector form that answer bit for bit alike, as wbvh_simd.h's
// (the same IEEE operations in the same order; std::fma is the fused operation the vector
// FMA performs, correctly rounded once).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "accelbench/accel/bvh/wbvh_simd.h"

namespace accelbench {

// Four triangles of one leaf as Embree's Triangle4 stores them, made from a WbvhTriPacket
// (same lanes, same prim). Unused lanes: zeros, prim kInvalidId, masked off by the test.
struct alignas(16) WbvhMoellerPacket {
    static constexpr int kLanes = 4;
    float v0[3][kLanes], e1[3][kLanes], e2[3][kLanes], n[3][kLanes];  // [axis][lane]
    uint32_t prim[kLanes];

    static WbvhMoellerPacket from(const WbvhTriPacket& p) {
        WbvhMoellerPacket m{};
        for (int k = 0; k < kLanes; ++k) {
            for (int a = 0; a < 3; ++a) {
                m.v0[a][k] = p.v[0][a][k];
                m.e1[a][k] = p.v[0][a][k] - p.v[1][a][k];
                m.e2[a][k] = p.v[2][a][k] - p.v[0][a][k];
            }
            for (int a = 0; a < 3; ++a) {
                const int b = (a + 1) % 3, c = (a + 2) % 3;
                m.n[a][k] = m.e1[b][k] * m.e2[c][k] - m.e1[c][k] * m.e2[b][k];
            }
            m.prim[k] = p.prim[k];
        }
        return m;
    }
};
static_assert(sizeof(WbvhMoellerPacket) == 208);

// The ablations' per-ray constants, made once per ray of an ablation's traversal only:
// origin, direction, reciprocal (1 / d, as the slab test's) and -(o * (1 / d)) per axis,
// and the near plane row of each axis (RayPrecomp's). With SSE, the same values broadcast.
template <int W>
struct WbvhAblationRay {
    float org[3], dir[3], inv[3], neg_org_inv[3];
    uint32_t near_row[3], far_row[3];
#if defined(ACCELBENCH_WBVH_SSE)
    using Lanes = typename detail::SlabLanes<W>::type;
    Lanes neg_org_inv_lanes[3];
    __m128 org4[3], dir4[3];
#endif

    explicit WbvhAblationRay(const Ray& ray) {
        for (int a = 0; a < 3; ++a) {
            org[a] = ray.org[a];
            dir[a] = ray.dir[a];
            inv[a] = safe_inverse(ray.dir[a]);  // +-inf for a zero component, as RayPrecomp
            neg_org_inv[a] = -(org[a] * inv[a]);
            const uint32_t upper_first = std::signbit(inv[a]) ? 1u : 0u;
            near_row[a] = uint32_t(a) + 3 * upper_first;
            far_row[a] = uint32_t(a) + 3 * (1 - upper_first);
#if defined(ACCELBENCH_WBVH_SSE)
            if constexpr (sizeof(Lanes) == 32) neg_org_inv_lanes[a] = _mm256_set1_ps(neg_org_inv[a]);
            else neg_org_inv_lanes[a] = _mm_set1_ps(neg_org_inv[a]);
            org4[a] = _mm_set1_ps(org[a]);
            dir4[a] = _mm_set1_ps(dir[a]);
#endif
        }
    }
};

namespace detail {
inline float flip_sign(float x, float sign_of) {
    return std::bit_cast<float>(std::bit_cast<uint32_t>(x) ^ (std::bit_cast<uint32_t>(sign_of) & 0x80000000u));
}
}  // namespace detail

// node_test=fma, scalar form: per child and axis, near = fma(plane, 1 / d, -o / d) (the
// same for far), tn = max, tf = min in MAXPS / MINPS's operand order, hit where tn <= tf,
// unwidened. Only used slots can hit (a zero direction component with a zero origin makes
// the distances NaN, which would otherwise let an empty slot through).
template <int W>
inline uint32_t wbvh_slab_test_fma(const WbvhNode<W>& node, const WbvhAblationRay<W>& r, float tmin, float tmax,
                                   float (&tnear)[W]) {
    uint32_t mask = 0;
    for (int k = 0; k < W; ++k) {
        float tn = tmin, tf = tmax;
        for (int a = 0; a < 3; ++a) {
            const float n = std::fma(node.planes[r.near_row[a]][k], r.inv[a], r.neg_org_inv[a]);
            const float f = std::fma(node.planes[r.far_row[a]][k], r.inv[a], r.neg_org_inv[a]);
            tn = n > tn ? n : tn;
            tf = f < tf ? f : tf;
        }
        tnear[k] = tn;
        if (tn <= tf && node.child[k] != kInvalidId) mask |= 1u << k;
    }
    return mask;
}

#if defined(ACCELBENCH_WBVH_SSE) && defined(__FMA__)
// The vector form: 8 lanes of AVX2 + FMA for W = 8, else 4 lanes of SSE + FMA.
template <int W>
inline uint32_t wbvh_slab_test_fma_vector(const WbvhNode<W>& node, const WbvhAblationRay<W>& r, float tmin, float tmax,
                                          float (&tnear)[W]) {
    const auto row = [&](uint32_t plane_row, int offset) { return node.planes[plane_row] + offset; };
    uint32_t mask = 0;
#if defined(ACCELBENCH_WBVH_AVX)
    if constexpr (W == 8) {
        __m256 tn = _mm256_set1_ps(tmin), tf = _mm256_set1_ps(tmax);
        for (int a = 0; a < 3; ++a) {
            const __m256 inv = _mm256_set1_ps(r.inv[a]), noi = r.neg_org_inv_lanes[a];
            tn = _mm256_max_ps(_mm256_fmadd_ps(_mm256_load_ps(row(r.near_row[a], 0)), inv, noi), tn);
            tf = _mm256_min_ps(_mm256_fmadd_ps(_mm256_load_ps(row(r.far_row[a], 0)), inv, noi), tf);
        }
        _mm256_storeu_ps(tnear, tn);
        mask = uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(tn, tf, _CMP_LE_OQ)));
    } else
#endif
    {
        for (int offset = 0; offset < W; offset += 4) {
            __m128 tn = _mm_set1_ps(tmin), tf = _mm_set1_ps(tmax);
            for (int a = 0; a < 3; ++a) {
                const __m128 inv = _mm_set1_ps(r.inv[a]), noi = _mm_set1_ps(r.neg_org_inv[a]);
                tn = _mm_max_ps(_mm_fmadd_ps(_mm_load_ps(row(r.near_row[a], offset)), inv, noi), tn);
                tf = _mm_min_ps(_mm_fmadd_ps(_mm_load_ps(row(r.far_row[a], offset)), inv, noi), tf);
            }
            _mm_storeu_ps(tnear + offset, tn);
            mask |= uint32_t(_mm_movemask_ps(_mm_cmple_ps(tn, tf))) << offset;
        }
    }
    uint32_t used = 0;
    for (int k = 0; k < W; ++k) used |= uint32_t(node.child[k] != kInvalidId) << k;
    return mask & used;
}
#endif

// leaf_test=moeller, scalar form, the first `lanes` triangles of a packet against
// [tmin, tmax): with C = v0 - o, R = d x C, den = n . d, and U = R . e2, V = R . e1,
// T = n . C each given den's sign: a hit where den != 0, U >= 0, V >= 0, U + V <= |den|
// and |den| tmin <= T < |den| tmax; t, u, v = T, U, V over |den| (u the weight of vertex
// 1, v of vertex 2, as intersect_triangle's).
inline WbvhPacketHits wbvh_moeller_test(const WbvhMoellerPacket& p, int lanes, const float (&o)[3], const float (&d)[3],
                                        float tmin, float tmax) {
    WbvhPacketHits out;
    for (int k = 0; k < lanes; ++k) {
        const float c[3] = {p.v0[0][k] - o[0], p.v0[1][k] - o[1], p.v0[2][k] - o[2]};
        const float r[3] = {d[1] * c[2] - d[2] * c[1], d[2] * c[0] - d[0] * c[2], d[0] * c[1] - d[1] * c[0]};
        const float den = p.n[0][k] * d[0] + p.n[1][k] * d[1] + p.n[2][k] * d[2];
        const float abs_den = std::fabs(den);
        const float u = detail::flip_sign(r[0] * p.e2[0][k] + r[1] * p.e2[1][k] + r[2] * p.e2[2][k], den);
        const float v = detail::flip_sign(r[0] * p.e1[0][k] + r[1] * p.e1[1][k] + r[2] * p.e1[2][k], den);
        const float t = detail::flip_sign(p.n[0][k] * c[0] + p.n[1][k] * c[1] + p.n[2][k] * c[2], den);
        if (den != 0.0f && u >= 0.0f && v >= 0.0f && u + v <= abs_den && abs_den * tmin <= t && t < abs_den * tmax) {
            const float inv_den = 1.0f / abs_den;
            out.t[k] = t * inv_den;
            out.u[k] = u * inv_den;
            out.v[k] = v * inv_den;
            out.mask |= 1u << k;
        }
    }
    return out;
}

#if defined(ACCELBENCH_WBVH_SSE)
// The vector form, 4 lanes in SSE; the same operations in the same order.
inline WbvhPacketHits wbvh_moeller_test(const WbvhMoellerPacket& p, int lanes, const __m128 (&o)[3],
                                        const __m128 (&d)[3], float tmin, float tmax) {
    WbvhPacketHits out;
    const auto ld = [](const float* x) { return _mm_load_ps(x); };
    const auto dot = [&](const __m128(&a)[3], const float(&b)[3][4]) {
        return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a[0], ld(b[0])), _mm_mul_ps(a[1], ld(b[1]))),
                          _mm_mul_ps(a[2], ld(b[2])));
    };
    const __m128 c[3] = {_mm_sub_ps(ld(p.v0[0]), o[0]), _mm_sub_ps(ld(p.v0[1]), o[1]), _mm_sub_ps(ld(p.v0[2]), o[2])};
    const __m128 r[3] = {_mm_sub_ps(_mm_mul_ps(d[1], c[2]), _mm_mul_ps(d[2], c[1])),
                         _mm_sub_ps(_mm_mul_ps(d[2], c[0]), _mm_mul_ps(d[0], c[2])),
                         _mm_sub_ps(_mm_mul_ps(d[0], c[1]), _mm_mul_ps(d[1], c[0]))};
    // n . d with n first, as the scalar form multiplies.
    const __m128 den = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ld(p.n[0]), d[0]), _mm_mul_ps(ld(p.n[1]), d[1])),
                                  _mm_mul_ps(ld(p.n[2]), d[2]));
    const __m128 sign = _mm_and_ps(den, _mm_set1_ps(-0.0f));
    const __m128 abs_den = _mm_andnot_ps(_mm_set1_ps(-0.0f), den);
    const __m128 u = _mm_xor_ps(dot(r, p.e2), sign);
    const __m128 v = _mm_xor_ps(dot(r, p.e1), sign);
    const __m128 t = _mm_xor_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(ld(p.n[0]), c[0]), _mm_mul_ps(ld(p.n[1]), c[1])),
                                           _mm_mul_ps(ld(p.n[2]), c[2])),
                                sign);
    const __m128 zero = _mm_setzero_ps();
    __m128 ok = _mm_and_ps(_mm_cmpneq_ps(den, zero), _mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmpge_ps(v, zero)));
    ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_add_ps(u, v), abs_den));
    ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_mul_ps(abs_den, _mm_set1_ps(tmin)), t));
    ok = _mm_and_ps(ok, _mm_cmplt_ps(t, _mm_mul_ps(abs_den, _mm_set1_ps(tmax))));
    out.mask = uint32_t(_mm_movemask_ps(ok)) & ((1u << lanes) - 1);
    if (out.mask == 0) return out;
    // Lanes that do not hit divide 1 by 1.
    const __m128 one = _mm_set1_ps(1.0f);
    const __m128 inv_den = _mm_div_ps(one, _mm_or_ps(_mm_and_ps(ok, abs_den), _mm_andnot_ps(ok, one)));
    _mm_storeu_ps(out.t, _mm_mul_ps(t, inv_den));
    _mm_storeu_ps(out.u, _mm_mul_ps(u, inv_den));
    _mm_storeu_ps(out.v, _mm_mul_ps(v, inv_den));
    return out;
}
#endif

}  // namespace accelbench
