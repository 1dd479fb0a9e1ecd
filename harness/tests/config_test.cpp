// The config loader: a valid config read completely, and every kind of error reported with
// its file, line, column and key path — all of them at once.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <algorithm>

#include "accelbench/accel/registry.h"
#include "accelbench/base/param_table.h"
#include "accelbench/verify/robustness_cases.h"
#include "config/config.h"
#include "harness_test_util.h"
#include "plan/combinations.h"

namespace accelbench {
namespace {

using namespace testing_util;

class ConfigTest : public ::testing::Test {
protected:
    TempDir dir{"accelbench-config-test-"};
    std::string write(const std::string& name, const std::string& text) { return write_file(dir.path(), name, text); }
};

TEST_F(ConfigTest, ReadsTheDocumentedShape) {
    write_triangle_case(dir.path());
    const std::string path = write("smoke.yaml", R"(name: smoke
repetitions: 3
timeout_s: 120
render: {width: 160, height: 120, spp: 1, light: true, shading: false, threads: 2, fp_mode: ftz_daz}
models:
  - stanford-bunny                                   # registry name
  - {procedural: soup, triangles: 2000, seed: 1}     # generated scene
  - {path: tri.obj, rays: {file: tri.rays.csv}}      # own mesh, own rays
  - {path: tri.obj, label: tri-view, repetitions: 1, camera: {eye: [0, 0, 5], look_at: [0, 0, 0], up: [0, 1, 0], fov: 45}}
accelerators:
  - {name: embree, params: {quality: [low, high], robust: [false, true]}}
  - {name: brute_force, params: {"[max_triangles, force]": [[1000, false], [5000, true]]}}
  - {name: embree}
skip:
  - {accel: brute_force, triangles_above: 5000, reason: "O(N*P) is too slow"}
)");
    const Config c = load_config(path, registry());
    EXPECT_EQ(c.name, "smoke");
    EXPECT_EQ(c.repetitions, 3);
    EXPECT_EQ(c.warmup, 1);
    EXPECT_EQ(c.timeout_s, 120);
    EXPECT_EQ(c.render.width, 160);
    EXPECT_EQ(c.render.height, 120);
    EXPECT_EQ(c.render.threads, 2);
    EXPECT_TRUE(c.render.light);
    EXPECT_FALSE(c.render.shading);
    EXPECT_EQ(c.render.fp_mode, FpMode::FtzDaz);

    ASSERT_EQ(c.models.size(), 4u);
    EXPECT_EQ(c.models[0].kind, ModelSpec::Kind::Registry);
    EXPECT_EQ(c.models[0].label, "stanford-bunny");
    EXPECT_EQ(c.models[1].kind, ModelSpec::Kind::Procedural);
    EXPECT_EQ(c.models[1].label, "soup(triangles=2000,seed=1)");
    EXPECT_EQ(c.models[1].procedural_params.at("triangles"), "2000");
    EXPECT_EQ(c.models[2].kind, ModelSpec::Kind::Path);
    EXPECT_EQ(c.models[2].label, "tri.obj");
    ASSERT_TRUE(c.models[2].rays);
    ASSERT_EQ(c.models[2].rays->rays.size(), 3u);
    EXPECT_EQ(c.models[2].rays->rays[1].dir.z, -2.0f);  // not normalised
    EXPECT_EQ(c.models[2].rays->rays[1].tmax, kInfinity);
    EXPECT_FALSE(c.models[3].rays);
    ASSERT_TRUE(c.models[3].camera);
    EXPECT_EQ(c.models[3].camera->eye, Vec3(0, 0, 5));
    EXPECT_EQ(c.models[3].label, "tri-view");
    EXPECT_EQ(c.models[3].repetitions, 1);
    EXPECT_FALSE(c.models[2].repetitions);
    EXPECT_NE(c.models[2].key, c.models[3].key);

    ASSERT_EQ(c.accelerators.size(), 3u);
    ASSERT_EQ(c.accelerators[0].axes.size(), 2u);
    EXPECT_EQ(c.accelerators[0].axes[0].names, std::vector<std::string>{"quality"});
    EXPECT_EQ(c.accelerators[0].axes[0].values.size(), 2u);
    ASSERT_EQ(c.accelerators[1].axes.size(), 1u);
    EXPECT_EQ(c.accelerators[1].axes[0].names, (std::vector<std::string>{"max_triangles", "force"}));
    EXPECT_EQ(c.accelerators[1].axes[0].values[1], (std::vector<std::string>{"5000", "true"}));
    EXPECT_TRUE(c.accelerators[2].axes.empty());

    ASSERT_EQ(c.skip.size(), 1u);
    EXPECT_EQ(*c.skip[0].accel, "brute_force");
    EXPECT_EQ(*c.skip[0].triangles_above, 5000u);
    EXPECT_EQ(c.skip[0].reason, "O(N*P) is too slow");
}

TEST_F(ConfigTest, DefaultsAndTheFileStemAsName) {
    const Config c = load_config(write("my-run.yaml", "models: [igea]\naccelerators: [{name: embree}]\n"), registry());
    EXPECT_EQ(c.name, "my-run");
    EXPECT_EQ(c.repetitions, 5);
    EXPECT_EQ(c.timeout_s, 300);
    EXPECT_EQ(c.render.width, 640);
    EXPECT_EQ(c.render.height, 480);
    EXPECT_EQ(c.render.threads, 1);
    EXPECT_FALSE(c.render.shading);  // configs time tracing, not shading
    EXPECT_EQ(c.render.fp_mode, RenderSettings{}.fp_mode);
    EXPECT_TRUE(c.errors);  // every row says how wrong it is unless told not to
}

TEST_F(ConfigTest, RobustnessCasesAreModels) {
    const Config c = load_config(write("c.yaml", R"(errors: false
models: [{case: all}]
accelerators: [{name: bvh}]
)"),
                                 registry());
    EXPECT_FALSE(c.errors);
    ASSERT_EQ(c.models.size(), robustness_case_list().size());
    EXPECT_EQ(c.models[0].kind, ModelSpec::Kind::Case);
    EXPECT_EQ(c.models[0].label, "case-1:closed-meshes");
    EXPECT_EQ(c.models[0].key, "case:1");
    const Config one =
        load_config(write("d.yaml", "models: [{case: 3b, label: tiny}]\naccelerators: [{name: bvh}]\n"), registry());
    ASSERT_EQ(one.models.size(), 1u);
    EXPECT_EQ(one.models[0].label, "tiny");
    EXPECT_EQ(one.models[0].name, "3b");
    // The same case twice is the same model twice.
    const ConfigError e =
        load_error(write("e.yaml", "models: [{case: all}, {case: 3b}]\naccelerators: [{name: bvh}]\n"));
    EXPECT_TRUE(has_issue(e, 1, 23, "models[1]", "the same model as models[0] ('case-3b:closed-meshes-scaled-2^-64')"));
}

TEST_F(ConfigTest, RobustnessCaseErrors) {
    const ConfigError e = load_error(write("a.yaml", R"(models:
  - {case: 99}
  - {case: "1", camera: {eye: [0, 0, 1], look_at: [0, 0, 0]}}
  - {case: all, label: x}
  - {case: "2a", name: igea}
errors: "yes"
accelerators: [{name: embree}]
)"));
    EXPECT_EQ(e.issues().size(), 5u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 2, 12, "models[0].case", "unknown robustness case '99' (known: all, 1, 2a,"));
    EXPECT_TRUE(has_issue(e, 3, 17, "models[1].camera", "unknown key 'camera' for a robustness case"));
    EXPECT_TRUE(has_issue(e, 4, 17, "models[2].label", "one label cannot name every case"));
    EXPECT_TRUE(has_issue(e, 5, 5, "models[3]", "exactly one of"));
    EXPECT_TRUE(has_issue(e, 6, 9, "errors", "expected"));
}

TEST_F(ConfigTest, InterleaveIsABooleanOffByDefault) {
    const char* body = "models: [{procedural: soup, triangles: 100}]\naccelerators: [{name: bvh}]\n";
    EXPECT_FALSE(load_config(write("a.yaml", body), registry()).interleave);
    EXPECT_TRUE(load_config(write("b.yaml", std::string("interleave: true\n") + body), registry()).interleave);
    const ConfigError e = load_error(write("c.yaml", std::string("interleave: sometimes\n") + body));
    EXPECT_TRUE(has_issue(e, 1, 13, "interleave", "expected")) << all_issues(e);
}

TEST_F(ConfigTest, UnknownKeyWithSuggestion) {
    const std::string p =
        write("a.yaml", "name: t\nrepetition: 3\nmodels: [stanford-bunny]\naccelerators: [{name: embree}]\n");
    const ConfigError e = load_error(p);
    EXPECT_TRUE(has_issue(e, 2, 1, "repetition", "did you mean 'repetitions'"));
    EXPECT_EQ(e.issues()[0].mark.file, p);
    EXPECT_NE(std::string(e.what()).find(p + ":2:1: repetition: unknown key"), std::string::npos) << e.what();
}

TEST_F(ConfigTest, AcceleratorErrorsAreAllReportedAtOnce) {
    const ConfigError e = load_error(write("a.yaml", R"(models: [stanford-bunny]
accelerators:
  - {name: embree, params: {threads: [1, 2000]}}
  - {name: octree}
  - {name: brute_force, params: {max_triangle: 5}}
  - {name: embree, params: {quality: [low, best], robust: "yes"}}
)"));
    EXPECT_EQ(e.issues().size(), 5u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 3, 42, "accelerators[0].embree.threads[1]", "out of range [0, 1024]"));
    EXPECT_TRUE(has_issue(e, 4, 12, "accelerators[1].name", "unknown accelerator 'octree'"));
    EXPECT_TRUE(has_issue(e, 5, 34, "accelerators[2].brute_force.max_triangle", "did you mean 'max_triangles'"));
    EXPECT_TRUE(has_issue(e, 6, 44, "accelerators[3].embree.quality[1]", "'best' is not one of {low, medium, high}"));
    EXPECT_TRUE(has_issue(e, 6, 59, "accelerators[3].embree.robust", "expected a bool value, got the quoted string"));
    // `!!str 4` is a string, not the integer 4, and the message says which type was expected.
    const ConfigError tagged = load_error(write("b.yaml", R"(models: [stanford-bunny]
accelerators: [{name: bvh, params: {max_prims: !!str 4}}]
)"));
    EXPECT_TRUE(
        has_issue(tagged, 2, 48, "accelerators[0].bvh.max_prims", "expected an int value, got the quoted string '4'"))
        << all_issues(tagged);
}

// `{name: all, except, params}`: every structure of the comparison (not the references, not
// the slow) but those excepted, in registry order, each with its declared variants and at its
// defaults unless `params` gives some; other entries stand beside it.
TEST_F(ConfigTest, AllMeansEveryRegisteredStructureButThoseExcepted) {
    const Config c = load_config(write("a.yaml", R"(models: [stanford-bunny]
accelerators:
  - {name: bvh, params: {split: median, max_prims: 1}}
  - name: all
    except: [bvh]
    params: {wbvh: {width: 4}, kdtree: {"[max_prims, max_depth]": [[1, 20], [4, 30]]}}
    repetitions: 2
)"),
                                 registry());
    auto in_all = [](const AcceleratorInfo& info) {
        return info.table.role != StructureRole::reference && !info.table.slow;
    };
    std::vector<std::string> expected = {"bvh"};
    for (const AcceleratorInfo& info : accelerator_registry())
        if (info.name != "bvh" && in_all(info)) expected.push_back(info.name);
    std::vector<std::string> names;
    for (const AcceleratorSpec& a : c.accelerators) names.push_back(a.name);
    EXPECT_EQ(names, expected);
    for (const AcceleratorSpec& a : c.accelerators) {
        SCOPED_TRACE(a.name);
        EXPECT_EQ(a.mark.line, a.name == "bvh" ? 3 : 4);
        EXPECT_EQ(a.repetitions, a.name == "bvh" ? std::nullopt : std::optional<int>(2));
        if (a.name == "wbvh") {  // the given width replaces the declared variants
            ASSERT_EQ(a.axes.size(), 1u);
            EXPECT_EQ(a.axes[0].values, (std::vector<std::vector<std::string>>{{"4"}}));
        } else if (a.name == "kdtree") {
            ASSERT_EQ(a.axes.size(), 1u);
            EXPECT_EQ(a.axes[0].names, (std::vector<std::string>{"max_prims", "max_depth"}));
        } else if (a.name != "bvh") {
            EXPECT_TRUE(a.axes.empty());
        }
    }
    // Without `except`, every structure of the comparison, each variant its table declares
    // an axis of its own; brute force (slow) and the reference are left out.
    const Config every =
        load_config(write("b.yaml", "models: [stanford-bunny]\naccelerators: [{name: all}]\n"), registry());
    EXPECT_EQ(every.accelerators.size(),
              size_t(std::count_if(accelerator_registry().begin(), accelerator_registry().end(), in_all)));
    for (const AcceleratorSpec& a : every.accelerators) {
        SCOPED_TRACE(a.name);
        EXPECT_NE(a.name, "brute_force");
        EXPECT_NE(a.name, "reference");
        const auto& variants = find_accelerator(a.name)->table.variants;
        ASSERT_EQ(a.axes.size(), variants.size());
        for (size_t i = 0; i < variants.size(); ++i) {
            EXPECT_EQ(a.axes[i].names, std::vector<std::string>{variants[i].param});
            EXPECT_EQ(a.axes[i].values.size(), variants[i].values.size());
        }
    }
}

TEST_F(ConfigTest, AllRefusesUnknownNamesNamingTheKnownOnes) {
    const ConfigError e = load_error(write("a.yaml", R"(models: [stanford-bunny]
accelerators:
  - {name: all, except: [bhv, embree, embree], params: {kdtre: {max_prims: 2}, embree: {robust: true}}}
  - {name: all, params: {kdtree: {max_prim: 2}}}
  - {name: kdtree, except: [bvh]}
  - {name: al}
  - {name: all, except: [brute_force]}
)"));
    EXPECT_TRUE(has_issue(e, 3, 26, "accelerators[0].except[0]", "unknown accelerator 'bhv' (did you mean 'bvh'?)"));
    EXPECT_TRUE(has_issue(e, 3, 39, "accelerators[0].except[2]", "'embree' is excepted twice"));
    EXPECT_TRUE(
        has_issue(e, 3, 57, "accelerators[0].params.kdtre", "unknown accelerator 'kdtre' (did you mean 'kdtree'?)"));
    EXPECT_TRUE(has_issue(e, 3, 80, "accelerators[0].params.embree", "'embree' is in `except`"));
    EXPECT_TRUE(has_issue(e, 4, 35, "accelerators[1].kdtree.max_prim", "did you mean 'max_prims'"));
    EXPECT_TRUE(has_issue(e, 5, 20, "accelerators[2].except", "`except` goes with `name: all`"));
    EXPECT_TRUE(has_issue(e, 6, 12, "accelerators[3].name", "unknown accelerator 'al' (did you mean 'all'?)"));
    EXPECT_TRUE(has_issue(e, 7, 26, "accelerators[4].except[0]", "'brute_force' is not in `all` (slow"));
    EXPECT_EQ(e.issues().size(), 8u) << all_issues(e);

    std::string every;
    for (const AcceleratorInfo& info : accelerator_registry())
        if (info.table.role != StructureRole::reference && !info.table.slow)
            every += (every.empty() ? "" : ", ") + info.name;
    const ConfigError none =
        load_error(write("b.yaml", "models: [stanford-bunny]\naccelerators: [{name: all, except: [" + every + "]}]\n"));
    EXPECT_TRUE(has_issue(none, 2, 36, "accelerators[0].except", "every structure is excepted"));
}

// An explicit entry beside `all` that names the same setting is the same combination twice.
TEST_F(ConfigTest, AllBesideAnEntryOfTheSameStructureRepeatsItsCombinations) {
    const Config c = load_config(
        write("a.yaml", "models: [stanford-bunny]\naccelerators: [{name: embree}, {name: all}]\n"), registry());
    try {
        expand(c);
        FAIL() << "expected the repeated embree combination to be refused";
    } catch (const ConfigError& e) {
        EXPECT_TRUE(has_issue(e, 2, 32, "accelerators[1] (all: embree)", "repeats")) << all_issues(e);
    }
}

TEST_F(ConfigTest, DuplicateKeysAreFoundInEveryMapping) {
    // yaml-cpp 0.7 accepts both and lookups see the first: the loader must walk the entries.
    const ConfigError e = load_error(write("a.yaml", R"(models: [stanford-bunny]
accelerators: [{name: embree, name: brute_force}]
models: [igea]
)"));
    EXPECT_TRUE(has_issue(e, 2, 31, "accelerators[0].name", "duplicate key 'name' (first given at line 2, column 17)"));
    EXPECT_TRUE(has_issue(e, 3, 1, "models", "duplicate key 'models'"));
}

TEST_F(ConfigTest, MissingKeysAreReportedAtTheirMapping) {
    // yaml-cpp has no mark for a key that is not there: the mapping's mark stands in.
    const ConfigError e =
        load_error(write("a.yaml", "models: [stanford-bunny]\naccelerators:\n  - params: {threads: 1}\n"));
    EXPECT_TRUE(has_issue(e, 3, 5, "accelerators[0].name", "missing key 'name'"));
    const ConfigError top = load_error(write("b.yaml", "name: x\nmodels: [igea]\n"));
    EXPECT_TRUE(has_issue(top, 1, 1, "accelerators", "missing key 'accelerators'"));
}

TEST_F(ConfigTest, MissingModels) {
    const ConfigError e = load_error(write("a.yaml", R"(models:
  - stanford-bunni
  - {path: nowhere.obj}
  - {procedural: forrest}
  - {procedural: soup, triangles: 0, colour: red}
accelerators: [{name: embree}]
)"));
    EXPECT_EQ(e.issues().size(), 5u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 2, 5, "models[0]", "unknown model 'stanford-bunni'"));
    EXPECT_TRUE(has_issue(e, 3, 12, "models[1].path", "no such mesh file"));
    EXPECT_TRUE(has_issue(e, 4, 18, "models[2].procedural", "unknown procedural scene 'forrest'"));
    EXPECT_TRUE(has_issue(e, 5, 35, "models[3].triangles", "out of range"));
    EXPECT_TRUE(has_issue(e, 5, 38, "models[3].colour", "procedural scene 'soup' has no parameter 'colour'"));
}

// A directory or a FIFO named as a mesh is there but cannot be read as one: the config
// says so, rather than calling it missing.
TEST_F(ConfigTest, AMeshPathThatIsNotARegularFile) {
    std::filesystem::create_directory(dir.path() / "folder.obj");
    ASSERT_EQ(mkfifo((dir.path() / "pipe.ply").c_str(), 0600), 0);
    const ConfigError e =
        load_error(write("a.yaml", "models: [{path: folder.obj}, {path: pipe.ply}]\naccelerators: [{name: embree}]\n"));
    EXPECT_EQ(e.issues().size(), 2u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 1, 17, "models[0].path", "not a regular file (a mesh file is needed)")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 1, 37, "models[1].path", "not a regular file (a mesh file is needed)")) << all_issues(e);
}

TEST_F(ConfigTest, ModelTransformsMakeDistinctModels) {
    const Config c = load_config(write("scaling.yaml", R"(models:
  - stanford-dragon
  - {name: stanford-dragon, decimate: 100000}
  - {name: stanford-dragon, decimate: 10000, repetitions: 1}
  - {name: stanford-bunny, subdivide: 2}
accelerators: [{name: embree}]
)"),
                                 registry());
    ASSERT_EQ(c.models.size(), 4u);
    EXPECT_FALSE(c.models[0].transform);
    EXPECT_EQ(c.models[1].label, "stanford-dragon@decimate=100000");
    ASSERT_TRUE(c.models[1].transform);
    EXPECT_EQ(c.models[1].transform->kind, ModelTransformSpec::Kind::Decimate);
    EXPECT_EQ(c.models[1].transform->amount, 100000u);
    EXPECT_EQ(c.models[2].label, "stanford-dragon@decimate=10000");
    EXPECT_EQ(c.models[2].repetitions, 1);
    EXPECT_EQ(c.models[3].label, "stanford-bunny@subdivide=2");
    EXPECT_EQ(c.models[3].transform->kind, ModelTransformSpec::Kind::Subdivide);
    EXPECT_EQ(c.models[3].transform->amount, 2u);
    // Every size is its own model: distinct keys, so distinct combination ids.
    EXPECT_NE(c.models[0].key, c.models[1].key);
    EXPECT_NE(c.models[1].key, c.models[2].key);
}

TEST_F(ConfigTest, ModelTransformErrors) {
    write_triangle_case(dir.path());
    const ConfigError e = load_error(write("a.yaml", R"(models:
  - {name: stanford-bunny, decimate: 69451}
  - {name: stanford-bunny, subdivide: 5}
  - {name: igea, decimate: 1000, subdivide: 1}
  - {path: tri.obj, decimate: 1}
  - {name: stanford-dragon, decimate: "1000"}
accelerators: [{name: embree}]
)"));
    EXPECT_EQ(e.issues().size(), 5u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 2, 38, "models[0].decimate", "out of range [1, 69450]"));
    EXPECT_TRUE(has_issue(e, 3, 39, "models[1].subdivide", "out of range [1, 4]"));
    EXPECT_TRUE(has_issue(e, 4, 34, "models[2].subdivide", "not both"));
    EXPECT_TRUE(has_issue(e, 5, 21, "models[3].decimate", "unknown key 'decimate'"));
    EXPECT_TRUE(has_issue(e, 6, 39, "models[4].decimate", "expected an integer"));
}

TEST_F(ConfigTest, ZippedGroupErrors) {
    const ConfigError e = load_error(write("a.yaml", R"(models: [stanford-bunny]
accelerators:
  - name: brute_force
    params:
      "[max_triangles, force]": [[100, true], [200]]
      max_triangles: 5
)"));
    EXPECT_TRUE(
        has_issue(e, 5, 47, "accelerators[0].brute_force.[max_triangles, force][1]", "expected a tuple of 2 values"));
    EXPECT_TRUE(has_issue(e, 6, 7, "accelerators[0].brute_force.max_triangles", "given twice"));
}

TEST_F(ConfigTest, WrongTypesAndRangesInSettings) {
    const ConfigError e = load_error(write("a.yaml", R"(render: {width: 0, height: 12.5, light: maybe, shading: [true]}
models: [stanford-bunny]
accelerators: [{name: embree}]
)"));
    EXPECT_EQ(e.issues().size(), 4u) << all_issues(e);
    const ConfigError mode = load_error(write("b.yaml", R"(render: {fp_mode: ftz}
models: [stanford-bunny]
accelerators: [{name: embree}]
)"));
    EXPECT_TRUE(has_issue(mode, 1, 19, "render.fp_mode", "unknown fp_mode 'ftz'")) << all_issues(mode);
    EXPECT_NE(all_issues(mode).find("(known: ieee, ftz_daz)"), std::string::npos) << all_issues(mode);
    EXPECT_TRUE(has_issue(e, 1, 17, "render.width", "value 0 is out of range [1, 16384]"));
    EXPECT_TRUE(has_issue(e, 1, 28, "render.height", "expected an integer"));
    EXPECT_TRUE(has_issue(e, 1, 41, "render.light", "expected true or false, got 'maybe'"));
    EXPECT_TRUE(has_issue(e, 1, 57, "render.shading", "expected true or false, got a list"));
    // Quoted, a word read as a bool unquoted is named as the string it is.
    EXPECT_TRUE(has_issue(load_error(write("q.yaml",
                                           "render: {light: \"yes\"}\nmodels: [stanford-bunny]\n"
                                           "accelerators: [{name: embree}]\n")),
                          1, 17, "render.light", "expected true or false, got the string 'yes'"));
}

TEST_F(ConfigTest, CameraErrors) {
    write_triangle_case(dir.path());
    const ConfigError e = load_error(write("a.yaml", R"(models:
  - {path: tri.obj, camera: {look_at: [0, 0, 0], fov: 180}}
  - {path: tri.obj, label: b, camera: {eye: [1, 2, 3], look_at: [1, 2, 3]}}
accelerators: [{name: embree}]
)"));
    EXPECT_TRUE(has_issue(e, 2, 29, "models[0].camera.eye", "missing key 'eye'"));
    EXPECT_TRUE(has_issue(e, 2, 55, "models[0].camera.fov", "out of range (0, 179]"));
    EXPECT_TRUE(has_issue(e, 3, 39, "models[1].camera", "eye and look_at are the same point"));
}

TEST_F(ConfigTest, SkipRuleErrors) {
    const ConfigError e = load_error(write("a.yaml", R"(models: [stanford-bunny]
accelerators: [{name: embree}]
skip:
  - {accel: brute_force, triangles_above: 10}
  - {accel: octree, reason: x}
  - {model: igea, reason: y}
  - {params: {quality: low}, reason: z}
)"));
    EXPECT_EQ(e.issues().size(), 4u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 4, 5, "skip[0].reason", "missing key 'reason'"));
    EXPECT_TRUE(has_issue(e, 5, 13, "skip[1].accel", "unknown accelerator 'octree'"));
    EXPECT_TRUE(has_issue(e, 6, 13, "skip[2].model", "matches no model of this config (stanford-bunny)"));
    EXPECT_TRUE(has_issue(e, 7, 6, "skip[3].params", "needs `accel:`"));
}

TEST_F(ConfigTest, SameModelTwiceAndSameLabelTwice) {
    write_triangle_case(dir.path());
    const ConfigError e = load_error(write("a.yaml", R"(models:
  - igea
  - igea
  - {path: tri.obj}
  - {path: tri.obj, rays: {file: tri.rays.csv}}
accelerators: [{name: embree}]
)"));
    EXPECT_TRUE(has_issue(e, 3, 5, "models[1]", "the same model as models[0]"));
    EXPECT_TRUE(has_issue(e, 5, 5, "models[3]", "the same label 'tri.obj' as models[2]"));
}

TEST_F(ConfigTest, YamlSyntaxErrorHasItsPosition) {
    const ConfigError e = load_error(write("a.yaml", "models: [stanford-bunny\naccelerators: 3\n"));
    ASSERT_EQ(e.issues().size(), 1u);
    EXPECT_EQ(e.issues()[0].mark.line, 2);
    EXPECT_NE(e.issues()[0].message.find("YAML syntax error"), std::string::npos);
}

TEST_F(ConfigTest, BadRayFileLinesNameTheRayFile) {
    write_triangle_case(dir.path());
    const std::string rays =
        write("bad.rays.csv", "ox,oy,oz,dx,dy,dz,tmax\n0,0,1,0,0,-1,5\n0,0,1,0,0\n0,0,1,0,x,-1,5\n");
    const ConfigError e = load_error(write("a.yaml",
                                           "models: [{path: tri.obj, rays: {file: bad.rays.csv}}]\n"
                                           "accelerators: [{name: embree}]\n"));
    ASSERT_EQ(e.issues().size(), 2u) << all_issues(e);
    EXPECT_EQ(e.issues()[0].mark.file, rays);
    EXPECT_TRUE(has_issue(e, 3, 1, "models[0].rays.file", "expected 7 comma-separated numbers, got 5"));
    EXPECT_TRUE(has_issue(e, 4, 9, "models[0].rays.file", "field 5 is not a number: 'x'"));
}

// A value is read as written, inf and nan included; one that is no float (1e-50 became a
// zero direction, 1e999 an infinite origin: every row's answer far from the cause) or a
// hexadecimal float (strtof's 0x1) is named at its line and column.
TEST_F(ConfigTest, RayFileValuesThatAreNoFloatAreNamed) {
    write_triangle_case(dir.path());
    write("f.rays.csv",
          "ox,oy,oz,dx,dy,dz\n0,0,1,0,0,-1e-50\n1e999,0,1,0,0,-1\n0,0,0x1,0,0,-1\n0,0,1,-inf,nan,-1\n"
          "0,0,1,0,-0,-1.5e-3\n");
    const ConfigError e = load_error(write("a.yaml",
                                           "models: [{path: tri.obj, rays: {file: f.rays.csv}}]\n"
                                           "accelerators: [{name: embree}]\n"));
    EXPECT_EQ(e.issues().size(), 3u) << all_issues(e);
    EXPECT_TRUE(
        has_issue(e, 2, 11, "models[0].rays.file", "field 6: value -1e-50 does not survive conversion to float"))
        << all_issues(e);
    EXPECT_TRUE(has_issue(e, 3, 1, "models[0].rays.file", "field 1: value 1e999 is beyond the float range"))
        << all_issues(e);
    EXPECT_TRUE(has_issue(e, 4, 5, "models[0].rays.file", "field 3: '0x1' is hexadecimal")) << all_issues(e);
}

TEST_F(ConfigTest, RayFileNeedsItsHeader) {
    write_triangle_case(dir.path());
    write("nohead.rays.csv", "0,0,1,0,0,-1\n");
    const ConfigError e = load_error(write("a.yaml",
                                           "models: [{path: tri.obj, rays: {file: nohead.rays.csv}}]\n"
                                           "accelerators: [{name: embree}]\n"));
    EXPECT_TRUE(has_issue(e, 1, 1, "models[0].rays.file", "expected the header 'ox,oy,oz,dx,dy,dz'"));
}

// ---- YAML forms people write: accepted, or refused naming the form ----------------------

TEST_F(ConfigTest, Yaml12CoreBooleansAreAccepted) {
    const Config c = load_config(write("b.yaml", R"(errors: False
render: {light: TRUE, shading: True}
models: [igea]
accelerators: [{name: embree, params: {robust: FALSE}}]
)"),
                                 registry());
    EXPECT_FALSE(c.errors);
    EXPECT_TRUE(c.render.light);
    EXPECT_TRUE(c.render.shading);
    ASSERT_EQ(c.accelerators.size(), 1u);
}

TEST_F(ConfigTest, MergeKeysAreAccepted) {
    const Config c = load_config(write("m.yaml", R"(models:
  - &bunny {name: stanford-bunny, repetitions: 2}
  - {<<: *bunny, label: bunny-3, repetitions: 3, camera: {eye: [0, 0, 5], look_at: [0, 0, 0]}}
accelerators:
  - &kd {name: kdtree, repetitions: 4}
  - {<<: [*kd], params: {max_prims: 8}}
)"),
                                 registry());
    ASSERT_EQ(c.models.size(), 2u);
    EXPECT_EQ(c.models[1].name, "stanford-bunny");
    EXPECT_EQ(c.models[1].label, "bunny-3");
    EXPECT_EQ(c.models[1].repetitions, 3);  // its own key wins over the merged one
    ASSERT_EQ(c.accelerators.size(), 2u);
    EXPECT_EQ(c.accelerators[1].name, "kdtree");
    EXPECT_EQ(c.accelerators[1].repetitions, 4);
    // A merged key that is not allowed is named as merged; a merge of a scalar is named.
    // Only these: a mapping whose merge failed is not also said to lack `name`, or to need
    // exactly one of name/path/procedural/case.
    const ConfigError e = load_error(write("n.yaml", R"(models: [igea, {<<: 3, seed: 2}]
accelerators:
  - &x {name: kdtree, colour: red}
  - {<<: 3}
)"));
    EXPECT_EQ(e.issues().size(), 3u) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 1, 21, "models[1].<<", "a merge key ('<<') takes a mapping")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 3, 23, "accelerators[0].colour", "unknown key 'colour'")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 4, 10, "accelerators[1].<<", "a merge key ('<<') takes a mapping")) << all_issues(e);
}

TEST_F(ConfigTest, AmbiguousNumberFormsAreRefusedNamingThem) {
    const ConfigError e = load_error(write("z.yaml", R"(repetitions: 010
warmup: 0x1
timeout_s: 0x10
render: {width: !!str 64, height: 08}
ray_sets: {ao: {distance: 1e-50}}
models: [igea]
accelerators: [{name: kdtree, params: {max_prims: 0x8, traversal_cost: 007.5}}]
)"));
    EXPECT_TRUE(has_issue(e, 1, 14, "repetitions", "'010' has a leading zero")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 2, 9, "warmup", "'0x1' is hexadecimal")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 3, 12, "timeout_s", "'0x10' is hexadecimal")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 4, 17, "render.width", "expected an integer in [1, 16384], got the string '64'"))
        << all_issues(e);
    EXPECT_TRUE(has_issue(e, 4, 35, "render.height", "'08' has a leading zero")) << all_issues(e);
    EXPECT_TRUE(has_issue(e, 5, 27, "ray_sets.ao.distance", "value 1e-50 does not survive conversion to float"))
        << all_issues(e);
    EXPECT_NE(all_issues(e).find("kdtree.max_prims: '0x8' is hexadecimal"), std::string::npos) << all_issues(e);
    EXPECT_NE(all_issues(e).find("kdtree.traversal_cost: '007.5' has a leading zero"), std::string::npos)
        << all_issues(e);
}

// render.threads reaches a structure's own `threads` parameter when its entry gives none:
// every count render.threads takes is one each structure builds with (lbvh took at most 256
// of the 1024, and a config of 1024 render threads was refused through lbvh's parameter).
TEST_F(ConfigTest, EveryRenderThreadCountIsOneEveryStructureBuildsWith) {
    for (const AcceleratorInfo& info : accelerator_registry())
        for (const ParamSpec& spec : info.params)
            if (spec.name == "threads") {
                EXPECT_LE(spec.min, 1) << info.name;
                EXPECT_GE(spec.max, kMaxThreads) << info.name;
            }
    const Config c = load_config(write("t.yaml", R"(render: {threads: [1, 1024]}
models: [igea]
accelerators: [{name: embree}, {name: lbvh}]
)"),
                                 registry());
    EXPECT_EQ(c.thread_counts, (std::vector<int>{1, 1024}));
    EXPECT_TRUE(has_issue(load_error(write("u.yaml",
                                           "render: {threads: 1025}\nmodels: [igea]\naccelerators: "
                                           "[{name: lbvh}]\n")),
                          1, 19, "render.threads", "out of range [1, 1024]"));
}

// A ray CSV saved by a spreadsheet starts with a UTF-8 byte-order mark: read; UTF-16 is
// named; another invisible byte in the header is shown as \xNN.
TEST_F(ConfigTest, RayFileWithAByteOrderMark) {
    write_triangle_case(dir.path());
    write("bom.rays.csv", "\xEF\xBB\xBFox,oy,oz,dx,dy,dz\r\n0,0,5,0,0,-1\r\n");
    const Config c = load_config(write("a.yaml", R"(models: [{path: tri.obj, rays: {file: bom.rays.csv}}]
accelerators: [{name: bvh}]
)"),
                                 registry());
    ASSERT_TRUE(c.models[0].rays);
    EXPECT_EQ(c.models[0].rays->rays.size(), 1u);
    write("utf16.rays.csv", std::string("\xFF\xFEo\0x\0", 6));
    write("nbsp.rays.csv", "ox,oy,oz,dx,dy,dz\xC2\xA0\n0,0,5,0,0,-1\n");
    const ConfigError e = load_error(write("b.yaml", R"(models:
  - {path: tri.obj, rays: {file: utf16.rays.csv}}
  - {path: tri.obj, label: t2, rays: {file: nbsp.rays.csv}}
accelerators: [{name: bvh}]
)"));
    EXPECT_NE(all_issues(e).find("the ray file is UTF-16"), std::string::npos) << all_issues(e);
    EXPECT_NE(all_issues(e).find("got 'ox,oy,oz,dx,dy,dz\\xC2\\xA0'"), std::string::npos) << all_issues(e);
}

}  // namespace
}  // namespace accelbench
