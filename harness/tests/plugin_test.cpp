// Structures from plugins (accelbench_plugin.h): a good one joins the registry and answers
// like Embree; each kind of bad plugin is refused in one line naming its file, or (a crash
// or a hang) fails its own rows while the run goes on. The plugins are built by CMake from
// examples/plugins/binned_bvh and harness/tests/plugins/fault_plugin.c.
#include <gtest/gtest.h>

#include <filesystem>

#include "accelbench/accel/plugin/plugin_accel.h"
#include "accelbench/accel/registry.h"
#include "agreement.h"
#include "commands/cli.h"
#include "csv/csv.h"
#include "csv/results.h"
#include "harness_test_util.h"
#include "test_scenes.h"

namespace accelbench {
namespace {

namespace fs = std::filesystem;
using namespace testing_util;

std::string plugin_path(const std::string& name) {
    return std::string(ACCELBENCH_TEST_PLUGIN_DIR) + "/" + name + ".so";
}

// The refusal of loading `path`: "plugin PATH: ..." on one line, or "" when it loaded.
std::string refusal(const std::string& path) {
    try {
        load_plugin_file(path);
    } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("plugin " + path + ": ", 0), 0u) << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        return m;
    }
    return "";
}

TEST(Plugin, AStructureJoinsTheRegistryWithItsParameters) {
    const std::string path = plugin_path("example_bvh");
    const auto columns_before = result_columns();
    ASSERT_EQ(refusal(path), "");
    const AcceleratorInfo* info = find_accelerator("example_bvh");
    ASSERT_NE(info, nullptr);
    ASSERT_TRUE(info->plugin);
    EXPECT_EQ(info->plugin->file, path);
    EXPECT_EQ(info->plugin->version, "example_bvh 1.0");
    EXPECT_EQ(info->plugin->sha256.size(), 64u);
    EXPECT_EQ(info->label(resolve_params("example_bvh", info->params, {})), "Example BVH (plugin)");
    ASSERT_EQ(info->params.size(), 2u);
    EXPECT_EQ(info->params[0].name, "max_leaf_size");
    EXPECT_EQ(info->params[0].default_value, "4");
    EXPECT_EQ(info->params[1].max, 64);
    EXPECT_TRUE(info->counts_traversal);
    // Checked like ours before the plugin sees a value.
    EXPECT_THROW(make_accelerator("example_bvh", {{"bins", "65"}}), ParamError);
    EXPECT_THROW(make_accelerator("example_bvh", {{"leaf", "4"}}), ParamError);
    // Loading the same file again changes nothing.
    const size_t structures = accelerator_registry().size();
    EXPECT_EQ(refusal(path), "");
    EXPECT_EQ(accelerator_registry().size(), structures);
    // Not in the CSV's parameter columns: the header is the same with or without plugins.
    EXPECT_EQ(result_columns(), columns_before);
}

TEST(Plugin, ItsAnswersAgreeWithEmbree) {
    ASSERT_EQ(refusal(plugin_path("example_bvh")), "");
    for (const char* bins : {"2", "16"}) {
        ParamSet resolved;
        auto accel = make_accelerator("example_bvh", {{"bins", bins}}, &resolved);
        const Scene scene = test::closed_grid();
        accel->build(scene);
        const BuildStats stats = accel->build_stats();
        ASSERT_TRUE(stats.nodes && stats.leaves && stats.sah_cost);
        EXPECT_EQ(*stats.nodes, 2 * *stats.leaves - 1);  // a binary tree
        test::expect_agrees_with_embree(scene, *accel, test::probe_rays(scene, 4000),
                                        std::string("example_bvh bins=") + bins);
        std::vector<RayStats> counts(8);
        std::vector<Hit> hits(8);
        const std::vector<Ray> rays = test::probe_rays(scene, 8);
        accel->closest_hits(rays, hits, counts);
        EXPECT_GT(counts[0].node_visits, 0u);
    }
}

TEST(Plugin, BadPluginsAreRefusedInOneLine) {
    TempDir dir{"accelbench-plugin-test-"};
    const std::string text = write_file(dir.path(), "text.so", "not an ELF file\n");
    EXPECT_NE(refusal(text).find("not a loadable shared library"), std::string::npos);
    EXPECT_NE(refusal((dir.path() / "absent.so").string()).find("no such file"), std::string::npos);
    EXPECT_NE(refusal(plugin_path("wrong_abi")).find("built for plugin ABI version 2, this accelbench loads version 1"),
              std::string::npos);
    EXPECT_NE(refusal(plugin_path("missing_symbol")).find("no entry point accelbench_plugin_entry"), std::string::npos);
    EXPECT_NE(refusal(plugin_path("duplicate_name")).find("structure 'bvh' is already registered (built in)"),
              std::string::npos);
    EXPECT_NE(refusal(plugin_path("bad_param_table"))
                  .find("structure 'fault_bad_param_table', parameter 'leaf_size': its default does not parse"),
              std::string::npos);
    // The same structures from another file: a name twice.
    ASSERT_EQ(refusal(plugin_path("example_bvh")), "");
    const std::string copy = (dir.path() / "copy.so").string();
    fs::copy_file(plugin_path("example_bvh"), copy);
    EXPECT_NE(
        refusal(copy).find("structure 'example_bvh' is already registered by plugin " + plugin_path("example_bvh")),
        std::string::npos);
    // Nothing of a refused plugin was registered.
    for (const char* name : {"fault_wrong_abi", "fault_missing_symbol", "fault_bad_param_table"})
        EXPECT_EQ(find_accelerator(name), nullptr) << name;
}

TEST(Plugin, AConfigNamesItsPluginsAndABadOneIsAnIssue) {
    TempDir dir{"accelbench-plugin-test-"};
    const std::string bad = write_file(dir.path(), "bad.yaml",
                                       "models: [{procedural: soup, triangles: 10}]\n"
                                       "plugins: [" +
                                           plugin_path("wrong_abi") +
                                           "]\n"
                                           "accelerators: [{name: brute_force}]\n");
    try {
        load_config(bad, registry());
        ADD_FAILURE() << "a plugin of another ABI was accepted";
    } catch (const ConfigError& e) {
        ASSERT_EQ(e.issues().size(), 1u) << all_issues(e);
        EXPECT_NE(all_issues(e).find("plugins[0]"), std::string::npos) << all_issues(e);
        EXPECT_NE(all_issues(e).find("plugin ABI version 2"), std::string::npos) << all_issues(e);
    }
    // A path relative to the config's directory.
    const std::string relative = fs::relative(plugin_path("example_bvh"), dir.path()).string();
    const std::string good = write_file(dir.path(), "good.yaml",
                                        "models: [{procedural: soup, triangles: 10}]\n"
                                        "plugins: [" +
                                            relative +
                                            "]\n"
                                            "accelerators: [{name: all}]\n");
    const Config c = load_config(good, registry());  // the path is the config's directory's
    ASSERT_EQ(c.plugins.size(), 1u);
    std::vector<std::string> names;
    for (const AcceleratorSpec& a : c.accelerators) names.push_back(a.name);
    EXPECT_NE(std::find(names.begin(), names.end(), "example_bvh"), names.end());
}

int run(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    return run_command(int(argv.size()), argv.data());
}

TEST(Plugin, ARunMeasuresItAndContainsCrashesAndHangs) {
    TempDir dir{"accelbench-plugin-test-"};
    const std::string config = write_file(dir.path(), "plugins.yaml",
                                          R"(name: plugins
repetitions: 1
warmup: 0
timeout_s: 2
render: {width: 32, height: 24}
plugins: [)" + plugin_path("crash_in_build") + ", " +
                                              plugin_path("crash_in_trace") + ", " + plugin_path("hang_in_build") + R"(]
models: [{procedural: soup, triangles: 2000, seed: 5}]
accelerators:
  - {name: fault_crash_in_build}
  - {name: example_bvh, params: {bins: [4, 16]}}
  - {name: fault_crash_in_trace}
  - {name: fault_hang_in_build}
  - {name: brute_force}
)");
    const std::string out = (dir.path() / "plugins.csv").string();
    EXPECT_EQ(run({config, "--plugin", plugin_path("example_bvh"), "--out", out}), 1);  // rows in error
    const CsvData d = read_csv(out);
    const auto keys = result_columns();
    ASSERT_EQ(d.header, column_headers(keys));
    std::map<std::string, std::map<std::string, std::string>> rows;  // by accel and params
    for (const auto& row : d.rows) {
        std::map<std::string, std::string> m;
        for (size_t i = 0; i < keys.size(); ++i) m[keys[i]] = row[i];
        rows[m["accel"] + " " + m["params"]] = m;
    }
    ASSERT_EQ(rows.size(), 6u);
    for (const char* params : {"max_leaf_size=4;bins=4", "max_leaf_size=4;bins=16"}) {
        auto& r = rows[std::string("example_bvh ") + params];
        EXPECT_EQ(r["status"], "ok") << r["message"];
        EXPECT_EQ(r["label"], "Example BVH (plugin)");
        EXPECT_EQ(r["false_misses"], "0");
        EXPECT_EQ(r["false_hits"], "0");
        EXPECT_EQ(r["prim_mismatches"], "0");
        EXPECT_NE(r["node_visits"], "");
        EXPECT_EQ(r["plugin_file"], plugin_path("example_bvh"));
        EXPECT_EQ(r["plugin_version"], "example_bvh 1.0");
        EXPECT_EQ(r["plugin_sha256"].size(), 64u);
    }
    auto& build_crash = rows["fault_crash_in_build mode=plain"];
    EXPECT_EQ(build_crash["status"], "error");
    EXPECT_NE(build_crash["message"].find("signal 11"), std::string::npos) << build_crash["message"];
    EXPECT_NE(build_crash["message"].find("build"), std::string::npos) << build_crash["message"];
    auto& trace_crash = rows["fault_crash_in_trace mode=plain"];
    EXPECT_EQ(trace_crash["status"], "error");
    EXPECT_NE(trace_crash["message"].find("signal 11"), std::string::npos) << trace_crash["message"];
    auto& hang = rows["fault_hang_in_build mode=plain"];
    EXPECT_EQ(hang["status"], "timeout");
    EXPECT_NE(hang["message"].find("build"), std::string::npos) << hang["message"];
    auto& ours = rows["brute_force max_triangles=20000;force=false"];
    EXPECT_EQ(ours["status"], "ok") << ours["message"];
    EXPECT_EQ(ours["plugin_file"], "");
}

// Interleaved, a crash or a hang in the shared child costs its own combination only: the
// child's last stage names it, and the others are measured again without it.
TEST(Plugin, AnInterleavedGroupOutlivesACrashAndAHang) {
    TempDir dir{"accelbench-plugin-test-"};
    const std::string config = write_file(dir.path(), "group.yaml",
                                          R"(name: group
repetitions: 1
warmup: 0
timeout_s: 1
interleave: true
errors: false
render: {width: 32, height: 24}
plugins: [)" + plugin_path("crash_in_trace") + ", " +
                                              plugin_path("hang_in_build") + R"(]
models: [{procedural: soup, triangles: 2000, seed: 5}]
accelerators:
  - {name: fault_crash_in_trace}
  - {name: brute_force}
  - {name: fault_hang_in_build}
  - {name: bvh}
)");
    const std::string out = (dir.path() / "group.csv").string();
    EXPECT_EQ(run({config, "--out", out}), 1);  // rows in error
    const CsvData d = read_csv(out);
    const auto keys = result_columns();
    std::map<std::string, std::map<std::string, std::string>> rows;  // by accel
    for (const auto& row : d.rows) {
        std::map<std::string, std::string> m;
        for (size_t i = 0; i < keys.size(); ++i) m[keys[i]] = row[i];
        rows[m["accel"]] = m;
    }
    ASSERT_EQ(rows.size(), 4u);
    EXPECT_EQ(rows["fault_hang_in_build"]["status"], "timeout");
    EXPECT_NE(
        rows["fault_hang_in_build"]["message"].find("(timeout_s = 1 s for each of the 4 combinations timed in one "
                                                    "process) during soup(triangles=2000,seed=5)/fault_hang_in_build: "
                                                    "build repetition 1 of 1"),
        std::string::npos)
        << rows["fault_hang_in_build"]["message"];
    EXPECT_EQ(rows["fault_crash_in_trace"]["status"], "error");
    EXPECT_NE(rows["fault_crash_in_trace"]["message"].find("signal 11"), std::string::npos)
        << rows["fault_crash_in_trace"]["message"];
    // The survivors, timed with each other in the last child.
    auto& brute = rows["brute_force"];
    auto& bvh = rows["bvh"];
    EXPECT_EQ(brute["status"], "ok") << brute["message"];
    EXPECT_EQ(bvh["status"], "ok") << bvh["message"];
    EXPECT_EQ(brute["timed_with"], bvh["combo_id"]);
    EXPECT_EQ(bvh["timed_with"], brute["combo_id"]);
}

}  // namespace
}  // namespace accelbench
