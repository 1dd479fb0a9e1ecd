// The reference is the ground truth, so it is checked against something it does not
// share code with: exact rational arithmetic (GMP's mpq_class) for the triangle test, and
// Embree (robust) for whole scenes.
#include "accelbench/accel/baseline/reference.h"

#include "accelbench/base/random.h"
#include "accelbench/scene/procedural.h"

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "agreement.h"

using namespace accelbench;

namespace {

// The exact answer for a ray and a triangle given as floats: the edge functions
// d . (q_j x q_l) with q = p - o, the hit rule of reference.h (all >= 0 or all <= 0, not
// all zero, tmin <= t < tmax), and t = sum(e_i q_i[k]) / (det d[k]).
struct ExactAnswer {
    bool hit = false;
    mpq_class t;
    int zero_edges = 0;  // edge functions exactly zero: the ray passes through an edge or vertex
};

ExactAnswer exact_intersect(const Ray& r, Vec3 p0, Vec3 p1, Vec3 p2) {
    const Vec3 p[3] = {p0, p1, p2};
    mpq_class q[3][3], d[3];
    for (int a = 0; a < 3; ++a) d[a] = double(r.dir[a]);
    for (int i = 0; i < 3; ++i)
        for (int a = 0; a < 3; ++a) q[i][a] = mpq_class(double(p[i][a])) - mpq_class(double(r.org[a]));
    mpq_class e[3];
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, l = (i + 2) % 3;
        e[i] = 0;
        for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            e[i] += d[a] * (q[j][b] * q[l][c] - q[j][c] * q[l][b]);
        }
    }
    ExactAnswer ans;
    for (const auto& x : e) ans.zero_edges += sgn(x) == 0;
    const bool any_neg = sgn(e[0]) < 0 || sgn(e[1]) < 0 || sgn(e[2]) < 0;
    const bool any_pos = sgn(e[0]) > 0 || sgn(e[1]) > 0 || sgn(e[2]) > 0;
    const mpq_class det = e[0] + e[1] + e[2];
    if ((any_neg && any_pos) || sgn(det) == 0) return ans;
    const int k = max_axis(Vec3{std::fabs(r.dir.x), std::fabs(r.dir.y), std::fabs(r.dir.z)});
    ans.t = (e[0] * q[0][k] + e[1] * q[1][k] + e[2] * q[2][k]) / (det * d[k]);
    ans.hit = ans.t >= mpq_class(double(r.tmin)) && (std::isinf(r.tmax) || ans.t < mpq_class(double(r.tmax)));
    return ans;
}

// Draws for the random pairs, on SplitMix64 (random.h) like every generator of ours.
class Draws {
public:
    explicit Draws(uint64_t seed) : rng_(seed) {}
    float uniform(float lo, float hi) { return rng_.uniform(lo, hi); }
    int integer(int lo, int hi) { return lo + int(rng_.below(uint32_t(hi - lo + 1))); }
    Vec3 point(float lo, float hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
    Vec3 lattice(int lo, int hi) { return {float(integer(lo, hi)), float(integer(lo, hi)), float(integer(lo, hi))}; }

private:
    SplitMix64 rng_;
};

struct Tally {
    int pairs = 0, hits = 0, through_edges = 0;
};

// Compares the reference's triangle test with the exact answer: the same hit decision
// always, t within a few double ulps, and the float t the nearest float (within 1 ulp).
void check_pair(const Ray& r, Vec3 a, Vec3 b, Vec3 c, Tally& tally) {
    const ExactAnswer exact = exact_intersect(r, a, b, c);
    ReferenceHit h;
    const bool got = reference_intersect_triangle(r, a, b, c, h);
    ++tally.pairs;
    tally.hits += exact.hit;
    tally.through_edges += exact.zero_edges > 0;
    ASSERT_EQ(got, exact.hit) << "ray org (" << r.org.x << "," << r.org.y << "," << r.org.z << ") dir (" << r.dir.x
                              << "," << r.dir.y << "," << r.dir.z << "), " << exact.zero_edges
                              << " zero edge functions";
    if (!got) return;
    const double t_exact = exact.t.get_d();
    EXPECT_LE(std::fabs(h.t - t_exact), 1e-12 * std::fabs(t_exact)) << "t " << h.t << " exact " << t_exact;
    EXPECT_LE(ulp_distance(float(h.t), float(t_exact)), 1);
}

}  // namespace

// Integer triangles and rays through exactly representable points of their edges and
// through their vertices: the edge functions are exactly zero, the case a float test gets
// wrong and the exact fallback decides.
TEST(ReferenceExact, RaysThroughEdgesAndVerticesOfLatticeTriangles) {
    Draws draw(1);
    Tally tally;
    for (int i = 0; i < 300; ++i) {
        const Vec3 a = draw.lattice(-8, 8), b = draw.lattice(-8, 8), c = draw.lattice(-8, 8);
        const Vec3 o = draw.lattice(-16, 16) * 0.5f;
        const Vec3 corners[3] = {a, b, c};
        const int k = draw.integer(0, 2);
        const Vec3 from = corners[k], to = corners[(k + 1) % 3];
        const float f = float(draw.integer(0, 8)) / 8.0f;  // 0 and 1: the vertices
        const Vec3 target = from + (to - from) * f;        // exact: small dyadic numbers
        if (target == o) continue;
        check_pair({o, 0.0f, target - o, kInfinity}, a, b, c, tally);
    }
    std::printf("[exact] lattice: %d pairs, %d hits, %d through an edge or vertex\n", tally.pairs, tally.hits,
                tally.through_edges);
    EXPECT_GT(tally.through_edges, 200);  // the exact path was exercised
}

// Float triangles, rays aimed at points within a few ulps of an edge or at a vertex: the
// rounded direction passes just inside or just outside, and only exact arithmetic knows.
TEST(ReferenceExact, RaysNearEdgesAndVerticesOfFloatTriangles) {
    Draws draw(2);
    Tally tally;
    for (int i = 0; i < 400; ++i) {
        const Vec3 a = draw.point(-1, 1), b = draw.point(-1, 1), c = draw.point(-1, 1);
        const Vec3 corners[3] = {a, b, c};
        const int k = draw.integer(0, 2);
        const Vec3 from = corners[k], to = corners[(k + 1) % 3];
        Vec3 target = i % 4 == 0 ? from : from + (to - from) * draw.uniform(0, 1);
        const float nudge = draw.uniform(-4e-7f, 4e-7f);
        target = target + Vec3{nudge, -nudge, 0.5f * nudge};
        const Vec3 o = draw.point(-3, 3) + Vec3{0, 0, 4};
        check_pair({o, 0.0f, target - o, kInfinity}, a, b, c, tally);
    }
    std::printf("[exact] float: %d pairs, %d hits\n", tally.pairs, tally.hits);
    EXPECT_GT(tally.hits, 50);
    EXPECT_LT(tally.hits, 350);  // near edges: both answers occur
}

// Far origins and large offsets: q = p - o spans many binades, where double rounding of
// the edge functions is largest relative to their value.
TEST(ReferenceExact, FarOriginsAndOffsets) {
    Draws draw(3);
    Tally tally;
    for (int i = 0; i < 200; ++i) {
        const float offset = i % 2 ? 1e6f : 3e4f;
        const Vec3 shift{offset, -offset, offset};
        const Vec3 a = draw.point(-1, 1) + shift, b = draw.point(-1, 1) + shift, c = draw.point(-1, 1) + shift;
        const Vec3 target = a + (b - a) * draw.uniform(0, 1);
        const Vec3 o = shift + draw.point(-1e3f, 1e3f);
        check_pair({o, 0.0f, target - o, kInfinity}, a, b, c, tally);
    }
    std::printf("[exact] far: %d pairs, %d hits\n", tally.pairs, tally.hits);
    EXPECT_GT(tally.hits, 20);
}

// Two triangles sharing an edge, rays exactly through it: at least one is hit (the exact
// sign of the shared edge function is the same, negated, in both).
TEST(ReferenceExact, SharedEdgesNeverLeak) {
    Draws draw(4);
    int leaks = 0, rays = 0;
    for (int i = 0; i < 300; ++i) {
        const Vec3 a = draw.point(-1, 1), b = draw.point(-1, 1);
        const Vec3 c = draw.point(-1, 1), d = draw.point(-1, 1);
        const Vec3 o = draw.point(-3, 3) + Vec3{0, 0, 5};
        const Vec3 target = a + (b - a) * draw.uniform(0.01f, 0.99f);
        const Ray r{o, 0.0f, target - o, kInfinity};
        // Only where the edge really separates the two triangles as seen from o.
        const ExactAnswer x = exact_intersect(r, a, b, c), y = exact_intersect(r, b, a, d);
        ReferenceHit h1, h2;
        const bool g1 = reference_intersect_triangle(r, a, b, c, h1), g2 = reference_intersect_triangle(r, b, a, d, h2);
        EXPECT_EQ(g1, x.hit);
        EXPECT_EQ(g2, y.hit);
        const bool opposite_sides = [&] {
            // c and d on opposite sides of the plane through o, a, b.
            auto side = [&](Vec3 p) {
                mpq_class u[3], v[3], w[3];
                for (int k = 0; k < 3; ++k) {
                    u[k] = mpq_class(double(a[k])) - double(o[k]);
                    v[k] = mpq_class(double(b[k])) - double(o[k]);
                    w[k] = mpq_class(double(p[k])) - double(o[k]);
                }
                mpq_class det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                    u[2] * (v[0] * w[1] - v[1] * w[0]);
                return sgn(det);
            };
            return side(c) * side(d) < 0;
        }();
        // The rounded direction may pass beside the edge; the ray still crosses the
        // union of the two triangles when it crosses the line of the edge between them.
        if (!opposite_sides || (!x.hit && !y.hit)) continue;
        ++rays;
        leaks += !g1 && !g2;
    }
    std::printf("[exact] shared edges: %d rays, %d leaks\n", rays, leaks);
    EXPECT_GT(rays, 30);
    EXPECT_EQ(leaks, 0);
}

TEST(Reference, InvalidRaysAndDegenerateTrianglesMiss) {
    const Vec3 a{0, 0, 1}, b{1, 0, 1}, c{0, 1, 1};
    ReferenceHit h;
    EXPECT_FALSE(reference_intersect_triangle({{0.2f, 0.2f, 0}, 0, {0, 0, 0}, kInfinity}, a, b, c, h));
    EXPECT_FALSE(reference_intersect_triangle({{0.2f, 0.2f, 0}, NAN, {0, 0, 1}, kInfinity}, a, b, c, h));
    EXPECT_FALSE(reference_intersect_triangle({{NAN, 0.2f, 0}, 0, {0, 0, 1}, kInfinity}, a, b, c, h));
    EXPECT_FALSE(reference_intersect_triangle({{0.2f, 0.2f, 0}, 0, {0, 0, 1}, kInfinity}, a, b, {2, 0, 1}, h));
    EXPECT_TRUE(reference_intersect_triangle({{0.2f, 0.2f, 0}, 0, {0, 0, 1}, kInfinity}, a, b, c, h));
    EXPECT_EQ(h.t, 1.0);
    EXPECT_DOUBLE_EQ(h.u, double(0.2f));  // the ray's origin is the float nearest 0.2
    EXPECT_DOUBLE_EQ(h.v, double(0.2f));
    // The interval is [tmin, tmax).
    EXPECT_TRUE(reference_intersect_triangle({{0.2f, 0.2f, 0}, 1.0f, {0, 0, 1}, kInfinity}, a, b, c, h));
    EXPECT_FALSE(reference_intersect_triangle({{0.2f, 0.2f, 0}, 0, {0, 0, 1}, 1.0f}, a, b, c, h));
}

// The closest hit does not depend on the tree: smallest t, then smallest id.
TEST(Reference, TiesGoToTheSmallestIdWhateverTheTree) {
    Scene s;
    s.name = "ties";
    for (int i = 0; i < 40; ++i) {  // 40 copies of one triangle, then one nearer at the end
        const uint32_t v = uint32_t(s.vertices.size());
        s.vertices.insert(s.vertices.end(), {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}});
        s.triangles.push_back({v, v + 1, v + 2});
    }
    s.vertices.insert(s.vertices.end(), {{0, 0, 0.5f}, {1, 0, 0.5f}, {0, 1, 0.5f}});
    s.triangles.push_back({120, 121, 122});
    s.finalize();
    const std::vector<Ray> rays = {{{0.2f, 0.2f, 2}, 0, {0, 0, -1}, kInfinity},   // nearest: copy at z = 1
                                   {{0.2f, 0.2f, -1}, 0, {0, 0, 1}, kInfinity}};  // nearest: the one at 0.5
    for (const char* leaf : {"1", "3", "64"}) {
        auto ref = make_accelerator("reference", {{"leaf_size", leaf}});
        ref->build(s);
        std::vector<Hit> hits(rays.size());
        ref->closest_hits(rays, hits);
        EXPECT_EQ(hits[0].prim, 0u) << "leaf_size " << leaf;
        EXPECT_EQ(hits[0].t, 1.0f);
        EXPECT_EQ(hits[1].prim, 40u) << "leaf_size " << leaf;
        std::vector<uint8_t> occluded(rays.size());
        ref->any_hits(rays, occluded);
        EXPECT_EQ(occluded[0], 1);
        EXPECT_EQ(occluded[1], 1);
    }
}

TEST(Reference, AgreesWithEmbreeRobustOnSoups) {
    for (auto [n, seed] : {std::pair{1000, 42}, std::pair{20000, 7}}) {
        const Scene scene = make_procedural("soup", {{"triangles", std::to_string(n)}, {"seed", std::to_string(seed)}});
        auto ref = make_accelerator("reference", {});
        ref->build(scene);
        test::expect_agrees_with_embree(scene, *ref, test::probe_rays(scene, 4000, uint64_t(seed)),
                                        "reference soup " + std::to_string(n));
    }
}

TEST(Reference, DepthIsLogarithmicAndStatsAreConsistent) {
    const Scene scene = make_procedural("soup", {{"triangles", "10000"}, {"seed", "5"}});
    auto ref = make_accelerator("reference", {{"leaf_size", "4"}});
    ref->build(scene);
    const BuildStats s = ref->build_stats();
    ASSERT_TRUE(s.max_depth && s.nodes && s.leaves && s.memory_bytes);
    EXPECT_LE(*s.max_depth, 12u);  // ceil(log2(10000 / 4)) = 12
    EXPECT_EQ(*s.nodes, 2 * *s.leaves - 1);
    EXPECT_NEAR(*s.avg_leaf_size * double(*s.leaves), 10000.0, 1e-6);
    Scene empty;
    empty.finalize();
    ref->build(empty);
    std::vector<Hit> hit(1);
    ref->closest_hits(std::vector<Ray>{{{0, 0, 0}, 0, {0, 0, 1}, kInfinity}}, hit);
    EXPECT_FALSE(hit[0].found());
}
