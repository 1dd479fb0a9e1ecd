// `accelbench run` end to end on a config that takes a second: the CSV it writes, skip
// rules, a ray file model, errors and time limits as rows, --dry-run, and --resume after
// an interrupted run.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <map>
#include <set>

#include "commands/cli.h"
#include "csv/csv.h"
#include "csv/results.h"
#include "csv/run_inputs.h"
#include "harness_test_util.h"
#include "plan/combinations.h"
#include "plan/run_plan.h"
#include "util/output_lock.h"
#include "util/sha256.h"

namespace accelbench {
namespace {

using namespace testing_util;

int run(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    return run_command(int(argv.size()), argv.data());
}

// A results row by column key (parameter columns share header text with other columns).
std::map<std::string, std::string> as_map(const CsvData& d, size_t row) {
    const auto keys = result_columns();
    EXPECT_EQ(d.header, column_headers(keys));
    std::map<std::string, std::string> m;
    for (size_t i = 0; i < keys.size() && i < d.rows[row].size(); ++i) m[keys[i]] = d.rows[row][i];
    return m;
}

class RunTest : public ::testing::Test {
protected:
    TempDir dir{"accelbench-run-test-"};
    std::string config, out;

    void SetUp() override {
        write_triangle_case(dir.path());
        config = write_file(dir.path(), "e2e.yaml", R"(name: e2e
repetitions: 2
timeout_s: 60
render: {width: 24, height: 16}
models:
  - {procedural: soup, triangles: 1000, seed: 3}
  - {path: tri.obj, rays: {file: tri.rays.csv}, label: tri-rays}
accelerators:
  - {name: brute_force}
  - {name: embree, params: {quality: [low, high]}}
skip:
  - {accel: embree, params: {quality: high}, triangles_below: 10, reason: "tiny scene"}
)");
        out = (dir.path() / "out" / "e2e.csv").string();
    }
};

TEST_F(RunTest, WritesOneRowPerCombination) {
    ASSERT_EQ(run({config, "--out", out}), 0);
    const CsvData d = read_csv(out);
    EXPECT_EQ(d.header, column_headers(result_columns()));
    ASSERT_EQ(d.rows.size(), 6u);
    std::map<std::string, std::map<std::string, std::string>> by_name;
    for (size_t i = 0; i < d.rows.size(); ++i) {
        auto r = as_map(d, i);
        by_name[r["model"] + "/" + r["accel"] + "/" + r[param_column("quality")]] = r;
    }
    const auto& bf = by_name.at("soup(triangles=1000,seed=3)/brute_force/");
    EXPECT_EQ(bf.at("status"), "ok");
    EXPECT_EQ(bf.at("config"), "e2e");
    EXPECT_EQ(bf.at("triangles"), "1000");
    EXPECT_EQ(bf.at("params"), "max_triangles=20000;force=false");
    EXPECT_EQ(bf.at("label"), "brute force");  // the registry's display label
    EXPECT_EQ(bf.at(param_column("max_triangles")), "20000");
    EXPECT_EQ(bf.at(param_column("quality")), "");  // not a brute_force parameter
    EXPECT_EQ(bf.at("repetitions"), "2");
    EXPECT_EQ(bf.at("processes"), "1");
    EXPECT_EQ(bf.at("render_s_process_gap"), "");  // one process: no gap measured
    EXPECT_EQ(bf.at("rays"), std::to_string(24 * 16));
    EXPECT_EQ(bf.at("ray_source"), "camera");
    EXPECT_EQ(bf.at("image_width"), "24");
    EXPECT_FALSE(bf.at("build_s_median").empty());
    EXPECT_FALSE(bf.at("render_s_ci_hi").empty());
    EXPECT_EQ(bf.at("ci_coverage"), "0.5");  // two repetitions: [min, max] covers the median half the time
    EXPECT_FALSE(bf.at("prim_tests").empty());
    EXPECT_FALSE(bf.at("mrays_per_s").empty());
    EXPECT_FALSE(bf.at("git_sha").empty());
    EXPECT_EQ(bf.at("render_threads"), "1");

    const auto& em = by_name.at("soup(triangles=1000,seed=3)/embree/low");
    EXPECT_EQ(em.at("status"), "ok");
    EXPECT_EQ(em.at(param_column("threads")), "1");  // the build threads
    EXPECT_EQ(em.at("prim_tests"), "");              // Embree does not count: missing, not zero
    EXPECT_EQ(em.at("nodes"), "");

    const auto& rays = by_name.at("tri-rays/brute_force/");
    EXPECT_EQ(rays.at("status"), "ok");
    EXPECT_EQ(rays.at("ray_source"), "tri.rays.csv");
    EXPECT_EQ(rays.at("rays"), "3");
    EXPECT_EQ(rays.at("hits"), "2");  // the ray beside the triangle misses
    EXPECT_EQ(rays.at("image_width"), "");

    const auto& skipped = by_name.at("tri-rays/embree/high");
    EXPECT_EQ(skipped.at("status"), "skipped");
    EXPECT_EQ(skipped.at("label"), "Embree");  // every row has it, whatever its status
    EXPECT_EQ(skipped.at("message"), "tiny scene");
    EXPECT_EQ(skipped.at("build_s_median"), "");
    EXPECT_EQ(skipped.at("triangles"), "1");

    // Raw samples: two per measured combination.
    const CsvData reps = read_csv(repetitions_path(out));
    EXPECT_EQ(reps.rows.size(), 5u * 2u);
}

// `processes: 2`: each combination measured in two child processes, pooled into one row
// whose repetitions say which process measured them.
TEST_F(RunTest, SeveralProcessesPoolIntoOneRowWithTheirGap) {
    const std::string two = write_file(dir.path(), "two.yaml", R"(name: two
repetitions: 2
processes: 2
render: {width: 24, height: 16}
models:
  - {procedural: soup, triangles: 1000, seed: 3}
accelerators:
  - {name: brute_force}
  - {name: embree}
)");
    const std::string two_out = (dir.path() / "out" / "two.csv").string();
    ASSERT_EQ(run({two, "--out", two_out}), 0);
    const CsvData d = read_csv(two_out);
    ASSERT_EQ(d.rows.size(), 2u);
    for (size_t i = 0; i < d.rows.size(); ++i) {
        const auto r = as_map(d, i);
        EXPECT_EQ(r.at("status"), "ok") << r.at("message");
        EXPECT_EQ(r.at("repetitions"), "4");
        EXPECT_EQ(r.at("processes"), "2");
        EXPECT_EQ(r.at("ci_coverage"), "0.875");  // [min, max] of four samples
        EXPECT_FALSE(r.at("build_s_process_gap").empty());
        EXPECT_FALSE(r.at("render_s_process_gap").empty());
        EXPECT_GE(std::stod(r.at("render_s_process_gap")), 0.0);
        EXPECT_EQ(r.at("false_misses"), "0");  // the first process's error trace
    }
    const CsvData reps = read_csv(repetitions_path(two_out));
    ASSERT_EQ(reps.header, repetition_columns());
    std::map<std::string, int> per_process;
    for (const auto& row : reps.rows) ++per_process[row.back()];
    EXPECT_EQ(per_process, (std::map<std::string, int>{{"1", 4}, {"2", 4}}));
}

// `interleave`: the combinations that trace the same rays are timed in one child per
// process, and each row names the others (`timed_with`); rows of other rays are not.
TEST_F(RunTest, InterleavedRowsNameWhatTheyWereTimedWith) {
    const std::string cfg = write_file(dir.path(), "il.yaml", R"(name: il
repetitions: 2
processes: 2
interleave: true
render: {width: 24, height: 16}
ray_sets: {sets: [primary, ao], random: {rays: 100}}
models:
  - {procedural: soup, triangles: 1000, seed: 3}
accelerators:
  - {name: brute_force}
  - {name: embree}
  - {name: bvh}
)");
    const std::string il_out = (dir.path() / "out" / "il.csv").string();
    ASSERT_EQ(run({cfg, "--out", il_out}), 0);
    const CsvData d = read_csv(il_out);
    ASSERT_EQ(d.rows.size(), 6u);
    std::map<std::string, std::set<std::string>> ids_by_set;
    std::vector<std::map<std::string, std::string>> rows;
    for (size_t i = 0; i < d.rows.size(); ++i) {
        rows.push_back(as_map(d, i));
        ids_by_set[rows.back().at("ray_set")].insert(rows.back().at("combo_id"));
    }
    for (const auto& r : rows) {
        EXPECT_EQ(r.at("status"), "ok") << r.at("message");
        EXPECT_EQ(r.at("processes"), "2");
        EXPECT_EQ(r.at("repetitions"), "4");
        EXPECT_EQ(r.at("false_misses"), "0");
        EXPECT_EQ(r.at("peak_rss_bytes"), "");  // the group's process held all three
        std::set<std::string> others = ids_by_set.at(r.at("ray_set"));
        others.erase(r.at("combo_id"));
        std::string expected;
        for (const std::string& id : others) expected += (expected.empty() ? "" : ";") + id;
        EXPECT_EQ(r.at("timed_with"), expected);
    }
}

// Every row says how wrong it is: the error columns against the reference.
TEST_F(RunTest, ErrorColumnsCompareEachCombinationWithTheReference) {
    ASSERT_EQ(run({config, "--out", out}), 0);
    const CsvData d = read_csv(out);
    for (size_t i = 0; i < d.rows.size(); ++i) {
        auto r = as_map(d, i);
        if (r["status"] != "ok") {
            EXPECT_EQ(r["false_misses"], "");
            continue;
        }
        // Brute force and Embree agree with the exact reference on these clean scenes.
        for (const char* col : {"false_misses", "false_hits", "prim_mismatches", "nan_results"})
            EXPECT_EQ(r[col], "0") << r["model"] << " " << r["accel"] << " " << col;
        EXPECT_FALSE(r["t_err_ulp_max"].empty());
        EXPECT_EQ(r["image_rmse"], "");  // shading is off: no image to compare
        EXPECT_EQ(r["hole_pixels"], "");
        EXPECT_GT(std::stoull(r["peak_rss_bytes"]), 1u << 20) << "the measuring process holds at least a MiB";
        EXPECT_EQ(r["verdict"], "");
    }
}

TEST_F(RunTest, ImageRunsCompareImagesAndErrorsFalseTurnsItOff) {
    const std::string shaded = write_file(dir.path(), "shaded.yaml", R"(name: shaded
repetitions: 1
render: {width: 24, height: 16, shading: true}
models: [{procedural: forest, triangles: 2000}]
accelerators: [{name: bvh}, {name: kdtree}]
)");
    ASSERT_EQ(run({shaded, "--out", out}), 0);
    CsvData d = read_csv(out);
    ASSERT_EQ(d.rows.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        auto r = as_map(d, i);
        EXPECT_EQ(r["hole_pixels"], "0") << r["accel"];
        EXPECT_LT(std::stod(r["image_rmse"]), 0.01) << r["accel"];
    }
    const std::string off = write_file(dir.path(), "off.yaml", read_file(shaded) + "errors: false\n");
    const std::string out2 = (dir.path() / "off.csv").string();
    ASSERT_EQ(run({off, "--out", out2}), 0);
    d = read_csv(out2);
    for (size_t i = 0; i < d.rows.size(); ++i) {
        auto r = as_map(d, i);
        EXPECT_EQ(r["status"], "ok");
        for (const char* col : {"false_misses", "t_err_ulp_p50", "image_rmse", "hole_pixels"})
            EXPECT_EQ(r[col], "") << col;
        EXPECT_FALSE(r["peak_rss_bytes"].empty());
    }
}

// Robustness cases are judged, not timed, and the run ends with the verdict table.
TEST_F(RunTest, RobustnessCasesGetVerdictsAndATable) {
    const std::string cfg = write_file(dir.path(), "cases.yaml", R"(name: cases
timeout_s: 60
models: [{case: "1"}, {case: 14a}, {case: "17"}]
accelerators: [{name: brute_force}, {name: bvh}, {name: kdtree, params: {max_prims: 1, max_depth: 100}}]
)");
    ::testing::internal::CaptureStdout();
    const int rc = run({cfg, "--out", out});
    const std::string table = ::testing::internal::GetCapturedStdout();
    ASSERT_EQ(rc, 0);
    const CsvData d = read_csv(out);
    ASSERT_EQ(d.rows.size(), 9u);
    std::map<std::string, std::map<std::string, std::string>> by;
    for (size_t i = 0; i < d.rows.size(); ++i) {
        auto r = as_map(d, i);
        by[r["model"] + "/" + r["accel"]] = r;
        EXPECT_EQ(r["status"], "ok") << r["message"];
        EXPECT_EQ(r["verdict"], "pass") << r["model"] << " " << r["accel"] << ": " << r["verdict_counts"];
        EXPECT_EQ(r["ray_source"], "robustness-case");
        EXPECT_EQ(r["build_s_median"], "");  // judged, not timed
        EXPECT_EQ(r["image_width"], "");
        EXPECT_FALSE(r["peak_rss_bytes"].empty());
    }
    const auto& closed = by.at("case-1:closed-meshes/bvh");
    EXPECT_EQ(closed.at("false_misses"), "0");  // watertight: no leaks, as the reference
    EXPECT_NE(closed.at("verdict_counts").find("leaks=0 "), std::string::npos);
    EXPECT_EQ(closed.at("tree_depth"),
              closed.at("verdict_counts")
                  .substr(closed.at("verdict_counts").find("depth=") + 6, closed.at("tree_depth").size()));
    const auto& nan = by.at("case-14a:nan-vertex/kdtree");
    EXPECT_NE(nan.at("message").find("rejected at load"), std::string::npos) << nan.at("message");
    EXPECT_EQ(nan.at("false_misses"), "");  // nothing was traced
    // Far from the scene the float triangle test and the exact reference can disagree near
    // edges; every structure of ours runs the same test, so all disagree alike.
    const auto& far = by.at("case-17:distant-camera/brute_force");
    for (const char* accel : {"bvh", "kdtree"})
        for (const char* col : {"false_misses", "false_hits", "prim_mismatches", "t_err_ulp_max"})
            EXPECT_EQ(by.at(std::string("case-17:distant-camera/") + accel).at(col), far.at(col))
                << accel << " " << col;

    EXPECT_NE(table.find("Robustness verdicts"), std::string::npos) << table;
    EXPECT_NE(table.find("[3] kdtree:max_depth=100,max_prims=1"), std::string::npos) << table;
    EXPECT_NE(table.find("case-14a:nan-vertex"), std::string::npos) << table;
    EXPECT_NE(table.find("9 pass"), std::string::npos) << table;
}

// render.fp_mode is recorded in every row and is part of the combination's identity, but
// never of the robustness cases', which are judged in IEEE mode whatever it says.
TEST_F(RunTest, TheFloatingPointModeIsInEveryRowAndCasesStayIeee) {
    const std::string models = R"(
repetitions: 1
models: [{procedural: soup, triangles: 500, seed: 2}, {case: 3b}]
accelerators: [{name: bvh}, {name: wbvh}]
)";
    const std::string flushed =
        write_file(dir.path(), "ftz.yaml", "name: fp\nrender: {width: 24, height: 16, fp_mode: ftz_daz}" + models);
    const std::string ieee =
        write_file(dir.path(), "ieee.yaml", "name: fp\nrender: {width: 24, height: 16, fp_mode: ieee}" + models);
    const std::string out_ieee = (dir.path() / "ieee.csv").string();
    ASSERT_EQ(run({flushed, "--out", out}), 0);
    ASSERT_EQ(run({ieee, "--out", out_ieee}), 0);
    const CsvData f = read_csv(out), i = read_csv(out_ieee);
    ASSERT_EQ(f.rows.size(), 4u);
    ASSERT_EQ(i.rows.size(), 4u);
    for (size_t k = 0; k < 4; ++k) {
        auto a = as_map(f, k), b = as_map(i, k);
        ASSERT_EQ(a["model"] + a["accel"], b["model"] + b["accel"]);
        EXPECT_EQ(a["status"], "ok") << a["message"];
        EXPECT_EQ(b["fp_mode"], "ieee");
        if (a["ray_source"] == "robustness-case") {
            EXPECT_EQ(a["fp_mode"], "ieee") << a["model"];
            EXPECT_EQ(a["verdict"], "pass") << a["model"] << " " << a["accel"] << ": " << a["verdict_counts"];
            EXPECT_EQ(a["combo_id"], b["combo_id"]);
            continue;
        }
        EXPECT_EQ(a["fp_mode"], "ftz_daz") << a["accel"];
        EXPECT_NE(a["combo_id"], b["combo_id"]) << a["accel"];
        // The same answers as the (IEEE) reference, and the same counts as in IEEE mode.
        for (const char* col : {"false_misses", "false_hits", "prim_mismatches", "nan_results"})
            EXPECT_EQ(a[col], "0") << a["accel"] << " " << col;
        for (const char* col : {"hits", "shadow_hits", "prim_tests", "node_visits", "t_err_ulp_max"})
            EXPECT_EQ(a[col], b[col]) << a["accel"] << " " << col;
    }
}

// Bad input is exit code 2 and leaves no row that could be taken for a result.
TEST_F(RunTest, AModelThatDoesNotLoadWritesNoRowsAndIsExitCode2) {
    write_file(dir.path(), "empty.obj", "v 0 0 0\nv 1 0 0\n");
    write_file(dir.path(), "corrupt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    write_file(dir.path(), "nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    const std::string cfg = write_file(dir.path(), "bad-input.yaml", R"(name: bad-input
repetitions: 1
render: {width: 8, height: 8}
models: [{path: empty.obj}, {procedural: soup, triangles: 1000}, {path: corrupt.obj}, {path: nan.obj}]
accelerators: [{name: bvh}, {name: embree}]
)");
    ::testing::internal::CaptureStderr();
    const int rc = run({cfg, "--out", out});
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(rc, 2);
    const CsvData d = read_csv(out);
    ASSERT_EQ(d.rows.size(), 2u);  // the soup's
    for (size_t i = 0; i < 2; ++i) EXPECT_EQ(as_map(d, i)["model"], "soup(triangles=1000)");
    EXPECT_NE(err.find("cannot load empty.obj"), std::string::npos) << err;
    // The place and the cause as the file has them: OBJ's line, face and vertex numbers.
    EXPECT_NE(err.find("corrupt.obj': line 4: face 1 refers to vertex 9 but the file has 3 vertices"),
              std::string::npos)
        << err;
    EXPECT_NE(err.find("nan.obj': line 3: vertex 3: a coordinate is not finite"), std::string::npos) << err;
    EXPECT_NE(err.find("6 combinations not run and not written: 3 models did not load"), std::string::npos) << err;
}

TEST_F(RunTest, ResumeAfterAnInterruptedRunMeasuresEachCombinationOnce) {
    ASSERT_EQ(run({config, "--out", out}), 0);
    const std::string full = read_file(out);
    const CsvData complete = read_csv(out);
    // Keep the header, two rows and half of the third: a run killed while writing.
    size_t cut = 0;
    for (int lines = 0; lines < 3; ++lines) cut = full.find('\n', cut) + 1;
    const size_t third_end = full.find('\n', cut);
    write_file(dir.path() / "out", "e2e.csv", full.substr(0, cut + (third_end - cut) / 2));

    EXPECT_NE(run({config, "--out", out}), 0);  // refuses to overwrite without --resume
    ASSERT_EQ(run({config, "--out", out, "--resume"}), 0);
    const CsvData d = read_csv(out);
    EXPECT_FALSE(d.incomplete_tail);
    std::multiset<std::string> ids;
    const size_t id = std::find(d.header.begin(), d.header.end(), "combo_id") - d.header.begin();
    for (const auto& r : d.rows) ids.insert(r[id]);
    std::set<std::string> expected;
    for (const auto& r : complete.rows) expected.insert(r[id]);
    EXPECT_EQ(ids.size(), expected.size());
    EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()), expected);
    // The first two rows were kept as they were.
    EXPECT_EQ(d.rows[0], complete.rows[0]);
    EXPECT_EQ(d.rows[1], complete.rows[1]);
    // Repetition rows: two per measured combination, none twice.
    const CsvData reps = read_csv(repetitions_path(out));
    std::map<std::string, int> per_combo;
    for (const auto& r : reps.rows) ++per_combo[r[1]];
    EXPECT_EQ(per_combo.size(), 5u);
    for (const auto& [combo, n] : per_combo) EXPECT_EQ(n, 2) << combo;

    // Resuming a finished run measures nothing.
    ASSERT_EQ(run({config, "--out", out, "--resume"}), 0);
    EXPECT_EQ(read_csv(out).rows.size(), expected.size());
}

// A run's identity is its inputs' contents, not their names: a results file is continued
// only from the config and files its rows were measured from.
TEST_F(RunTest, ResumeRefusesInputsThatChangedUnderTheSameNames) {
    ASSERT_EQ(run({config, "--out", out}), 0);
    const auto recorded = read_inputs(out);
    ASSERT_TRUE(recorded);
    EXPECT_EQ(*recorded,
              (RunInputs{{"config", sha256_file(config), "e2e"},
                         {"model", sha256_file((dir.path() / "tri.obj").string()), "tri-rays"},
                         {"rays", sha256_file((dir.path() / "tri.rays.csv").string()), "tri.rays.csv"}}));
    const std::string mesh = read_file((dir.path() / "tri.obj").string());
    auto refused = [&](const std::string& said) {
        ::testing::internal::CaptureStderr();
        EXPECT_EQ(run({config, "--out", out, "--resume"}), 2);
        const std::string err = ::testing::internal::GetCapturedStderr();
        EXPECT_NE(err.find("measured from other inputs"), std::string::npos) << err;
        EXPECT_NE(err.find(said), std::string::npos) << err;
    };
    // The same mesh name with another triangle in it.
    write_file(dir.path(), "tri.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
    refused("model tri-rays: sha256 ");
    write_file(dir.path(), "tri.obj", mesh);
    // The same config name with other contents.
    const std::string text = read_file(config);
    write_file(dir.path(), "e2e.yaml", text + "errors: false\n");
    refused("config e2e: sha256 ");
    write_file(dir.path(), "e2e.yaml", text);
    const size_t rows = read_csv(out).rows.size();
    EXPECT_EQ(run({config, "--out", out, "--resume"}), 0);  // the same contents again
    EXPECT_EQ(read_csv(out).rows.size(), rows);

    // Rows without a record (an older build's) cannot be compared: refused.
    remove_inputs(out);
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(run({config, "--out", out, "--resume"}), 2);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("no record of the inputs"), std::string::npos) << err;
}

// A mesh file replaced while a run goes on: the model's rows are refused, not measured
// from a file the record does not name.
TEST_F(RunTest, AModelFileReplacedAfterPlanningIsNotMeasured) {
    RunOptions options;
    options.config_path = config;
    const RunPlan plan = plan_run(options);
    const ModelSpec& tri = plan.config.models[1];
    EXPECT_EQ(model_file_changed(plan, tri), "");
    EXPECT_EQ(model_file_changed(plan, plan.config.models[0]), "");  // procedural: made by the code
    write_file(dir.path(), "tri.obj", "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\n");
    EXPECT_NE(model_file_changed(plan, tri).find("changed since the run started"), std::string::npos);
}

TEST_F(RunTest, DryRunPrintsTheInputsARunRecords) {
    ::testing::internal::CaptureStdout();
    ASSERT_EQ(run({config, "--dry-run"}), 0);
    const std::string text = ::testing::internal::GetCapturedStdout();
    EXPECT_NE(text.find("  config " + sha256_file(config) + " e2e\n"), std::string::npos) << text;
    EXPECT_NE(text.find("  rays   " + sha256_file((dir.path() / "tri.rays.csv").string()) + " tri.rays.csv\n"),
              std::string::npos)
        << text;
    EXPECT_FALSE(std::filesystem::exists(inputs_path(out)));
}

TEST_F(RunTest, ShardsTogetherGiveTheWholeRunAndMergeBack) {
    std::vector<std::string> parts;
    for (int i = 0; i < 3; ++i) {
        parts.push_back((dir.path() / ("shard" + std::to_string(i) + ".csv")).string());
        ASSERT_EQ(run({config, "--out", parts.back(), "--shard", std::to_string(i) + "/3"}), 0);
    }
    const std::string merged = (dir.path() / "merged.csv").string();
    std::vector<std::string> args = {merged};
    args.insert(args.end(), parts.begin(), parts.end());
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    ASSERT_EQ(merge_command(int(argv.size()), argv.data()), 0);
    const CsvData d = read_csv(merged);
    EXPECT_EQ(d.rows.size(), 6u);
}

int merge(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    return merge_command(int(argv.size()), argv.data());
}

TEST_F(RunTest, MergeWithTheConfigNamesTheMissingShardsAndWritesNothing) {
    std::vector<std::string> parts;
    for (int i = 0; i < 3; ++i) {
        parts.push_back((dir.path() / ("shard" + std::to_string(i) + ".csv")).string());
        ASSERT_EQ(run({config, "--out", parts.back(), "--shard", std::to_string(i) + "/3"}), 0);
    }
    // Which shard holds what, from the combinations themselves (not from the files).
    std::map<uint64_t, size_t> per_shard;
    for (const auto& c : expand(load_config(config, ModelRegistry::load_default()))) ++per_shard[c.hash % 3];
    const uint64_t lost = per_shard.begin()->first;  // a non-empty shard
    std::vector<std::string> rest;
    for (uint64_t i = 0; i < 3; ++i)
        if (i != lost) rest.push_back(parts[i]);

    const std::string merged = (dir.path() / "merged.csv").string();
    testing::internal::CaptureStderr();
    EXPECT_EQ(merge({"--config", config, "--shards", "3", merged, rest[0], rest[1]}), 3);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find(std::to_string(per_shard.begin()->second) + " of the 6 combinations"), std::string::npos) << err;
    EXPECT_NE(err.find("shard " + std::to_string(lost) + ": "), std::string::npos) << err;
    EXPECT_NE(err.find("--array=" + std::to_string(lost) + ")"), std::string::npos) << err;
    EXPECT_FALSE(std::filesystem::exists(merged));

    // A row of another config is refused too; all shards of this one merge.
    const std::string other = write_file(dir.path(), "other.yaml", R"(name: other
render: {width: 24, height: 16}
models: [{procedural: soup, triangles: 500, seed: 3}]
accelerators: [{name: brute_force}]
)");
    EXPECT_EQ(merge({"--config", other, merged, parts[0], parts[1], parts[2]}), 2);
    EXPECT_FALSE(std::filesystem::exists(merged));
    EXPECT_EQ(merge({"--config", config, "--shards", "3", merged, parts[0], parts[1], parts[2]}), 0);
    EXPECT_EQ(read_csv(merged).rows.size(), 6u);
}

// Shards of one config name measured from different contents, shards of different configs,
// and a shard a run is still writing are refused, with and without --config.
TEST_F(RunTest, MergeRefusesShardsOfOtherContentsOtherConfigsAndOneStillWritten) {
    const std::string a = (dir.path() / "a.csv").string(), b = (dir.path() / "b.csv").string();
    const std::string merged = (dir.path() / "merged.csv").string();
    ASSERT_EQ(run({config, "--out", a, "--shard", "0/2"}), 0);
    const std::string text = read_file(config);
    write_file(dir.path(), "e2e.yaml", text + "errors: false\n");  // same name, other contents
    ASSERT_EQ(run({config, "--out", b, "--shard", "1/2"}), 0);
    auto refused = [&](std::vector<std::string> args, int rc, const std::string& said) {
        ::testing::internal::CaptureStderr();
        EXPECT_EQ(merge(args), rc);
        const std::string err = ::testing::internal::GetCapturedStderr();
        EXPECT_NE(err.find(said), std::string::npos) << err;
        EXPECT_FALSE(std::filesystem::exists(merged));
    };
    refused({merged, a, b}, 2, "were measured from different inputs (config e2e: sha256 ");
    refused({"--config", config, "--shards", "2", merged, a, b}, 2, "measured from other contents than");
    // Merged anyway on request, the output then has no record: its contents are unknown.
    EXPECT_EQ(merge({"--allow-mixed", merged, a, b}), 0);
    EXPECT_FALSE(read_inputs(merged));
    std::filesystem::remove(merged);

    // Another config's shard.
    const std::string other_cfg = write_file(dir.path(), "other.yaml", R"(name: other
render: {width: 24, height: 16}
models: [{procedural: soup, triangles: 500, seed: 3}]
accelerators: [{name: brute_force}]
)");
    const std::string other = (dir.path() / "other.csv").string();
    ASSERT_EQ(run({other_cfg, "--out", other}), 0);
    write_inputs(other, *read_inputs(b));  // even with a matching record, the config column differs
    refused({merged, b, other}, 2, "rows of different configs");

    // A shard whose run still holds its output lock.
    write_file(dir.path(), "e2e.yaml", text);
    const std::string c = (dir.path() / "c.csv").string();  // shard 1 again, of a's contents
    ASSERT_EQ(run({config, "--out", c, "--shard", "1/2"}), 0);
    {
        const OutputLock running({a});
        refused({merged, a, c}, 2, "is being written by another process");
        refused({"--config", config, "--shards", "2", merged, a, c}, 2, "is being written by another process");
    }
    EXPECT_EQ(merge({"--config", config, "--shards", "2", merged, a, c}), 0);
    EXPECT_EQ(read_inputs(merged), read_inputs(a));
}

TEST_F(RunTest, TimeoutsAreRowsAndTheRunGoesOn) {
    // A limit the model's preparation fits (generating 20000 triangles: 0.02 s; no
    // reference pass) and brute force's render cannot (76800 rays x 20000 triangles, seconds):
    // the parent stops each measuring child (or the child sees the limit passed at a stage
    // boundary), records a timeout and goes on to the next.
    const std::string cfg = write_file(dir.path(), "slow.yaml", R"(name: slow
repetitions: 2
timeout_s: 0.5
errors: false
render: {width: 320, height: 240}
models: [{procedural: soup, triangles: 20000}]
accelerators:
  - {name: brute_force, params: {max_triangles: [20000, 30000]}}
)");
    ASSERT_EQ(run({cfg, "--out", out}), 0);
    const CsvData d = read_csv(out);
    ASSERT_EQ(d.rows.size(), 2u);
    for (size_t i = 0; i < 2; ++i) {
        auto r = as_map(d, i);
        EXPECT_EQ(r["status"], "timeout");
        EXPECT_NE(r["message"].find("exceeded the time limit (timeout_s = 0.5 s)"), std::string::npos) << r["message"];
        EXPECT_EQ(r["message"].find("loading"), std::string::npos) << r["message"];  // a measurement's stage
        EXPECT_EQ(r["triangles"], "20000");
        EXPECT_EQ(r["render_s_median"], "");
        EXPECT_EQ(r["rays"], "");
    }
    EXPECT_EQ(read_csv(repetitions_path(out)).rows.size(), 0u);
}

// Every column that is a property of the model, the structure and the rays (no time, no
// memory high-water mark, no clock), keyed by combo_id.
std::map<std::string, std::map<std::string, std::string>> answers_and_counts(const std::string& csv) {
    static const std::vector<std::string> deterministic = {
        "model",         "triangles",   "vertices",   "ray_source",   "ray_set",    "ray_set_hash",    "accel",
        "params",        "status",      "message",    "rays",         "hits",       "shadow_rays",     "shadow_hits",
        "nodes",         "leaves",      "tree_depth", "memory_bytes", "sah_cost",   "avg_leaf_size",   "build_extra",
        "prim_tests",    "node_visits", "box_tests",  "false_misses", "false_hits", "prim_mismatches", "t_err_ulp_p50",
        "t_err_ulp_max", "nan_results", "image_rmse", "hole_pixels"};
    const CsvData d = read_csv(csv);
    std::map<std::string, std::map<std::string, std::string>> out;
    for (size_t i = 0; i < d.rows.size(); ++i) {
        auto r = as_map(d, i);
        for (const std::string& k : deterministic) out[r["combo_id"]][k] = r.at(k);
    }
    return out;
}

TEST_F(RunTest, APreparedModelComesBackFromItsChildProcessUnchanged) {
    // Models are prepared (loaded, ray sets made, reference traced) in a child process and
    // sent back as bytes; --in-process prepares them in the run's own process. Every answer
    // and count must be the same: a procedural scene with colours in an image run (the
    // reference's image), a mesh file with a ray file, and generated ray sets.
    const std::string image = write_file(dir.path(), "image.yaml", R"(name: image
repetitions: 1
warmup: 0
render: {width: 24, height: 16, shading: true, light: true}
models:
  - {procedural: forest, triangles: 3000, seed: 2}
  - {path: tri.obj, rays: {file: tri.rays.csv}, label: tri-rays}
accelerators: [{name: bvh}, {name: kdtree}]
)");
    const std::string sets = write_file(dir.path(), "sets.yaml", R"(name: sets
repetitions: 1
warmup: 0
render: {width: 24, height: 16}
ray_sets: {sets: [primary, shadow, ao, diffuse, random], random: {rays: 300}}
models: [{procedural: soup, triangles: 800, seed: 5}]
accelerators: [{name: bvh}, {name: lbvh}]
)");
    for (const auto& [cfg, rows] : {std::pair<std::string, size_t>{image, 4}, {sets, 10}}) {
        const std::string child = (dir.path() / "child.csv").string(), here = (dir.path() / "here.csv").string();
        for (const std::string& f : {child, here, repetitions_path(child), repetitions_path(here)})
            std::filesystem::remove(f);
        ASSERT_EQ(run({cfg, "--out", child}), 0) << cfg;
        ASSERT_EQ(run({cfg, "--out", here, "--in-process"}), 0) << cfg;
        const auto a = answers_and_counts(child), b = answers_and_counts(here);
        ASSERT_EQ(a.size(), rows) << cfg;
        EXPECT_EQ(a, b) << cfg;
        for (const auto& [id, r] : a) {
            EXPECT_EQ(r.at("status"), "ok") << id << ": " << r.at("message");
            EXPECT_EQ(r.at("false_misses"), "0") << id;  // compared with the reference's answers
            EXPECT_EQ(r.at("false_hits"), "0") << id;
            if (r.at("model") == "tri-rays") EXPECT_EQ(r.at("ray_source"), "tri.rays.csv") << id;
            else if (cfg == image) EXPECT_EQ(r.at("hole_pixels"), "0") << id;
            else EXPECT_FALSE(r.at("ray_set_hash").empty()) << id;
        }
    }
}

TEST_F(RunTest, ErrorsAreRowsAndTheExitCodeSaysSo) {
    const std::string cfg = write_file(dir.path(), "bad.yaml", R"(name: bad
repetitions: 2
render: {width: 24, height: 16}
models: [{procedural: soup, triangles: 1000}]
accelerators:
  - {name: brute_force, params: {max_triangles: [10, 20000]}}
)");
    EXPECT_EQ(run({cfg, "--out", out}), 1);
    const CsvData d = read_csv(out);
    ASSERT_EQ(d.rows.size(), 2u);
    EXPECT_EQ(as_map(d, 0)["status"], "error");
    EXPECT_NE(as_map(d, 0)["message"].find("refuses"), std::string::npos);
    EXPECT_EQ(as_map(d, 0)["build_s_median"], "");
    EXPECT_EQ(as_map(d, 1)["status"], "ok");
}

TEST_F(RunTest, DryRunPrintsTheCombinationsAndTheirCount) {
    ::testing::internal::CaptureStdout();
    const int rc = run({config, "--dry-run"});
    const std::string text = ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(rc, 0);
    EXPECT_NE(text.find("6 combinations: 5 to measure, 1 skipped by rules"), std::string::npos) << text;
    EXPECT_NE(text.find("tri-rays"), std::string::npos);
    EXPECT_NE(text.find("[skip: tiny scene]"), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(out));
}

// --dry-run=json: the expansion for programs (the grid search reads its axes from it). JSON
// is YAML's flow form, so yaml-cpp reads it back here.
TEST_F(RunTest, DryRunAsJsonGivesTheAxesWithRangesExpandedAndEveryCombination) {
    const std::string grid = write_file(dir.path(), "grid.yaml", R"(name: grid
render: {width: 24, height: 16}
models: [{procedural: soup, triangles: 1000, seed: 3}, {path: tri.obj, label: "tri \"quoted\""}]
accelerators:
  - name: kdtree
    params: {max_prims: {from: 1, to: 8, scale: log2}, empty_bonus: {from: 0, to: 0.9, step: 0.3},
             "[isect_cost, max_depth]": [[80, auto], [10, 20]]}
skip:
  - {accel: kdtree, params: {max_prims: 8}, triangles_below: 10, reason: "tiny scene"}
)");
    ::testing::internal::CaptureStdout();
    const int rc = run({grid, "--dry-run=json"});
    const std::string text = ::testing::internal::GetCapturedStdout();
    ASSERT_EQ(rc, 0);
    const YAML::Node doc = YAML::Load(text);
    EXPECT_EQ(doc["config"].as<std::string>(), "grid");
    ASSERT_EQ(doc["models"].size(), 2u);
    EXPECT_EQ(doc["models"][1].as<std::string>(), "tri \"quoted\"");
    const YAML::Node axes = doc["accelerators"][0]["axes"];
    ASSERT_EQ(axes.size(), 3u);
    const auto values = [&](size_t i) {
        std::vector<std::vector<std::string>> v;
        for (const auto& t : axes[i]["values"]) v.push_back(t.as<std::vector<std::string>>());
        return v;
    };
    EXPECT_EQ(values(0), (std::vector<std::vector<std::string>>{{"1"}, {"2"}, {"4"}, {"8"}}));
    EXPECT_EQ(values(1), (std::vector<std::vector<std::string>>{{"0"}, {"0.3"}, {"0.6"}, {"0.9"}}));
    EXPECT_EQ(axes[2]["names"].as<std::vector<std::string>>(), (std::vector<std::string>{"isect_cost", "max_depth"}));
    EXPECT_EQ(values(2), (std::vector<std::vector<std::string>>{{"80", "auto"}, {"10", "20"}}));
    EXPECT_EQ(doc["combinations_in_config"].as<size_t>(), 64u);
    ASSERT_EQ(doc["combinations"].size(), 64u);
    size_t skipped = 0;
    for (const auto& c : doc["combinations"]) {
        EXPECT_EQ(c["combo_id"].as<std::string>().size(), 16u);
        const bool tri = c["model"].as<std::string>() == "tri \"quoted\"";
        EXPECT_EQ(c["triangles"].as<uint64_t>(), tri ? 1u : 1000u);
        if (!c["skip"].IsNull()) {
            ++skipped;
            EXPECT_TRUE(tri && c["given"]["max_prims"].as<std::string>() == "8");
            EXPECT_EQ(c["skip"].as<std::string>(), "tiny scene");
        }
    }
    EXPECT_EQ(skipped, 8u);
}

TEST(ShippedConfigsTest, AreValidAndExpandToTheDocumentedCounts) {
    const std::string dir = registry().project_dir() + "/configs/";
    const std::map<std::string, size_t> expected = {
        {"smoke.yaml", 24}, {"table2.yaml", 7}, {"table4.yaml", 40}, {"table5.yaml", 40}, {"robustness.yaml", 1540}};
    for (const auto& [file, count] : expected) {
        const Config c = load_config(dir + file, registry());
        EXPECT_EQ(expand(c).size(), count) << file;
        EXPECT_EQ(c.render.width, file == "smoke.yaml" ? 64 : file == "robustness.yaml" ? 32 : 640) << file;
    }
}

// The incoherent-ray goals' config: five settings on three models' five ray sets, timed
// interleaved in two processes, and the catalogue's 26 cases for the same five.
TEST(ShippedConfigsTest, TheGoalsRaySetConfigIsInterleaved) {
    const Config c = load_config(registry().project_dir() + "/configs/ray-sets-vs-embree.yaml", registry());
    EXPECT_TRUE(c.interleave);
    EXPECT_EQ(c.processes, 2);
    EXPECT_EQ(c.render.width, 640);
    EXPECT_EQ(c.render.height, 480);
    EXPECT_EQ(expand(c).size(), 3u * 5u * 5u + 26u * 5u);
}

TEST(ShippedConfigsTest, SmokeRunsCleanInSeconds) {
    TempDir dir("accelbench-smoke-test-");
    const std::string out = (dir.path() / "smoke.csv").string();
    ASSERT_EQ(run({registry().project_dir() + "/configs/smoke.yaml", "--out", out}), 0);
    const CsvData d = read_csv(out);
    ASSERT_EQ(d.rows.size(), 24u);
    size_t skipped = 0;
    for (size_t i = 0; i < d.rows.size(); ++i) {
        auto r = as_map(d, i);
        EXPECT_TRUE(r["status"] == "ok" || r["status"] == "skipped")
            << r["model"] << " " << r["accel"] << ": " << r["message"];
        skipped += r["status"] == "skipped";
    }
    EXPECT_EQ(skipped, 2u);  // brute force on the bunny and the forest
}

TEST_F(RunTest, AMalformedConfigIsExitCode2) {
    const std::string cfg = write_file(dir.path(), "broken.yaml", "models: [igea]\naccelerators: [{name: nope}]\n");
    ::testing::internal::CaptureStderr();
    EXPECT_EQ(run({cfg, "--out", out}), 2);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find(cfg + ":2:23: accelerators[0].name: unknown accelerator 'nope'"), std::string::npos) << err;
    EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace accelbench
