// The one interface every acceleration structure answers, in the shape of pbrt-v4's
// aggregates: build once from a scene, then closest-hit and any-hit queries.
//
// Queries are batched: the virtual call happens once per batch (a tile of the image, a
// chunk of a ray file), and the per-ray loop inside is concrete code of the structure,
// instantiated twice — with NoCounters for the timed path and with RayStats when the
// caller wants counts. So there is no virtual call and no counting branch per ray.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "accelbench/base/counters.h"
#include "accelbench/base/geometry.h"
#include "accelbench/base/params.h"
#include "accelbench/scene/scene.h"

namespace accelbench {

// The constants of every structure's `sah_cost`, so that the column compares like with
// like (BVH, LBVH, kd-tree, wide BVH): the expected number of node visits plus triangle
// tests of a ray that hits the root box, sum over inner nodes of C_trav A(n)/A(root) plus
// over leaves of C_isect prims(l) A(l)/A(root) (MacDonald & Booth 1990), with C_trav =
// C_isect = 1 whatever constants the builder itself used (those appear, where a builder
// has its own, as an extra named for them, e.g. the kd-tree's sah_cost_build).
inline constexpr double kSahCostTraversal = 1.0;
inline constexpr double kSahCostIntersection = 1.0;

// What a structure reports after build. A value a structure cannot know (Embree's node
// count) stays empty and is reported as missing, never as zero.
struct BuildStats {
    std::optional<uint64_t> nodes, leaves, max_depth, memory_bytes;
    std::optional<double> avg_leaf_size;  // primitive references per leaf
    std::optional<double> sah_cost;       // of the finished tree, with kSahCostTraversal/Intersection
    // Structure-specific extras, e.g. "degenerate_splits", "prim_refs".
    std::map<std::string, double> extra;
};

class Accelerator {
public:
    virtual ~Accelerator() = default;

    // Builds over the scene. The scene must outlive the accelerator (structures keep a
    // reference to its vertex data rather than copying it).
    virtual void build(const Scene& scene) = 0;

    // Closest hit of each ray within [ray.tmin, ray.tmax). hits[i] is overwritten.
    // When stats is non-empty it has one entry per ray and receives that ray's counts
    // (added to what is there).
    virtual void closest_hits(std::span<const Ray> rays, std::span<Hit> hits, std::span<RayStats> stats = {}) const = 0;

    // Whether anything lies within [ray.tmin, ray.tmax) (shadow rays): occluded[i] is 1
    // or 0. May stop at the first hit found.
    virtual void any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded,
                          std::span<RayStats> stats = {}) const = 0;

    virtual BuildStats build_stats() const = 0;
};

// Turns a structure with per-ray template members
//   template <class C> void intersect(const Ray&, Hit&, C& counters) const;
//   template <class C> bool occluded(const Ray&, C& counters) const;
// into an Accelerator (CRTP: the per-ray calls are static and inline).
template <class Derived>
class AcceleratorBase : public Accelerator {
public:
    void closest_hits(std::span<const Ray> rays, std::span<Hit> hits, std::span<RayStats> stats = {}) const override {
        const Derived& self = static_cast<const Derived&>(*this);
        if (stats.empty()) {
            NoCounters none;
            for (size_t i = 0; i < rays.size(); ++i) {
                hits[i] = Hit{};
                self.intersect(rays[i], hits[i], none);
            }
        } else {
            for (size_t i = 0; i < rays.size(); ++i) {
                hits[i] = Hit{};
                self.intersect(rays[i], hits[i], stats[i]);
            }
        }
    }

    void any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded,
                  std::span<RayStats> stats = {}) const override {
        const Derived& self = static_cast<const Derived&>(*this);
        if (stats.empty()) {
            NoCounters none;
            for (size_t i = 0; i < rays.size(); ++i) occluded[i] = self.occluded(rays[i], none) ? 1 : 0;
        } else {
            for (size_t i = 0; i < rays.size(); ++i) occluded[i] = self.occluded(rays[i], stats[i]) ? 1 : 0;
        }
    }
};

// Where a structure loaded from a plugin came from (accel/plugin/plugin_accel.h): every
// CSV row of it records these (plugin_file, plugin_sha256, plugin_version).
struct PluginSource {
    std::string file;     // the shared library, as given to --plugin or `plugins:`
    std::string sha256;   // of the file's bytes
    std::string version;  // the plugin's own version string
};

// What the factory and the harness know of a structure: its name, its declared
// parameters and how to make one. Each structure's static info() returns it; only the
// registry (accel/registry.cpp) lists them all.
//
// The capabilities after `create` are what the harness and the tests ask of a structure
// (never its name); their defaults are those of every structure of ours.
// What a structure is in the comparison: ours, the baseline every ratio is taken against
// (Embree), a reference that only checks the others (the errors' ground truth, the brute
// force of the tests), or a plugin that joined the registry at run time.
enum class StructureRole { ours, baseline, reference, plugin };
const char* to_string(StructureRole role);

// A parameter whose values are different structures in the report's tables (the BVH's
// split, the wide BVH's width): `{name: all}` runs every value, and the analysis shows each
// as its own row, under the label of those parameters.
struct StructureVariants {
    std::string param;
    std::vector<std::string> values;
};

// A structure's row of the structure table (`accelbench list --json`), which the analysis
// reads instead of keeping a list of structures of its own.
struct StructureEntry {
    StructureRole role = StructureRole::ours;
    std::string family{};  // the kind of structure ("BVH", "kd-tree"), for grouping
    std::vector<StructureVariants> variants{};
    // O(N) or worse per ray: left out of `{name: all}` (a config names it to run it).
    bool slow = false;
};

struct AcceleratorInfo {
    std::string name;
    std::string description;
    std::vector<ParamSpec> params;
    std::function<std::unique_ptr<Accelerator>(const ParamSet&)> create;
    // The display label the tables and figures use (the CSV column `label`), of the
    // resolved parameters: one structure may appear as several, as the wide BVH of width 4
    // and of width 8 do.
    std::function<std::string(const ParamSet&)> label;
    // Whether closest_hits/any_hits fill RayStats (node visits, box and primitive tests).
    // When not, the count columns stay missing and cost images cannot be made.
    bool counts_traversal = true;
    // Whether its ray/triangle test is watertight with these resolved parameters: no ray
    // leaks through an edge or vertex two triangles share. Robustness cases require that
    // of watertight structures and only count such leaks for the others.
    std::function<bool(const ParamSet&)> watertight = [](const ParamSet&) { return true; };
    // Code that is not ours (a production library as baseline): a robustness failure is a
    // finding to report, not a bug the tests hold against it.
    bool third_party = false;
    // The deepest tree (BuildStats::max_depth) these resolved parameters allow, where they
    // bound it: robustness cases hold the structure to it. Empty: no bound of its own.
    std::function<std::optional<uint64_t>(const ParamSet&)> depth_limit =
        [](const ParamSet&) -> std::optional<uint64_t> { return std::nullopt; };
    // Set for a structure from a plugin (its role is `plugin`); empty for ours and the
    // baselines, which are compiled in.
    std::optional<PluginSource> plugin = std::nullopt;
    // Its row of the structure table; the registry (registry.cpp) sets it, as does whatever
    // adds a structure at run time.
    StructureEntry table{};
};

// A label that does not depend on the parameters.
inline std::function<std::string(const ParamSet&)> fixed_label(std::string text) {
    return [text = std::move(text)](const ParamSet&) { return text; };
}

}  // namespace accelbench

// The per-ray members are templates defined in the structure's .cpp; this instantiates
// them there for both counter types, the timed (NoCounters) and the counting (RayStats).
#define ACCELBENCH_INSTANTIATE_RAY_QUERIES(Structure)                        \
    template void Structure::intersect(const Ray&, Hit&, NoCounters&) const; \
    template void Structure::intersect(const Ray&, Hit&, RayStats&) const;   \
    template bool Structure::occluded(const Ray&, NoCounters&) const;        \
    template bool Structure::occluded(const Ray&, RayStats&) const
