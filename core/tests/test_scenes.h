// Small scenes for structure tests: random soups and hand-made layouts whose trees can be
// worked out by hand. Deterministic (xorshift), so a failing case reproduces.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/scene.h"

namespace accelbench::test {

// The Stanford bunny of ../shared/models (beside the project, as CI lays it out). ctest sets
// ACCELBENCH_SOURCE_DIR; the model registry (harness) is not used here, core's tests stay
// below the harness.
inline Scene stanford_bunny() {
    const char* src = std::getenv("ACCELBENCH_SOURCE_DIR");
    if (!src) throw std::runtime_error("ACCELBENCH_SOURCE_DIR is not set (run the test through ctest)");
    return load_mesh(std::string(src) + "/../shared/models/stanford-bunny.obj");
}

// Uniform floats in [0, 1) from a xorshift64 state.
class TestRandom {
public:
    explicit TestRandom(uint64_t seed) : x_(seed ? seed : 1) {}
    float next() {
        x_ ^= x_ << 13;
        x_ ^= x_ >> 7;
        x_ ^= x_ << 17;
        return float(x_ >> 40) / float(1 << 24);
    }

private:
    uint64_t x_;
};

inline void add_triangle(Scene& s, Vec3 a, Vec3 b, Vec3 c) {
    const uint32_t i = uint32_t(s.vertices.size());
    s.vertices.insert(s.vertices.end(), {a, b, c});
    s.triangles.push_back({i, i + 1, i + 2});
}

// A closed height field of shared edges (40 x 40 cells, two triangles each): a ray hitting
// an edge must hit one of its triangles, so a hierarchy that drops one shows as a miss.
inline Scene closed_grid() {
    Scene scene;
    scene.name = "test-grid";
    const int w = 40;
    for (int j = 0; j <= w; ++j)
        for (int i = 0; i <= w; ++i) {
            const float x = float(i) / w, y = float(j) / w;
            scene.vertices.push_back({x, y, 0.1f * std::sin(6 * x) * std::cos(5 * y)});
        }
    for (int j = 0; j < w; ++j)
        for (int i = 0; i < w; ++i) {
            const uint32_t a = uint32_t(j * (w + 1) + i), b = a + 1, c = a + uint32_t(w + 1), d = c + 1;
            scene.triangles.push_back({a, b, d});
            scene.triangles.push_back({a, d, c});
        }
    scene.finalize();
    return scene;
}

// Random triangles (size ~0.2) in a unit box: many overlaps, many near-grazing hits.
inline Scene random_soup(int n, uint64_t seed) {
    Scene s;
    s.name = "test-soup";
    TestRandom r(seed);
    for (int i = 0; i < n; ++i) {
        Vec3 c{r.next(), r.next(), r.next()};
        Vec3 p[3];
        for (Vec3& v : p) v = c + Vec3{r.next() - 0.5f, r.next() - 0.5f, r.next() - 0.5f} * 0.2f;
        add_triangle(s, p[0], p[1], p[2]);
    }
    s.finalize();
    return s;
}

// Right triangles of leg `size` in the plane z = 0, the i-th with its right angle at
// (xs[i], 0, 0): separated along x when the xs are further apart than `size`.
inline Scene triangles_along_x(const std::vector<float>& xs, float size = 0.5f) {
    Scene s;
    s.name = "test-along-x";
    for (float x : xs) add_triangle(s, {x, 0, 0}, {x + size, 0, 0}, {x, size, 0});
    s.finalize();
    return s;
}

}  // namespace accelbench::test
