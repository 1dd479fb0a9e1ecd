// The extreme-case catalogue: small procedural scenes with ray sets that break
// ray tracers in practice, each with what a correct implementation must do, and a
// verdict per accelerator.
//
// A case is data: a scene, rays, and per ray an expectation (must hit, must miss, must
// hit one of these primitives, or nothing beyond "no NaN"). One judge applies every
// case the same way to any accelerator, so a new case is a new generator, not new
// checking code. Every expectation is unambiguous for the exact geometry (the rays are
// built so that margins dwarf float rounding, or exact so that the answer is decided by
// a rule, e.g. "a ray through the edge shared by two triangles hits one of them"); the
// reference structure passes every case, which the tests check. The generators are
// robustness_generators.cpp (their building blocks robustness_helpers.h), the catalogue
// robustness_cases.cpp, the judge robustness_judge.cpp.
//
// Cases (ids are numbers, a letter for variants; configs name them as `{case: ID}`):
//   1  closed meshes, rays from inside at vertices and edge points   (leaks)
//   2  the same translated by 1.5e5 (a), 1e6 (b), 1e7 (c)             (leaks)
//   3  the same scaled by 1e-6 (a), 2^-64 (b), 2^-90 (c)              (leaks)
//   4  axis-aligned rays with origins exactly on box faces
//   5  direction components -0.0 and 0.0
//   6  tiny direction components (1e-40, 1e-20, 1e-15, 1e-11)
//   7  grazing rays in and 1 ulp off a triangle's plane
//   8  degenerate triangles: collinear, coincident vertices, needles
//   9  N copies of one triangle; triangles whose centroids are all equal
//  10  a flat scene (all vertices x = 2)
//  11  a dense cluster plus one outlier at 1e6 (Morton quantization)
//  12  coplanar axis-aligned triangles on candidate split planes (kd-tree flat cells)
//  13  overlapping coplanar triangles (deterministic closest primitive)
//  14  bad input: NaN (a), Inf (b), huge (c) vertices, an out-of-range index (d) and a
//      NaN vertex no face uses (e) are rejected at load (one vertex policy, docs/configs.md)
//  15  NaN/Inf rays, tmin = -0, tmax = inf, empty intervals
//  16  nested shells 4e-5 apart
//  17  long rays from a camera 1e6 scene sizes away
//  18  a very deep tree (a geometric progression of tiny triangles) against stack limits
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "accelbench/accel/accelerator.h"
#include "accelbench/base/params.h"
#include "accelbench/scene/scene.h"
#include "accelbench/verify/error_metrics.h"

namespace accelbench {

enum class Expect : uint8_t {
    Any,   // only "no NaN": the answer is compared with the reference for information
    Hit,   // must hit something; a miss is a leak
    Miss,  // must hit nothing
    Prim,  // must hit a primitive with id in [prim_lo, prim_hi] (a miss is a leak)
};

struct RayExpectation {
    Expect kind = Expect::Any;
    uint32_t prim_lo = 0, prim_hi = 0;
    // The expectation relies on watertightness (a ray exactly through an edge or a
    // vertex): required from watertight structures, reported for the others.
    bool watertight_only = false;
};

struct RobustnessCase {
    std::string id;           // "1", "2a", ... (the numbering of the list above)
    std::string name;         // short, for tables: "closed-meshes", ...
    std::string requirement;  // what a correct implementation must do
    Scene scene;              // finalized, except for cases that expect rejection
    std::vector<Ray> rays;
    std::vector<RayExpectation> expect;  // one per ray
    std::vector<Hit> reference_hits;     // the reference's answers, one per ray

    // Bad input: Scene::finalize() must throw a message containing this text (it names
    // the offending face). Empty: the scene is valid.
    std::string rejection_mentions;
    bool expects_rejection() const { return !rejection_mentions.empty(); }
};

// The catalogue's entries in order, each generating its case on demand (cheap to list).
struct RobustnessCaseEntry {
    std::string id;
    std::function<RobustnessCase()> make;  // without reference_hits; see make_robustness_case
};
const std::vector<RobustnessCaseEntry>& robustness_case_list();

// A case's short name ("closed-meshes-at-1e6"), generating the case to learn it. Throws
// like make_robustness_case for an unknown id.
std::string robustness_case_name(const std::string& id);

// One case, complete with the reference's answers. Throws std::invalid_argument naming the
// known ids for an unknown one.
RobustnessCase make_robustness_case(const std::string& id);

// Every case, complete (deterministic; about a second in an optimised build).
std::vector<RobustnessCase> robustness_catalogue();

struct JudgeOptions {
    // Expectations marked watertight_only are required (else reported as tolerated).
    bool watertight = true;
    // BuildStats.max_depth must not exceed this (default: triangles + 64, deeper than
    // any tree whose every split separates something).
    std::optional<uint64_t> depth_limit;
};

// Watertight as the structure's info says for these parameters (every structure of ours
// uses triangle.h's watertight test; Embree only with robust=true), and its depth limit
// (AcceleratorInfo::depth_limit) where it declares one.
JudgeOptions judge_options(const AcceleratorInfo& accelerator, const ParamSet& params);

// BuildStats.memory_bytes must stay below this for a case's scene: 4 KiB per triangle
// plus 1 MiB, far above any sane structure (a node or a reference costs tens of bytes).
uint64_t case_memory_limit(const Scene& scene);

struct CaseVerdict {
    std::string case_id;
    bool pass = false;
    std::string detail;  // what failed, or how a bad input was refused
    bool built = false;
    uint64_t rays = 0;
    uint64_t leaks = 0;                 // Hit/Prim rays that missed
    uint64_t leaks_tolerated = 0;       // of watertight_only rays, for a non-watertight structure
    uint64_t false_hits = 0;            // Miss rays that hit
    uint64_t wrong_prims = 0;           // Prim rays that hit another primitive
    uint64_t nan_results = 0;           // NaN t, u or v in a hit record
    uint64_t occlusion_mismatches = 0;  // any_hits disagrees with closest_hits on hit/miss
    uint64_t nondeterministic = 0;      // answers differing between two traces or two builds
    std::optional<uint64_t> max_depth, depth_limit, memory_bytes, memory_limit;
    HitErrors vs_reference;  // informational: error against the reference

    // "leaks=0 false_hits=0 ..." for the verdict table.
    std::string counts() const;
};

using AcceleratorFactory = std::function<std::unique_ptr<Accelerator>()>;

// Builds (twice, to check determinism) and traces one case. A build that throws fails
// the case (a bad-input case never reaches the build: it is judged on the rejection).
CaseVerdict judge_case(const RobustnessCase& c, const AcceleratorFactory& make, const JudgeOptions& options);

// The same through the registry: make_accelerator(name, params) and judge_options.
CaseVerdict judge_case(const RobustnessCase& c, const std::string& accelerator,
                       const std::map<std::string, std::string>& params);

}  // namespace accelbench
