#include "accelbench/scene/procedural.h"
#include "accelbench/base/unknown_name.h"

#include <algorithm>
#include <cmath>

#include "accelbench/base/random.h"

namespace accelbench {

namespace {

constexpr float kPi = 3.14159265358979f;

// ---- building blocks shared by every kind ----------------------------------------------

// Appends triangles, each with its own colour, to a ProceduralScene. Vertices are not
// shared between calls: scenes are triangle soups as far as the structures care.
class ColouredSoupBuilder {
public:
    explicit ColouredSoupBuilder(ProceduralScene& out) : scene_(out.scene), albedo_(out.albedo) {}

    size_t triangles() const { return scene_.triangles.size(); }

    void triangle(Vec3 a, Vec3 b, Vec3 c, Vec3 colour) {
        const uint32_t i = uint32_t(scene_.vertices.size());
        scene_.vertices.insert(scene_.vertices.end(), {a, b, c});
        scene_.triangles.push_back({i, i + 1, i + 2});
        albedo_.push_back(colour);
    }

    // A planar quad given by its corners in order around the edge: 2 triangles.
    void quad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, Vec3 colour) {
        const uint32_t i = uint32_t(scene_.vertices.size());
        scene_.vertices.insert(scene_.vertices.end(), {a, b, c, d});
        scene_.triangles.push_back({i, i + 1, i + 2});
        scene_.triangles.push_back({i, i + 2, i + 3});
        albedo_.insert(albedo_.end(), 2, colour);
    }

    // Axis-aligned box: 12 triangles, or 10 without the bottom face (things standing on
    // something, whose bottom nobody sees).
    static constexpr size_t kBoxTriangles = 12, kBoxNoBottomTriangles = 10;
    void box(const Bounds3& b, Vec3 colour, bool bottom = true) {
        const Vec3 l = b.lower, u = b.upper;
        quad({l.x, u.y, l.z}, {l.x, u.y, u.z}, {u.x, u.y, u.z}, {u.x, u.y, l.z}, colour);  // top
        quad({l.x, l.y, l.z}, {u.x, l.y, l.z}, {u.x, u.y, l.z}, {l.x, u.y, l.z}, colour);  // -z
        quad({l.x, l.y, u.z}, {l.x, u.y, u.z}, {u.x, u.y, u.z}, {u.x, l.y, u.z}, colour);  // +z
        quad({l.x, l.y, l.z}, {l.x, u.y, l.z}, {l.x, u.y, u.z}, {l.x, l.y, u.z}, colour);  // -x
        quad({u.x, l.y, l.z}, {u.x, l.y, u.z}, {u.x, u.y, u.z}, {u.x, u.y, l.z}, colour);  // +x
        if (bottom) quad({l.x, l.y, l.z}, {l.x, l.y, u.z}, {u.x, l.y, u.z}, {u.x, l.y, l.z}, colour);
    }

    // The side of a cone frustum from centre a (radius ra) to centre b (radius rb) with
    // `sides` facets and no caps: 2 * sides triangles. Trunks, branches, tanks.
    void tube(Vec3 a, Vec3 b, float ra, float rb, int sides, Vec3 colour) {
        const Vec3 axis = normalize(b - a);
        const Vec3 helper = std::fabs(axis.y) < 0.9f ? Vec3{0, 1, 0} : Vec3{1, 0, 0};
        const Vec3 u = normalize(cross(axis, helper)), v = cross(axis, u);
        for (int i = 0; i < sides; ++i) {
            const float a0 = 2 * kPi * float(i) / float(sides), a1 = 2 * kPi * float(i + 1) / float(sides);
            const Vec3 d0 = u * std::cos(a0) + v * std::sin(a0), d1 = u * std::cos(a1) + v * std::sin(a1);
            quad(a + d0 * ra, a + d1 * ra, b + d1 * rb, b + d0 * rb, colour);
        }
    }

    // A flat disc cap of `sides` triangles (the top of a tank).
    void disc(Vec3 centre, float r, int sides, Vec3 colour) {
        for (int i = 0; i < sides; ++i) {
            const float a0 = 2 * kPi * float(i) / float(sides), a1 = 2 * kPi * float(i + 1) / float(sides);
            triangle(centre, centre + Vec3{std::cos(a0), 0, std::sin(a0)} * r,
                     centre + Vec3{std::cos(a1), 0, std::sin(a1)} * r, colour);
        }
    }

    // A triangle in a random orientation around `centre`: a tip at distance `length` along
    // a random direction and two base corners at -length/2 along it, `width` to either side.
    // length = r, width = r*sqrt(3)/2 is equilateral with circumradius r (soup, broad
    // leaves); a narrow one is a needle.
    void random_triangle(SplitMix64& rng, Vec3 centre, float length, float width, Vec3 colour) {
        const Vec3 e1 = rng.unit_vector();
        Vec3 e2 = cross(e1, rng.unit_vector());
        // A second direction (almost) parallel to the first leaves no plane: take any
        // perpendicular instead.
        if (!(dot(e2, e2) > 1e-6f)) e2 = cross(e1, std::fabs(e1.x) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
        e2 = normalize(e2);
        triangle(centre + e1 * length, centre - e1 * (0.5f * length) + e2 * width,
                 centre - e1 * (0.5f * length) - e2 * width, colour);
    }

private:
    Scene& scene_;
    std::vector<Vec3>& albedo_;
};

// A colour varied per element (each leaf, each building) so that flat-shaded surfaces read
// as many objects: brightness scaled by up to +-amount, hue shifted a little.
Vec3 vary(SplitMix64& rng, Vec3 base, float amount) {
    const float k = rng.uniform(1.0f - amount, 1.0f + amount);
    const Vec3 tint{rng.uniform(1.0f - 0.3f * amount, 1.0f + 0.3f * amount), 1.0f,
                    rng.uniform(1.0f - 0.3f * amount, 1.0f + 0.3f * amount)};
    const Vec3 c = base * tint * k;
    return {std::clamp(c.x, 0.0f, 1.0f), std::clamp(c.y, 0.0f, 1.0f), std::clamp(c.z, 0.0f, 1.0f)};
}

// Splits `total` into integer shares proportional to `weights`, summing to exactly
// `total` (cumulative rounding: share i is round(total*W_i) - round(total*W_{i-1}) over
// the normalised running sums W).
std::vector<size_t> proportional_shares(size_t total, const std::vector<double>& weights) {
    double sum = 0;
    for (double w : weights) sum += w;
    std::vector<size_t> shares(weights.size(), 0);
    double running = 0;
    size_t given = 0;
    for (size_t i = 0; i < weights.size(); ++i) {
        running += weights[i];
        const size_t upto = i + 1 == weights.size() ? total : size_t(std::llround(double(total) * running / sum));
        shares[i] = upto - given;
        given = upto;
    }
    return shares;
}

// A camera at `distance` from `target`, seen from compass angle `azimuth_deg` (0: from +z)
// and `elevation_deg` above the horizon.
Camera orbit_camera(Vec3 target, float azimuth_deg, float elevation_deg, float distance) {
    const float az = azimuth_deg * kPi / 180.0f, el = elevation_deg * kPi / 180.0f;
    Camera c;
    c.look_at = target;
    c.eye = target + Vec3{std::sin(az) * std::cos(el), std::sin(el), std::cos(az) * std::cos(el)} * distance;
    c.up = {0, 1, 0};
    c.fov_deg = 45.0f;
    return c;
}

std::string scene_name(const std::string& kind, const ParamSet& p) { return kind + "(" + p.canonical() + ")"; }

void too_few_triangles(const std::string& kind, int64_t asked, size_t needed) {
    throw ParamError("procedural scene '" + kind + "': triangles=" + std::to_string(asked) +
                     " is too few for its fixed structure (needs at least " + std::to_string(needed) + ")");
}

std::vector<ParamSpec> size_and_seed(const char* default_triangles, const char* help) {
    return {
        {"triangles", ParamType::Int, default_triangles, {}, 1000, 5e7, help},
        {"seed", ParamType::Int, "1", {}, 0, 1e18, "generator seed: same seed, same scene"},
    };
}

// The forest's and the city's sizes: by triangles or, as the report counts its scenes
// (its #Primitives are vertex counts), by vertices.
std::vector<ParamSpec> scene_size(const char* default_triangles, const char* help) {
    std::vector<ParamSpec> specs = size_and_seed(default_triangles, help);
    specs.push_back({"vertices",
                     ParamType::Int,
                     "0",
                     {},
                     0,
                     1.5e8,
                     "size by vertices instead (0: by triangles): the largest scene with at most this many "
                     "vertices; not together with triangles"});
    return specs;
}

// ---- forest ----------------------------------------------------------------------------
//
// The Trees scene's character (report 5.3.1): most triangles are small leaves packed into
// clusters with empty space between them, around thin trunks, over a large ground plane,
// under a big empty sky. Broad-leaved trees carry several leaf clusters at the ends of
// their branches; conifers carry flattened whorls of needles. Trees stand in groves, so
// the clusters themselves cluster.

struct LeafCluster {
    Vec3 centre, radii;  // an ellipsoid; leaves fill its outer shell
    bool needles;
    Vec3 colour;
};

constexpr Vec3 kGround{0.30f, 0.36f, 0.15f}, kBark{0.28f, 0.19f, 0.11f};
constexpr Vec3 kBroadLeaf{0.20f, 0.42f, 0.10f}, kNeedle{0.07f, 0.24f, 0.09f};

// How big the forest is: about one tree per 10k triangles, so leaves stay small and dense
// at any size.
struct ForestLayout {
    int trees;
    float radius;       // metres
    float ground_half;  // half the ground's side: reaches far toward the horizon
};

ForestLayout forest_layout(int64_t target) {
    const int trees = std::clamp(int(std::lround(double(target) / 10000.0)), 2, 60);
    const float forest_radius = 6.0f * std::sqrt(float(trees)) + 10.0f;
    return {trees, forest_radius, 6.0f * forest_radius};
}

// Gently rolling ground: the sum of two waves with random phases.
struct Ground {
    float ph0 = 0, ph1 = 0, ph2 = 0;
    float height(float x, float z) const {
        return 0.8f * std::sin(0.07f * x + ph0) * std::cos(0.05f * z + ph1) + 0.4f * std::sin(0.13f * (x + z) + ph2);
    }
};

// The ground as a grid of about 0.8% of the triangles.
Ground build_ground(ColouredSoupBuilder& mesh, SplitMix64& rng, const ForestLayout& forest, int64_t target) {
    Ground ground;
    ground.ph0 = rng.uniform(0, 2 * kPi);
    ground.ph1 = rng.uniform(0, 2 * kPi);
    ground.ph2 = rng.uniform(0, 2 * kPi);
    const float ground_half = forest.ground_half;
    const int grid = std::clamp(int(std::sqrt(double(target) * 0.004)), 2, 48);
    const float cell = 2 * ground_half / float(grid);
    for (int i = 0; i < grid; ++i)
        for (int j = 0; j < grid; ++j) {
            const float x0 = -ground_half + cell * float(i), z0 = -ground_half + cell * float(j);
            const float x1 = x0 + cell, z1 = z0 + cell;
            mesh.quad({x0, ground.height(x0, z0), z0}, {x0, ground.height(x0, z1), z1}, {x1, ground.height(x1, z1), z1},
                      {x1, ground.height(x1, z0), z0}, vary(rng, kGround, 0.08f));
        }
    return ground;
}

// Groves: trees gather around a few centres, keeping a minimum gap between trunks. The
// trunks' positions on the ground plane (y = 0).
std::vector<Vec3> place_trunks(SplitMix64& rng, const ForestLayout& forest) {
    const float forest_radius = forest.radius;
    const int groves = std::max(1, forest.trees / 5);
    std::vector<Vec3> grove_centres;
    for (int g = 0; g < groves; ++g) {
        const float r = 0.6f * forest_radius * std::sqrt(rng.uniform()), a = rng.uniform(0, 2 * kPi);
        grove_centres.push_back({r * std::cos(a), 0, r * std::sin(a)});
    }
    std::vector<Vec3> trunks;
    for (int t = 0; t < forest.trees; ++t) {
        Vec3 best;
        for (int attempt = 0; attempt < 40; ++attempt) {
            const Vec3 c = grove_centres[rng.below(uint32_t(groves))];
            // Sum of two uniforms: a soft, centre-heavy spread around the grove centre.
            const float spread = 0.3f * forest_radius;
            Vec3 q = c +
                Vec3{rng.uniform(-1, 1) + rng.uniform(-1, 1), 0, rng.uniform(-1, 1) + rng.uniform(-1, 1)} *
                    (0.5f * spread);
            const float r = length(q);
            if (r > forest_radius) q = q * (forest_radius / r);
            best = q;
            bool clear = true;
            for (const Vec3& other : trunks) clear &= length(other - q) >= 5.0f;
            if (clear) break;
        }
        trunks.push_back(best);
    }
    return trunks;
}

// One tree standing at `base`: its trunk and branches, its leaf clusters appended to
// `clusters` (filled with leaves later, when the leaves' budget is known). Returns its height.
float build_tree(ColouredSoupBuilder& mesh, SplitMix64& rng, Vec3 base, std::vector<LeafCluster>& clusters) {
    const bool conifer = rng.uniform() < 0.35f;
    const float h = conifer ? rng.uniform(12, 20) : rng.uniform(9, 16);
    const Vec3 leaf_colour = vary(rng, conifer ? kNeedle : kBroadLeaf, 0.2f);
    // The trunk: three tapering segments with a slight random lean.
    const float trunk_top = conifer ? 0.97f * h : 0.62f * h;
    const Vec3 lean{rng.uniform(-0.04f, 0.04f) * h, 0, rng.uniform(-0.04f, 0.04f) * h};
    const float r_base = (conifer ? 0.028f : 0.035f) * h, r_top = conifer ? 0.006f * h : 0.022f * h;
    Vec3 prev = base;
    for (int s = 1; s <= 3; ++s) {
        const float f = float(s) / 3.0f;
        const Vec3 next = base + Vec3{0, trunk_top * f, 0} + lean * (f * f);
        mesh.tube(prev, next, r_base + (r_top - r_base) * (f - 1.0f / 3.0f), r_base + (r_top - r_base) * f, 7, kBark);
        prev = next;
    }
    const Vec3 top = prev;
    if (conifer) {
        // Whorls of needles, widest at the bottom: a layered cone.
        const int whorls = 6 + int(rng.below(3));
        for (int w = 0; w < whorls; ++w) {
            const float f = float(w) / float(whorls);
            const float r = (0.30f * (1.0f - f) + 0.05f) * h * rng.uniform(0.9f, 1.1f);
            const Vec3 c = base + Vec3{0, (0.22f + 0.72f * f) * h, 0} + lean * (f * f);
            clusters.push_back({c, {r, 0.07f * h, r}, true, leaf_colour});
        }
        return h;
    }
    // Branches from the upper trunk, each ending in a leaf cluster, plus one on top.
    const int branches = 4 + int(rng.below(3));
    for (int b = 0; b < branches; ++b) {
        const float az = 2 * kPi * (float(b) + rng.uniform(-0.3f, 0.3f)) / float(branches);
        const float el = rng.uniform(0.6f, 1.05f);  // radians above the horizontal
        const float from = rng.uniform(0.45f, 0.62f) / 0.62f;
        const Vec3 start = base + (top - base) * from;
        const Vec3 dir{std::cos(az) * std::cos(el), std::sin(el), std::sin(az) * std::cos(el)};
        const Vec3 end = start + dir * (rng.uniform(0.25f, 0.35f) * h);
        mesh.tube(start, end, 0.012f * h, 0.007f * h, 5, kBark);
        const float r = rng.uniform(0.17f, 0.24f) * h;
        clusters.push_back({end + Vec3{0, 0.3f * r, 0}, {r, 0.75f * r, r}, false, leaf_colour});
    }
    const float r = rng.uniform(0.2f, 0.25f) * h;
    clusters.push_back({top + Vec3{0, 0.6f * r, 0}, {r, 0.8f * r, r}, false, leaf_colour});
    return h;
}

// The leaves: everything the trees left of the triangle target, shared among the clusters.
void fill_leaves(ColouredSoupBuilder& mesh, SplitMix64& rng, const std::vector<LeafCluster>& clusters, int64_t target) {
    const size_t fixed = mesh.triangles();
    if (size_t(target) < fixed + 10 * clusters.size())
        too_few_triangles("forest", target, fixed + 10 * clusters.size());
    // Leaves per cluster in proportion to its surface (Thomsen's ellipsoid-area formula is
    // overkill; the mean of the pairwise radius products is close enough for a share).
    std::vector<double> surface;
    for (const auto& c : clusters)
        surface.push_back(4.0 * double(kPi) * (c.radii.x * c.radii.y + c.radii.x * c.radii.z + c.radii.y * c.radii.z) /
                          3.0);
    const std::vector<size_t> leaves = proportional_shares(size_t(target) - fixed, surface);
    for (size_t k = 0; k < clusters.size(); ++k) {
        const LeafCluster& c = clusters[k];
        // Leaf size from the coverage we want: the leaves' total area is about twice the
        // cluster's surface, so clusters look dense from outside yet keep gaps between
        // leaves (a leaf's area is ~1.3 r^2 for circumradius r).
        const float r = std::min(std::sqrt(2.0f * float(surface[k]) / (1.3f * float(std::max<size_t>(leaves[k], 1)))),
                                 0.3f * std::min(c.radii.x, c.radii.y));
        for (size_t i = 0; i < leaves[k]; ++i) {
            // Uniform in volume over the outer shell (radius fraction 0.67..1).
            const Vec3 d = rng.unit_vector();
            const float shell = std::cbrt(rng.uniform(0.3f, 1.0f));
            const Vec3 at = c.centre + Vec3{d.x * c.radii.x, d.y * c.radii.y, d.z * c.radii.z} * shell;
            const Vec3 colour = vary(rng, c.colour, 0.15f);
            if (c.needles) mesh.random_triangle(rng, at, 1.6f * r, 0.3f * r, colour);
            else mesh.random_triangle(rng, at, r, 0.866f * r, colour);
        }
    }
}

// The stages in the order they draw from the one random stream: ground, trunk positions,
// trees (trunks and branches first, their count is fixed), then the leaves take what is left.
ProceduralScene make_forest(const ParamSet& p) {
    const int64_t target = p.get_int("triangles");
    SplitMix64 rng(mix_seed(uint64_t(p.get_int("seed")), 0xF0235Full));
    ProceduralScene out;
    out.scene.name = scene_name("forest", p);
    ColouredSoupBuilder mesh(out);

    const ForestLayout forest = forest_layout(target);
    const Ground ground = build_ground(mesh, rng, forest, target);
    const std::vector<Vec3> trunks = place_trunks(rng, forest);
    std::vector<LeafCluster> clusters;
    float tallest = 0;
    for (const Vec3& base_xz : trunks) {
        const Vec3 base{base_xz.x, ground.height(base_xz.x, base_xz.z) - 0.3f, base_xz.z};
        tallest = std::max(tallest, build_tree(mesh, rng, base, clusters));
    }
    fill_leaves(mesh, rng, clusters, target);

    // The view: from the south-east, low enough that the sky shows above the far edge of
    // the ground; the light: a high sun to the right, so trees cast shadows toward the
    // viewer's left.
    const Vec3 target_point{0, 0.3f * tallest, 0};
    out.camera = orbit_camera(target_point, 35.0f, 16.0f, 1.9f * forest.radius);
    out.light = Light{Vec3{0, 0, 0} + normalize(Vec3{0.9f, 1.3f, -0.2f}) * (4.0f * forest.radius)};
    out.scene.finalize();
    return out;
}

// ---- city ------------------------------------------------------------------------------
//
// The Sci-Fi Tropical City's character (report 5.3.2): fewer triangles than the forest
// but more detail per object, and geometry covering most of the image. Buildings on a
// street grid, each a stack of set-back tiers; every facade is a grid of inset windows
// (a frame and a recess per window), every tier a cornice slab; rooftops carry machinery,
// tanks and antennas; palms line the blocks.
//
// Hitting the triangle target: everything but the windows is laid out first; the window
// size is then chosen (bisection) so the facades use as much of the rest as possible, and
// the last few triangles become rooftop extras (boxes, solar panels, one fin), so the
// total is exact.

constexpr Vec3 kAsphalt{0.16f, 0.16f, 0.17f}, kPavement{0.62f, 0.60f, 0.56f}, kGlass{0.10f, 0.20f, 0.28f};
constexpr Vec3 kRoofGrey{0.55f, 0.55f, 0.55f}, kMetal{0.70f, 0.72f, 0.74f}, kPalmTrunk{0.42f, 0.32f, 0.20f};
constexpr Vec3 kPalmLeaf{0.16f, 0.45f, 0.14f}, kSolar{0.08f, 0.10f, 0.22f};
constexpr Vec3 kFacadeColours[] = {{0.92f, 0.90f, 0.84f}, {0.95f, 0.80f, 0.62f}, {0.90f, 0.62f, 0.52f},
                                   {0.55f, 0.80f, 0.78f}, {0.95f, 0.88f, 0.55f}, {0.75f, 0.82f, 0.90f}};

constexpr float kFloorHeight = 3.5f, kBayWidth = 3.0f;  // the window grid at scale 1
constexpr size_t kWindowTriangles = 18;                 // 8 frame + 10 recess

struct Tier {
    Bounds3 box;  // walls from box.lower.y to box.upper.y
    Vec3 colour;
};

// One facade: a rectangle of width `w` and height `h`, lower-left corner `o` seen from
// outside, `right` along its width, `out` its outward normal.
struct Facade {
    Vec3 o, right, out;
    float w, h;
    Vec3 colour;
};

std::vector<Facade> facades_of(const Tier& t) {
    const Vec3 l = t.box.lower, u = t.box.upper;
    const float w = u.x - l.x, d = u.z - l.z, h = u.y - l.y;
    return {{{l.x, l.y, u.z}, {1, 0, 0}, {0, 0, 1}, w, h, t.colour},
            {{u.x, l.y, l.z}, {-1, 0, 0}, {0, 0, -1}, w, h, t.colour},
            {{u.x, l.y, u.z}, {0, 0, -1}, {1, 0, 0}, d, h, t.colour},
            {{l.x, l.y, l.z}, {0, 0, 1}, {-1, 0, 0}, d, h, t.colour}};
}

// Windows across and up a facade at window-grid scale `scale`; 0 when it gets none.
std::pair<int, int> window_grid(const Facade& f, float scale) {
    const int nx = int(f.w / (kBayWidth * scale)), ny = int(f.h / (kFloorHeight * scale));
    return nx >= 1 && ny >= 1 ? std::pair{nx, ny} : std::pair{0, 0};
}

size_t facade_triangles(const Facade& f, float scale) {
    const auto [nx, ny] = window_grid(f, scale);
    return nx ? kWindowTriangles * size_t(nx) * size_t(ny) : 2;  // a plain wall otherwise
}

void build_facade(ColouredSoupBuilder& mesh, const Facade& f, float scale) {
    const Vec3 up{0, 1, 0};
    auto at = [&](float x, float y, float depth) { return f.o + f.right * x + up * y + f.out * depth; };
    const auto [nx, ny] = window_grid(f, scale);
    if (!nx) {
        mesh.quad(at(0, 0, 0), at(f.w, 0, 0), at(f.w, f.h, 0), at(0, f.h, 0), f.colour);
        return;
    }
    const float cw = f.w / float(nx), ch = f.h / float(ny), depth = std::min(0.35f, 0.15f * cw);
    const Vec3 reveal = f.colour * 0.8f;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const float x0 = cw * float(i), x1 = x0 + cw, y0 = ch * float(j), y1 = y0 + ch;
            const float wx0 = x0 + 0.18f * cw, wx1 = x1 - 0.18f * cw, wy0 = y0 + 0.3f * ch, wy1 = y1 - 0.15f * ch;
            // The frame: four strips of wall around the opening.
            mesh.quad(at(x0, y0, 0), at(x1, y0, 0), at(x1, wy0, 0), at(x0, wy0, 0), f.colour);
            mesh.quad(at(x0, wy1, 0), at(x1, wy1, 0), at(x1, y1, 0), at(x0, y1, 0), f.colour);
            mesh.quad(at(x0, wy0, 0), at(wx0, wy0, 0), at(wx0, wy1, 0), at(x0, wy1, 0), f.colour);
            mesh.quad(at(wx1, wy0, 0), at(x1, wy0, 0), at(x1, wy1, 0), at(wx1, wy1, 0), f.colour);
            // The recess: four reveals and the glass at the back.
            mesh.quad(at(wx0, wy0, 0), at(wx1, wy0, 0), at(wx1, wy0, -depth), at(wx0, wy0, -depth), reveal);
            mesh.quad(at(wx0, wy1, 0), at(wx0, wy1, -depth), at(wx1, wy1, -depth), at(wx1, wy1, 0), reveal);
            mesh.quad(at(wx0, wy0, 0), at(wx0, wy0, -depth), at(wx0, wy1, -depth), at(wx0, wy1, 0), reveal);
            mesh.quad(at(wx1, wy0, 0), at(wx1, wy1, 0), at(wx1, wy1, -depth), at(wx1, wy0, -depth), reveal);
            mesh.quad(at(wx0, wy0, -depth), at(wx1, wy0, -depth), at(wx1, wy1, -depth), at(wx0, wy1, -depth), kGlass);
        }
}

// A palm: a curved trunk of four segments and a crown of drooping fronds.
void build_palm(ColouredSoupBuilder& mesh, SplitMix64& rng, Vec3 base) {
    const float h = rng.uniform(6, 10), lean_az = rng.uniform(0, 2 * kPi), lean = rng.uniform(0.05f, 0.18f) * h;
    const Vec3 lean_dir{std::cos(lean_az), 0, std::sin(lean_az)};
    Vec3 prev = base;
    for (int s = 1; s <= 4; ++s) {
        const float f = float(s) / 4.0f;
        const Vec3 next = base + Vec3{0, h * f, 0} + lean_dir * (lean * f * f);
        mesh.tube(prev, next, 0.22f - 0.03f * float(s - 1), 0.22f - 0.03f * float(s), 5, kPalmTrunk);
        prev = next;
    }
    const int fronds = 7;
    for (int k = 0; k < fronds; ++k) {
        const float az = 2 * kPi * (float(k) + rng.uniform(-0.2f, 0.2f)) / float(fronds);
        const Vec3 out{std::cos(az), 0, std::sin(az)}, side{-std::sin(az), 0, std::cos(az)};
        const float len = rng.uniform(2.8f, 3.8f);
        const Vec3 mid = prev + out * (0.55f * len) + Vec3{0, 0.35f, 0};
        const Vec3 tip = prev + out * len + Vec3{0, -1.0f, 0};
        const Vec3 colour = vary(rng, kPalmLeaf, 0.15f);
        mesh.quad(prev + side * 0.1f, prev - side * 0.1f, mid - side * 0.45f, mid + side * 0.45f, colour);
        mesh.triangle(mid + side * 0.45f, mid - side * 0.45f, tip, colour);
    }
}

// How big the city is: about 6k triangles per block of four buildings at any size.
struct CityLayout {
    int blocks;  // along each side of the grid
    float block = 44.0f, street = 12.0f, pitch = 56.0f;
    float half;           // half the grid's side
    int palms_per_block;  // at the block's corners
};

CityLayout city_layout(int64_t target) {
    CityLayout city;
    city.blocks = std::clamp(int(std::lround(std::sqrt(double(target) / 6000.0))), 2, 12);
    city.pitch = city.block + city.street;
    city.half = 0.5f * city.pitch * float(city.blocks);
    city.palms_per_block = int(std::min<int64_t>(4, target / 20000));
    return city;
}

// The tiers of the city's buildings, and which of them have a roof for rooftop extras.
struct Buildings {
    std::vector<Tier> tiers;
    std::vector<size_t> roof_tiers;
};

constexpr float kKerb = 0.2f;  // the pavement's height

// A building's tiers on the footprint `fp` (at kerb height), up to `height` above the
// kerb, each crowned by a cornice slab and the next set back.
void build_tiers(ColouredSoupBuilder& mesh, SplitMix64& rng, Bounds3 fp, float height, int levels, Vec3 colour,
                 Buildings& city) {
    float y = kKerb;
    for (int t = 0; t < levels; ++t) {
        const float share = t + 1 == levels ? 1.0f : rng.uniform(0.45f, 0.6f);
        const float top = t + 1 == levels ? kKerb + height : y + share * (kKerb + height - y);
        city.tiers.push_back({{{fp.lower.x, y, fp.lower.z}, {fp.upper.x, top, fp.upper.z}}, colour});
        // A cornice slab crowns each tier; its top is the roof.
        mesh.box(
            {{fp.lower.x - 0.4f, top - 0.5f, fp.lower.z - 0.4f}, {fp.upper.x + 0.4f, top + 0.3f, fp.upper.z + 0.4f}},
            colour * 0.9f);
        city.roof_tiers.push_back(city.tiers.size() - 1);
        // The next tier sets back 1.5-3 m a side (keeping at least 5 m).
        const float inset = std::min(rng.uniform(1.5f, 3.0f),
                                     0.5f * (std::min(fp.upper.x - fp.lower.x, fp.upper.z - fp.lower.z) - 5.0f));
        fp = {{fp.lower.x + std::max(0.0f, inset), top, fp.lower.z + std::max(0.0f, inset)},
              {fp.upper.x - std::max(0.0f, inset), top, fp.upper.z - std::max(0.0f, inset)}};
        y = top;
    }
}

// The top roof's machinery: air-conditioning boxes, a water tank, an antenna.
void build_roof_machinery(ColouredSoupBuilder& mesh, SplitMix64& rng, const Bounds3& roof) {
    const float ry = roof.upper.y + 0.3f;
    auto roof_point = [&](float margin) {
        return Vec3{rng.uniform(roof.lower.x + margin, roof.upper.x - margin), ry,
                    rng.uniform(roof.lower.z + margin, roof.upper.z - margin)};
    };
    const int units = 1 + int(rng.below(3));
    for (int u = 0; u < units; ++u) {
        const Vec3 c = roof_point(2.0f);
        const float sx = rng.uniform(0.8f, 1.8f), sz = rng.uniform(0.8f, 1.8f), sy = rng.uniform(0.6f, 1.4f);
        mesh.box({{c.x - sx, ry, c.z - sz}, {c.x + sx, ry + sy, c.z + sz}}, kMetal, false);
    }
    const Vec3 tank = roof_point(2.0f);
    const float tank_h = rng.uniform(1.5f, 3.0f), tank_r = rng.uniform(0.8f, 1.3f);
    mesh.tube(tank, tank + Vec3{0, tank_h, 0}, tank_r, tank_r, 8, kRoofGrey);
    mesh.disc(tank + Vec3{0, tank_h, 0}, tank_r, 8, kRoofGrey);
    const Vec3 mast = roof_point(1.0f);
    const float mast_h = rng.uniform(3.0f, 9.0f);
    mesh.box({{mast.x - 0.1f, ry, mast.z - 0.1f}, {mast.x + 0.1f, ry + mast_h, mast.z + 0.1f}}, kMetal, false);
}

// One building on the 20 m x 20 m lot at (lx, lz): a footprint of 12-18 m a side, tiers
// taller toward the city's centre (a skyline, not a carpet), machinery on the top roof.
void build_building(ColouredSoupBuilder& mesh, SplitMix64& rng, float lx, float lz, float half, Buildings& city) {
    const float w = rng.uniform(12, 18), d = rng.uniform(12, 18);
    const float x0 = lx + (20.0f - w) * rng.uniform(0.2f, 0.8f);
    const float z0 = lz + (20.0f - d) * rng.uniform(0.2f, 0.8f);
    const Vec3 centre{x0 + 0.5f * w, 0, z0 + 0.5f * d};
    const float falloff = std::exp(-dot(centre, centre) / (0.45f * half * half));
    const float height = 10.0f + 55.0f * falloff * rng.uniform(0.4f, 1.3f) + rng.uniform(0, 10);
    const int levels = height > 25 ? 1 + int(rng.below(3)) : 1 + int(rng.below(2));
    const Vec3 colour = vary(rng, kFacadeColours[rng.below(6)], 0.06f);
    build_tiers(mesh, rng, {{x0, kKerb, z0}, {x0 + w, kKerb, z0 + d}}, height, levels, colour, city);
    build_roof_machinery(mesh, rng, city.tiers.back().box);
}

// Block (bi, bj): its pavement, four buildings, palms near its corners.
void build_block(ColouredSoupBuilder& mesh, SplitMix64& rng, const CityLayout& layout, int bi, int bj,
                 Buildings& city) {
    const float bx = -layout.half + layout.pitch * float(bi) + 0.5f * layout.street;
    const float bz = -layout.half + layout.pitch * float(bj) + 0.5f * layout.street;
    mesh.box({{bx, 0, bz}, {bx + layout.block, kKerb, bz + layout.block}}, kPavement, false);
    for (int li = 0; li < 2; ++li)
        for (int lj = 0; lj < 2; ++lj)
            build_building(mesh, rng, bx + 2.0f + 20.0f * float(li), bz + 2.0f + 20.0f * float(lj), layout.half, city);
    for (int k = 0; k < layout.palms_per_block; ++k) {
        const float px = k & 1 ? bx + layout.block - 1.0f : bx + 1.0f;
        const float pz = k & 2 ? bz + layout.block - 1.0f : bz + 1.0f;
        build_palm(mesh, rng, {px + rng.uniform(-0.3f, 0.3f), kKerb, pz + rng.uniform(-0.3f, 0.3f)});
    }
}

// The windows: the smallest window scale (most windows) whose facades still fit in what
// the target leaves, found by bisection.
void build_windows(ColouredSoupBuilder& mesh, const std::vector<Tier>& tiers, int64_t target) {
    std::vector<Facade> facades;
    for (const Tier& t : tiers)
        for (const Facade& f : facades_of(t)) facades.push_back(f);
    auto window_triangles = [&](float scale) {
        size_t n = 0;
        for (const Facade& f : facades) n += facade_triangles(f, scale);
        return n;
    };
    const size_t fixed = mesh.triangles();
    constexpr float kFinest = 0.15f, kCoarsest = 100.0f;  // 0.45 m bays .. no windows at all
    if (size_t(target) < fixed + window_triangles(kCoarsest))
        too_few_triangles("city", target, fixed + window_triangles(kCoarsest));
    const size_t window_budget = size_t(target) - fixed;
    float lo = kFinest, hi = kCoarsest;  // invariant: hi fits
    if (window_triangles(lo) <= window_budget) hi = lo;
    for (int it = 0; it < 60 && hi - lo > 1e-5f * hi; ++it) {
        const float mid = 0.5f * (lo + hi);
        (window_triangles(mid) <= window_budget ? hi : lo) = mid;
    }
    for (const Facade& f : facades) build_facade(mesh, f, hi);
}

// The rest of the budget becomes rooftop extras on random roofs: boxes (10 triangles),
// then tilted solar panels (2), then one fin (1) — so the count comes out exact. They
// draw from their own stream so the layout does not depend on the budget.
void build_rooftop_extras(ColouredSoupBuilder& mesh, uint64_t seed, const Buildings& city, int64_t target) {
    SplitMix64 extras(mix_seed(seed, 0xE7A5ull));
    size_t left = size_t(target) - mesh.triangles();
    while (left > 0) {
        const Bounds3& roof = city.tiers[city.roof_tiers[extras.below(uint32_t(city.roof_tiers.size()))]].box;
        const float ry = roof.upper.y + 0.3f;
        const Vec3 c{extras.uniform(roof.lower.x + 1.0f, roof.upper.x - 1.0f), ry,
                     extras.uniform(roof.lower.z + 1.0f, roof.upper.z - 1.0f)};
        if (left >= ColouredSoupBuilder::kBoxNoBottomTriangles) {
            const float s = extras.uniform(0.4f, 1.0f);
            mesh.box({{c.x - s, ry, c.z - s}, {c.x + s, ry + extras.uniform(0.4f, 1.2f), c.z + s}}, kMetal, false);
            left -= ColouredSoupBuilder::kBoxNoBottomTriangles;
        } else if (left >= 2) {
            mesh.quad(c + Vec3{-0.8f, 0.2f, -0.5f}, c + Vec3{0.8f, 0.2f, -0.5f}, c + Vec3{0.8f, 0.8f, 0.5f},
                      c + Vec3{-0.8f, 0.8f, 0.5f}, kSolar);
            left -= 2;
        } else {
            mesh.triangle(c, c + Vec3{0.6f, 0, 0}, c + Vec3{0, 2.0f, 0}, kMetal);
            left -= 1;
        }
    }
}

// The stages in the order they draw from the layout's random stream: streets, then block
// by block (pavement, buildings, palms); then the windows, sized to the budget, and the
// rooftop extras from a stream of their own.
ProceduralScene make_city(const ParamSet& p) {
    const int64_t target = p.get_int("triangles");
    const uint64_t seed = uint64_t(p.get_int("seed"));
    SplitMix64 rng(mix_seed(seed, 0xC17Cull));
    ProceduralScene out;
    out.scene.name = scene_name("city", p);
    ColouredSoupBuilder mesh(out);

    const CityLayout layout = city_layout(target);
    // Streets: one big asphalt quad reaching well beyond the grid, so no view shows its edge.
    const float g = 3.0f * layout.half + 2.0f * layout.pitch;
    mesh.quad({-g, 0, -g}, {-g, 0, g}, {g, 0, g}, {g, 0, -g}, kAsphalt);
    Buildings city;
    for (int bi = 0; bi < layout.blocks; ++bi)
        for (int bj = 0; bj < layout.blocks; ++bj) build_block(mesh, rng, layout, bi, bj, city);
    build_windows(mesh, city.tiers, target);
    build_rooftop_extras(mesh, seed, city, target);

    // The view: from above the south-east corner looking down across the grid, close
    // enough that buildings fill the frame; the sun high to the right.
    out.camera = orbit_camera({0, 8.0f, 0}, 35.0f, 38.0f, 1.35f * layout.half + 40.0f);
    out.light = Light{normalize(Vec3{1.0f, 2.2f, -0.4f}) * (3.0f * layout.half + 100.0f)};
    out.scene.finalize();
    return out;
}

// ---- soup ------------------------------------------------------------------------------
//
// Independent random triangles in the unit box: no structure for a builder to exploit,
// many overlaps — the stress case, and small versions make quick agreement tests.

ProceduralScene make_soup(const ParamSet& p) {
    const int64_t n = p.get_int("triangles");
    const float size = float(p.get_float("size"));
    SplitMix64 rng(mix_seed(uint64_t(p.get_int("seed")), 0x5002ull));
    ProceduralScene out;
    out.scene.name = scene_name("soup", p);
    ColouredSoupBuilder mesh(out);
    // Equilateral, edge length `size`: circumradius size / sqrt(3).
    const float r = size / std::sqrt(3.0f);
    for (int64_t i = 0; i < n; ++i) {
        const Vec3 c{rng.uniform(), rng.uniform(), rng.uniform()};
        const Vec3 colour{rng.uniform(0.35f, 0.95f), rng.uniform(0.35f, 0.95f), rng.uniform(0.35f, 0.95f)};
        mesh.random_triangle(rng, c, r, 0.866f * r, colour);
    }
    out.scene.finalize();
    return out;
}

// The largest scene of the kind with at most `want` vertices. Vertices grow with the
// triangle target at a nearly fixed ratio (forest ~3: its leaves are lone triangles; city
// ~2: quads and boxes) but in steps (the layout changes with the size), so the target is
// found by search: secant steps on the ratio, then single steps to the largest target
// that does not exceed `want`. Each step generates the scene (tens of ms at the report's
// sizes).
ProceduralScene sized_by_vertices(const ProceduralInfo& info, const std::map<std::string, std::string>& given,
                                  int64_t want) {
    auto make = [&](int64_t triangles) {
        std::map<std::string, std::string> p = given;  // keeps `vertices`: the name says how it was sized
        p["triangles"] = std::to_string(triangles);
        return info.generate(resolve_params(info.name, info.params, p, "procedural scene"));
    };
    auto vertices = [](const ProceduralScene& s) { return int64_t(s.scene.vertices.size()); };
    const int64_t lowest = 1000;
    int64_t t = std::max(lowest, want / 2);
    ProceduralScene s = make(t);
    for (int step = 0; step < 8 && vertices(s) != want; ++step) {
        const double ratio = double(vertices(s)) / double(t);
        const int64_t next = std::max(lowest, int64_t(double(want) / ratio));
        if (next == t) break;
        t = next;
        s = make(t);
    }
    while (vertices(s) > want) {
        if (t == lowest)
            throw ParamError("procedural scene '" + info.name + "': vertices=" + std::to_string(want) +
                             " is fewer than its smallest scene has (" + std::to_string(vertices(s)) + ")");
        s = make(--t);
    }
    for (ProceduralScene up = make(t + 1); vertices(up) <= want; up = make(++t + 1)) s = std::move(up);
    return s;
}

}  // namespace

const std::vector<ProceduralInfo>& procedural_registry() {
    static const std::vector<ProceduralInfo> registry = [] {
        std::vector<ProceduralInfo> r;
        r.push_back(
            {"forest",
             "procedural analog of the report's Trees scene (5.3.1), not that model: groves of broad-leaved "
             "trees and conifers whose leaves are dense clusters of small triangles, on a large ground plane "
             "under an empty sky",
             scene_size("252000", "total triangle count (exact; the report's Trees scene has 252,178 primitives)"),
             make_forest});
        r.push_back(
            {"city",
             "procedural analog of the report's Sci-Fi Tropical City (5.3.2), not that model: a street grid "
             "of set-back buildings with inset windows, cornices, rooftop machinery and palms, filling the view",
             scene_size("91000", "total triangle count (exact; the report's city has 90,811 primitives)"), make_city});
        std::vector<ParamSpec> soup = size_and_seed("10000", "number of triangles");
        soup[0].min = 1;
        soup.push_back(
            {"size", ParamType::Float, "0.05", {}, 1e-6, 1.0, "triangle edge length, relative to the unit box"});
        r.push_back({"soup", "random equilateral triangles in random orientations in the unit box", soup, make_soup});
        return r;
    }();
    return registry;
}

const ProceduralInfo* find_procedural(std::string_view kind) {
    for (const auto& info : procedural_registry())
        if (info.name == kind) return &info;
    return nullptr;
}

ProceduralScene generate_procedural(const std::string& kind, const std::map<std::string, std::string>& params,
                                    ParamSet* resolved) {
    const ProceduralInfo* info = find_procedural(kind);
    if (!info)
        throw ParamError(
            unknown_name("procedural scene", kind, names_of(procedural_registry(), &ProceduralInfo::name)));
    ParamSet set = resolve_params(kind, info->params, params, "procedural scene");
    const bool by_vertices = set.given("vertices") && set.get_int("vertices") > 0;
    if (by_vertices && set.given("triangles"))
        throw ParamError("procedural scene '" + kind + "': give triangles or vertices, not both");
    ProceduralScene scene =
        by_vertices ? sized_by_vertices(*info, params, set.get_int("vertices")) : info->generate(set);
    if (resolved) *resolved = std::move(set);
    return scene;
}

Scene make_procedural(const std::string& kind, const std::map<std::string, std::string>& params) {
    return generate_procedural(kind, params).scene;
}

}  // namespace accelbench
