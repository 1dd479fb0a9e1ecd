// The ray sets (ray_sets.h): made deterministically from a seed and the
// reference's answers, the same on every run, different for another seed; answered by
// every structure as the reference answers them; secondary rays that never find the
// surface they leave, even on the closed meshes translated to 1e7; and the same hits
// and counts on one thread and on two.
#include "accelbench/render/ray_sets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/base/random.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"
#include "agreement.h"
#include "test_scenes.h"

using namespace accelbench;

namespace {

constexpr RaySetKind kAll[] = {RaySetKind::Primary, RaySetKind::Shadow, RaySetKind::Ao, RaySetKind::Diffuse,
                               RaySetKind::Random};

// Every structure as the robustness test judges it: Embree with and without its robust
// flag, brute force forced on small scenes and left out on the bunny (69k triangles per
// ray would make it the slowest test of the project; the soup tests it).
struct Structure {
    std::string name;
    std::map<std::string, std::string> params;
    std::string label;
};

std::vector<Structure> structures(const Scene& scene) {
    std::vector<Structure> out;
    for (const auto& info : accelerator_registry()) {
        if (info.name == "embree") {
            out.push_back({"embree", {{"robust", "false"}}, "embree"});
            out.push_back({"embree", {{"robust", "true"}}, "embree_robust"});
        } else if (info.name == "brute_force") {
            if (scene.triangle_count() <= 5000) out.push_back({"brute_force", {{"force", "true"}}, "brute_force"});
        } else {
            out.push_back({info.name, {}, info.name});
        }
    }
    return out;
}

std::unique_ptr<Accelerator> built(const std::string& name, const std::map<std::string, std::string>& params,
                                   const Scene& scene) {
    auto a = make_accelerator(name, params);
    a->build(scene);
    return a;
}

// A scene with its view, its reference structure and its camera rays.
struct Model {
    Scene scene;
    Camera camera;
    Vec3 light;
    std::vector<Ray> primary;
    std::unique_ptr<Accelerator> reference;

    std::vector<GeneratedRaySet> sets(const RaySetParams& params) const {
        return make_ray_sets(*reference, scene, primary, light, kAll, params);
    }
};

Model model(Scene scene, int width, int height) {
    Model m;
    m.scene = std::move(scene);
    m.camera = Camera::fit(m.scene.bounds, float(width) / float(height));
    m.light = default_light(m.scene.bounds, m.camera).position;
    RenderSettings rs;
    rs.width = width;
    rs.height = height;
    m.primary = camera_rays(m.camera, rs);
    m.reference = built("reference", {}, m.scene);
    return m;
}

const Model& bunny() {
    static const Model m = model(test::stanford_bunny(), 64, 48);
    return m;
}

RaySetParams small_params(uint64_t seed = 1) {
    RaySetParams p;
    p.ao_samples = 2;
    p.diffuse_bounces = 2;
    p.random_rays = 3000;
    p.seed = seed;
    return p;
}

bool same_rays(const std::vector<Ray>& a, const std::vector<Ray>& b) {
    return a.size() == b.size() && hash_ray_set(a, RayQuery::Closest) == hash_ray_set(b, RayQuery::Closest);
}

TEST(RaySets, NamesRoundTripAndQueries) {
    ASSERT_EQ(ray_set_names().size(), std::size(kAll));
    for (RaySetKind k : kAll) EXPECT_EQ(parse_ray_set(ray_set_name(k)), k);
    EXPECT_FALSE(parse_ray_set("camera"));
    EXPECT_EQ(ray_set_query(RaySetKind::Shadow), RayQuery::Any);
    EXPECT_EQ(ray_set_query(RaySetKind::Ao), RayQuery::Any);
    EXPECT_EQ(ray_set_query(RaySetKind::Diffuse), RayQuery::Closest);
    EXPECT_EQ(ray_set_query(RaySetKind::Random), RayQuery::Closest);
}

TEST(RaySets, IdenticalAcrossRunsAndTheSeedChangesThem) {
    const auto a = bunny().sets(small_params(1));
    const auto b = bunny().sets(small_params(1));
    const auto c = bunny().sets(small_params(2));
    ASSERT_EQ(a.size(), std::size(kAll));
    for (size_t i = 0; i < a.size(); ++i) {
        const std::string name(ray_set_name(a[i].kind));
        std::printf("[ray-set] %-8s %7zu rays  hash %016llx (seed 1)  %016llx (seed 2)\n", name.c_str(),
                    a[i].rays.size(), (unsigned long long)a[i].hash, (unsigned long long)c[i].hash);
        EXPECT_EQ(a[i].kind, kAll[i]);
        EXPECT_FALSE(a[i].rays.empty()) << name;
        EXPECT_EQ(a[i].hash, hash_ray_set(a[i].rays, a[i].query)) << name;
        EXPECT_EQ(a[i].hash, b[i].hash) << name;
        EXPECT_TRUE(same_rays(a[i].rays, b[i].rays)) << name;
        const size_t answers =
            a[i].query == RayQuery::Closest ? a[i].reference_hits.size() : a[i].reference_occluded.size();
        EXPECT_EQ(answers, a[i].rays.size()) << name;
        const bool seeded =
            a[i].kind == RaySetKind::Ao || a[i].kind == RaySetKind::Diffuse || a[i].kind == RaySetKind::Random;
        if (seeded) EXPECT_NE(a[i].hash, c[i].hash) << name << " must change with the seed";
        else EXPECT_EQ(a[i].hash, c[i].hash) << name << " does not depend on the seed";
    }
    // The hash sees the query, not only the rays.
    EXPECT_NE(hash_ray_set(a[0].rays, RayQuery::Closest), hash_ray_set(a[0].rays, RayQuery::Any));
}

TEST(RaySets, SizesFollowFromThePrimaryHits) {
    const RaySetParams p = small_params();
    const auto sets = bunny().sets(p);
    const auto& primary = sets[0];
    const uint64_t hits = uint64_t(std::count_if(primary.reference_hits.begin(), primary.reference_hits.end(),
                                                 [](const Hit& h) { return h.found(); }));
    ASSERT_GT(hits, 100u);
    EXPECT_EQ(primary.rays.size(), size_t(64 * 48));
    EXPECT_EQ(sets[1].rays.size(), hits);                           // one shadow ray per hit
    EXPECT_EQ(sets[2].rays.size(), hits * uint64_t(p.ao_samples));  // every bunny triangle hit has a normal
    const GeneratedRaySet& diffuse = sets[3];
    ASSERT_EQ(diffuse.bounce_begin.size(), size_t(p.diffuse_bounces));
    EXPECT_EQ(diffuse.bounce_begin[0], 0u);
    EXPECT_EQ(diffuse.bounce_begin[1], hits);  // bounce 1 leaves every primary hit
    // Bounce 2 starts where bounce 1's reference answers hit, and nowhere else.
    const uint64_t bounce1_hits =
        uint64_t(std::count_if(diffuse.reference_hits.begin(), diffuse.reference_hits.begin() + ptrdiff_t(hits),
                               [](const Hit& h) { return h.found(); }));
    EXPECT_EQ(diffuse.rays.size() - diffuse.bounce_begin[1], bounce1_hits);
    EXPECT_EQ(sets[4].rays.size(), p.random_rays);
    const float tmax = p.ao_distance * length(bunny().scene.bounds.diagonal());
    for (const Ray& r : sets[2].rays) ASSERT_EQ(r.tmax, tmax);
    const Bounds3& b = bunny().scene.bounds;
    for (const Ray& r : sets[4].rays) {
        ASSERT_TRUE(r.org.x >= b.lower.x && r.org.x <= b.upper.x && r.org.y >= b.lower.y && r.org.y <= b.upper.y &&
                    r.org.z >= b.lower.z && r.org.z <= b.upper.z);
        ASSERT_NEAR(length(r.dir), 1.0f, 1e-5f);
    }
}

TEST(RaySets, OutOfRangeParametersAreRefused) {
    for (auto change : {+[](RaySetParams& p) { p.ao_samples = 0; }, +[](RaySetParams& p) { p.ao_distance = 0; },
                        +[](RaySetParams& p) { p.diffuse_bounces = 0; }, +[](RaySetParams& p) { p.random_rays = 0; }}) {
        RaySetParams p = small_params();
        change(p);
        EXPECT_THROW(bunny().sets(p), std::invalid_argument);
    }
}

// Cosine-weighted: every direction in the hemisphere, unit length, and E[cos theta] =
// integral of cos^2 / pi over the hemisphere = 2/3 (a uniform hemisphere would give 1/2).
TEST(RaySets, CosineHemisphereHasTheCosineDensity) {
    SplitMix64 rng(7);
    for (Vec3 n :
         {Vec3{0, 0, 1}, Vec3{0, 0, -1}, normalize(Vec3{1, -2, 0.5f}), Vec3{1, 0, 0}, normalize(Vec3{0, -1, -1e-7f})}) {
        double sum = 0;
        const int count = 40000;
        for (int i = 0; i < count; ++i) {
            const float u1 = rng.uniform(), u2 = rng.uniform();
            const Vec3 d = cosine_hemisphere(n, u1, u2);
            ASSERT_NEAR(length(d), 1.0f, 1e-5f);
            ASSERT_GE(dot(d, n), -1e-6f);
            sum += dot(d, n);
        }
        EXPECT_NEAR(sum / count, 2.0 / 3.0, 0.01) << n.x << " " << n.y << " " << n.z;
    }
}

TEST(RaySets, OffsetMovesByUlpsAwayFromZeroAndByAFixedStepNearIt) {
    // At 1e7 (float spacing 1) the offset along +x is 256 ulps = 256 units; along -x too.
    EXPECT_EQ(offset_ray_origin({1e7f, 0, 0}, {1, 0, 0}, 1.0f).x, 1e7f + 256.0f);
    EXPECT_EQ(offset_ray_origin({1e7f, 0, 0}, {-1, 0, 0}, 1.0f).x, 1e7f - 256.0f);
    EXPECT_EQ(offset_ray_origin({-1e7f, 0, 0}, {-1, 0, 0}, 1.0f).x, -1e7f - 256.0f);
    // At 1.0 it is 256 ulps of 1.0 (2^-23 each).
    EXPECT_EQ(offset_ray_origin({1.0f, 0, 0}, {1, 0, 0}, 1.0f).x, 1.0f + 256.0f * 0x1p-23f);
    // Near zero (below size / 32): a fixed size / 65536 along the normal.
    const Vec3 q = offset_ray_origin({0, 0, 0}, {0, 0, 1}, 2.0f);
    EXPECT_EQ(q.z, 2.0f / 65536.0f);
    EXPECT_EQ(q.x, 0.0f);
}

// The agreement test of every structure, on every set: a real model (the bunny) and a
// procedural one with many overlaps.
TEST(RaySets, EveryStructureAgreesWithTheReferenceOnEverySet) {
    const Model soup = model(generate_procedural("soup", {{"triangles", "3000"}, {"size", "0.1"}}).scene, 48, 36);
    for (const Model* m : {&bunny(), &soup}) {
        const auto sets = m->sets(small_params());
        for (const Structure& s : structures(m->scene)) {
            auto accel = built(s.name, s.params, m->scene);
            for (const GeneratedRaySet& set : sets) {
                // Shadow and ao rays graze the surfaces they leave; Embree's non-watertight
                // default test may answer a few of them differently from the exact reference.
                const uint64_t allowed = s.label == "embree" ? set.rays.size() / 1000 : 0;
                test::expect_agrees_on_ray_set(set, *accel, m->scene.name + " " + s.label, allowed);
            }
        }
    }
}

// Per ray: the hits (prim, t, u, v) or occlusion answers, and the counters.
void expect_identical(const TraceOutput& a, const TraceOutput& b, const std::string& what) {
    EXPECT_EQ(a.rays, b.rays) << what;
    EXPECT_EQ(a.hits, b.hits) << what;
    EXPECT_EQ(a.primary_stats.node_visits, b.primary_stats.node_visits) << what;
    EXPECT_EQ(a.primary_stats.box_tests, b.primary_stats.box_tests) << what;
    EXPECT_EQ(a.primary_stats.prim_tests, b.primary_stats.prim_tests) << what;
    EXPECT_EQ(a.occluded, b.occluded) << what;
    ASSERT_EQ(a.primary_hits.size(), b.primary_hits.size()) << what;
    for (size_t i = 0; i < a.primary_hits.size(); ++i) {
        const Hit &x = a.primary_hits[i], &y = b.primary_hits[i];
        ASSERT_TRUE(x.prim == y.prim && x.t == y.t && x.u == y.u && x.v == y.v) << what << " ray " << i;
    }
    ASSERT_EQ(a.per_pixel.size(), b.per_pixel.size()) << what;
    for (size_t i = 0; i < a.per_pixel.size(); ++i)
        ASSERT_EQ(a.per_pixel[i].prim_tests, b.per_pixel[i].prim_tests) << what << " ray " << i;
}

TEST(RaySets, OneAndTwoThreadsGiveIdenticalHitsAndCounts) {
    const auto sets = bunny().sets(small_params());
    for (const Structure& s : structures(bunny().scene)) {
        auto accel = built(s.name, s.params, bunny().scene);
        TraceRequest one;
        one.keep_hits = true;
        one.counts = CountMode::PerPixel;
        TraceRequest two = one;
        two.settings.threads = 2;
        for (const GeneratedRaySet& set : sets)
            expect_identical(trace_ray_set(*accel, set.rays, set.query, one),
                             trace_ray_set(*accel, set.rays, set.query, two),
                             s.label + " " + std::string(ray_set_name(set.kind)));
        // The camera run of today's rows (primary + shadow rays) as well.
        one.settings.width = two.settings.width = 64;
        one.settings.height = two.settings.height = 48;
        one.settings.shading = two.settings.shading = false;
        const TraceOutput a = render(*accel, bunny().scene, bunny().camera, one);
        const TraceOutput b = render(*accel, bunny().scene, bunny().camera, two);
        expect_identical(a, b, s.label + " render");
        EXPECT_EQ(a.shadow_rays, b.shadow_rays);
        EXPECT_EQ(a.shadow_hits, b.shadow_hits);
        EXPECT_EQ(a.shadow_stats.prim_tests, b.shadow_stats.prim_tests);
        EXPECT_EQ(a.shadow_stats.node_visits, b.shadow_stats.node_visits);
    }
}

// Connected components of a mesh by shared vertex indices (the robustness cases share
// vertices by position, so each closed mesh is one component).
std::vector<uint32_t> components(const Scene& s) {
    std::vector<uint32_t> parent(s.vertex_count());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (const auto& t : s.triangles) {
        parent[find(t[1])] = find(t[0]);
        parent[find(t[2])] = find(t[0]);
    }
    std::vector<uint32_t> comp(s.triangle_count());
    for (size_t i = 0; i < comp.size(); ++i) comp[i] = find(s.triangles[i][0]);
    return comp;
}

// Whether every vertex of component c lies on or behind the plane of every non-degenerate
// triangle of c (oriented away from the component's vertex centroid), in double: the
// unit sphere at 1e7 collapses onto the float lattice and is no longer convex.
bool convex(const Scene& s, const std::vector<uint32_t>& comp, uint32_t c) {
    std::vector<uint32_t> verts;
    for (size_t i = 0; i < comp.size(); ++i)
        if (comp[i] == c) verts.insert(verts.end(), s.triangles[i].begin(), s.triangles[i].end());
    double centre[3] = {0, 0, 0};
    for (uint32_t v : verts)
        for (int a = 0; a < 3; ++a) centre[a] += double(s.vertices[v][a]) / double(verts.size());
    for (size_t i = 0; i < comp.size(); ++i) {
        if (comp[i] != c) continue;
        double p[3][3];
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) p[k][a] = double(s.vertex(uint32_t(i), k)[a]);
        const double e1[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
        const double e2[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len == 0) continue;
        auto side = [&](const double* q) {
            return ((q[0] - p[0][0]) * n[0] + (q[1] - p[0][1]) * n[1] + (q[2] - p[0][2]) * n[2]) / len;
        };
        const double flip = side(centre) > 0 ? -1.0 : 1.0;
        for (uint32_t v : verts) {
            const double q[3] = {double(s.vertices[v].x), double(s.vertices[v].y), double(s.vertices[v].z)};
            if (flip * side(q) > 1e-9 * (1.0 + std::fabs(p[0][0]) + std::fabs(p[0][1]) + std::fabs(p[0][2])))
                return false;
        }
    }
    return true;
}

// Secondary rays leave the closed meshes of robustness cases 1-3a (a unit icosphere and
// a 4-unit box; at the origin, translated to 1.5e5, 1e6, 1e7, scaled to 1e-6) from hit
// points of rays coming from inside (the case's own rays, aimed at vertices and edge
// points; about a thousand of them) and from outside (the same rays mirrored through their target), in 8
// cosine-weighted directions each, as the ao and diffuse sets make them. Then:
// - no ray finds the triangle it leaves (a planar triangle cannot be met again by a ray
//   leaving it toward its normal: any such hit is a self-intersection at t ~ 0);
// - no ray leaving a convex mesh outward finds that mesh at all (the whole mesh lies
//   behind the plane of each of its faces).
// For every structure (the reference is one of the registry's).
TEST(RaySets, SecondaryRaysNeverFindTheSurfaceTheyLeave) {
    for (const std::string id : {"1", "2a", "2b", "2c", "3a"}) {
        const RobustnessCase c = make_robustness_case(id);
        const Scene& scene = c.scene;
        const float size = length(scene.bounds.diagonal());
        const std::vector<uint32_t> comp = components(scene);
        // The starting rays: inside (the case's) and outside (mirrored), with the
        // reference's hits.
        // About a thousand of the case's rays (every one of 2c's), spread over all targets.
        std::vector<Ray> incoming;
        const size_t stride = std::max<size_t>(1, c.rays.size() / 1000);
        for (size_t i = 0; i < c.rays.size(); i += stride) {
            const Ray& r = c.rays[i];
            incoming.push_back(r);
            const Vec3 target = r.org + r.dir;
            incoming.push_back({target + r.dir, 0.0f, -r.dir, kInfinity});
        }
        auto reference = built("reference", {}, scene);
        std::vector<Hit> first(incoming.size());
        reference->closest_hits(incoming, first);
        struct Leaving {
            uint32_t prim;
            bool outward_from_convex;
        };
        std::vector<Ray> rays;
        std::vector<Leaving> from;
        size_t outward_starts = 0;
        // convex() per component once: it is quadratic in the component's size, and asked
        // for every outside ray (the sanitized build spent minutes on it).
        std::map<uint32_t, bool> convex_component;
        auto is_convex = [&](uint32_t component) {
            auto [it, inserted] = convex_component.try_emplace(component, false);
            if (inserted) it->second = convex(scene, comp, component);
            return it->second;
        };
        for (size_t i = 0; i < incoming.size(); ++i) {
            if (!first[i].found()) continue;
            const auto n = facing_normal(scene, first[i], incoming[i].dir);
            if (!n) continue;
            const bool outward = i % 2 == 1 && is_convex(comp[first[i].prim]);
            outward_starts += outward;
            const Vec3 org = offset_ray_origin(hit_point(scene, first[i]), *n, size);
            SplitMix64 rng(mix_seed(uint64_t(i), 14));
            for (int k = 0; k < 8; ++k) {
                const float u1 = rng.uniform(), u2 = rng.uniform();
                rays.push_back({org, 0.0f, cosine_hemisphere(*n, u1, u2), kInfinity});
                from.push_back({first[i].prim, outward});
            }
        }
        ASSERT_GT(rays.size(), 1000u) << "case " << id;
        ASSERT_GT(outward_starts, 10u) << "case " << id;
        for (const Structure& s : structures(scene)) {
            auto accel = built(s.name, s.params, scene);
            std::vector<Hit> hits(rays.size());
            accel->closest_hits(rays, hits);
            std::vector<uint8_t> occluded(rays.size());
            accel->any_hits(rays, occluded);
            uint64_t self_hits = 0, same_mesh = 0, outward_occluded = 0;
            for (size_t j = 0; j < rays.size(); ++j) {
                if (hits[j].found() && hits[j].prim == from[j].prim) ++self_hits;
                if (from[j].outward_from_convex && hits[j].found() && comp[hits[j].prim] == comp[from[j].prim])
                    ++same_mesh;
                // Outward from a convex mesh the other mesh may lie ahead, so occlusion
                // alone proves nothing; closest hits say which mesh was found.
                if (from[j].outward_from_convex && occluded[j] && !hits[j].found()) ++outward_occluded;
            }
            std::printf(
                "[self-intersection] case %-3s %-14s %zu rays: %llu self hits, %llu outward rays finding their "
                "own mesh\n",
                id.c_str(), s.label.c_str(), rays.size(), (unsigned long long)self_hits, (unsigned long long)same_mesh);
            EXPECT_EQ(self_hits, 0u) << "case " << id << " " << s.label;
            EXPECT_EQ(same_mesh, 0u) << "case " << id << " " << s.label;
            EXPECT_EQ(outward_occluded, 0u) << "case " << id << " " << s.label << ": any-hit and closest-hit disagree";
        }
    }
}

}  // namespace
