// `accelbench run` with `ray_sets` and a list of render thread counts: one row
// per combination and set, the set's hash the same on every structure's row, answers
// compared with the reference, hits and counts independent of the thread count; and the
// config errors of the new keys.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "accelbench/verify/robustness_cases.h"
#include "commands/cli.h"
#include "config/config.h"
#include "csv/csv.h"
#include "csv/results.h"
#include "harness_test_util.h"
#include "plan/combinations.h"
#include "plan/loaded_model.h"

namespace accelbench {
namespace {

using namespace testing_util;

int run(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    return run_command(int(argv.size()), argv.data());
}

std::vector<std::map<std::string, std::string>> rows_of(const std::string& path) {
    const CsvData d = read_csv(path);
    const auto keys = result_columns();
    EXPECT_EQ(d.header, column_headers(keys));
    std::vector<std::map<std::string, std::string>> out;
    for (const auto& row : d.rows) {
        std::map<std::string, std::string> m;
        for (size_t i = 0; i < keys.size() && i < row.size(); ++i) m[keys[i]] = row[i];
        out.push_back(std::move(m));
    }
    return out;
}

TEST(RaySetsRun, OneRowPerSetWithTheSameRaysForEveryStructure) {
    TempDir dir("accelbench-ray-sets-run-");
    const std::string cfg = write_file(dir.path(), "rs.yaml", R"(name: rs
repetitions: 2
render: {width: 32, height: 24, threads: [1, 2]}
ray_sets:
  sets: [primary, ao, diffuse, random, shadow]
  ao: {samples: 2}
  random: {rays: 500}
models:
  - {procedural: soup, triangles: 1500, seed: 3}
accelerators:
  - {name: bvh}
  - {name: kdtree}
  - {name: embree}
)");
    const std::string out = (dir.path() / "rs.csv").string();
    ASSERT_EQ(run({cfg, "--out", out}), 0);
    const auto rows = rows_of(out);
    ASSERT_EQ(rows.size(), 3u * 2u * 5u);                 // structures x thread counts x sets
    std::map<std::string, std::set<std::string>> hashes;  // set -> hashes seen
    std::map<std::string, std::string> counts;            // structure/set -> rays, hits, tests
    std::set<std::string> ids;
    for (const auto& r : rows) {
        EXPECT_EQ(r.at("status"), "ok") << r.at("message");
        ids.insert(r.at("combo_id"));
        hashes[r.at("ray_set")].insert(r.at("ray_set_hash"));
        EXPECT_EQ(r.at("shadow_rays"), "0");
        EXPECT_EQ(r.at("false_misses"), "0") << r.at("accel") << " " << r.at("ray_set");
        EXPECT_EQ(r.at("false_hits"), "0") << r.at("accel") << " " << r.at("ray_set");
        EXPECT_FALSE(r.at("render_cpu_s_median").empty());
        if (r.at("ray_set") == "random") {
            EXPECT_EQ(r.at("rays"), "500");
        }
        // Thread counts 1 and 2: the same rays, hits and traversal counts.
        const std::string what = r.at("accel") + "/" + r.at("ray_set");
        const std::string value =
            r.at("rays") + " " + r.at("hits") + " " + r.at("prim_tests") + " " + r.at("node_visits");
        if (auto [it, fresh] = counts.emplace(what, value); !fresh) {
            EXPECT_EQ(it->second, value) << what;
        }
    }
    EXPECT_EQ(ids.size(), rows.size());  // every row its own combination id
    ASSERT_EQ(hashes.size(), 5u);
    for (const auto& [set, h] : hashes) {
        EXPECT_EQ(h.size(), 1u) << set << ": every structure and thread count traces the same rays";
        EXPECT_EQ(h.begin()->size(), 16u) << set;
    }
}

// A set that cannot be made takes only its own rows: the model's other sets are made (and
// reach the parent process from the preparing child) and are measured.
TEST(RaySetsRun, ASetThatCannotBeMadeLeavesTheOtherSets) {
    TempDir dir("accelbench-ray-sets-fail-");
    const std::string cfg = write_file(dir.path(), "f.yaml", R"(errors: false
render: {width: 16, height: 12}
ray_sets: {sets: [primary, ao, random], random: {rays: 100}}
models:
  - {procedural: soup, triangles: 200, seed: 3}
accelerators: [{name: bvh}]
)");
    const Config config = load_config(cfg, registry());
    LoadedModel model = load_model(config.models[0], registry(), config.render);
    RaySetsSpec spec = *config.ray_sets;
    spec.params.ao_samples = 0;  // what the config refuses: make_ray_sets throws for it
    add_ray_sets(model, config.render, spec);
    ASSERT_TRUE(model.ray_sets);
    ASSERT_EQ(model.ray_sets->size(), 2u);
    EXPECT_EQ((*model.ray_sets)[0].kind, RaySetKind::Primary);
    EXPECT_EQ((*model.ray_sets)[1].kind, RaySetKind::Random);
    ASSERT_EQ(model.ray_set_errors.count(RaySetKind::Ao), 1u);
    EXPECT_NE(model.ray_set_errors.at(RaySetKind::Ao).find("ao samples must be at least 1"), std::string::npos);
    // Through the wire form that brings a prepared model from its child process.
    const LoadedModel back = model_from_wire(model_wire_bytes(model), config.models[0]);
    EXPECT_EQ(back.ray_set_errors, model.ray_set_errors);
    EXPECT_EQ(back.ray_sets->size(), 2u);
}

// A robustness case beside ray-set models is judged once on its own rays (no ray set), so
// a structure's leaks sit in the same run as its ray-set speed.
TEST(RaySetsRun, ARobustnessCaseIsJudgedOnceNotPerSet) {
    TempDir dir("accelbench-ray-sets-case-");
    const std::string cfg = write_file(dir.path(), "c.yaml", R"(repetitions: 1
render: {width: 16, height: 12}
ray_sets: {sets: [primary, ao]}
models:
  - {procedural: soup, triangles: 300, seed: 2}
  - {case: 1}
accelerators: [{name: bvh}, {name: wbvh}]
)");
    const std::string out = (dir.path() / "c.csv").string();
    ASSERT_EQ(run({cfg, "--out", out}), 0);
    const auto rows = rows_of(out);
    ASSERT_EQ(rows.size(), 2u * 2u + 2u);  // 2 structures x 2 sets, and the case once each
    int cases = 0;
    for (const auto& r : rows) {
        if (r.at("ray_source") == "robustness-case") {
            ++cases;
            EXPECT_EQ(r.at("ray_set"), "") << r.at("accel");
            EXPECT_EQ(r.at("verdict"), "pass") << r.at("accel") << " " << r.at("message");
        } else {
            EXPECT_TRUE(r.at("ray_set") == "primary" || r.at("ray_set") == "ao") << r.at("ray_set");
            EXPECT_EQ(r.at("verdict"), "");
        }
    }
    EXPECT_EQ(cases, 2);
}

TEST(RaySetsRun, AConfigWithoutRaySetsWritesTheCameraRow) {
    TempDir dir("accelbench-ray-sets-run-");
    const std::string cfg = write_file(dir.path(), "cam.yaml", R"(repetitions: 1
render: {width: 16, height: 12}
models: [{procedural: soup, triangles: 500, seed: 1}]
accelerators: [{name: bvh}]
)");
    const std::string out = (dir.path() / "cam.csv").string();
    ASSERT_EQ(run({cfg, "--out", out}), 0);
    const auto rows = rows_of(out);
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_EQ(rows[0].at("ray_set"), "camera");
    EXPECT_EQ(rows[0].at("ray_set_hash"), "");
    EXPECT_NE(rows[0].at("shadow_rays"), "0");
}

TEST(RaySetsRun, TheSeedChangesTheSeededSetsOnly) {
    TempDir dir("accelbench-ray-sets-run-");
    std::map<std::string, std::string> hash[2];
    for (const char* seed : {"1", "2"}) {
        // Built with append: GCC 12's -Wrestrict misreads `"literal" + std::string`.
        std::string text = "repetitions: 1\nerrors: false\nrender: {width: 16, height: 12}\n";
        text.append("ray_sets: {random: {rays: 100}, seed: ").append(seed).append("}\n");
        text.append("models: [{procedural: soup, triangles: 500, seed: 1}]\naccelerators: [{name: bvh}]\n");
        const std::string name = std::string("s").append(seed);
        const std::string cfg = write_file(dir.path(), name + ".yaml", text);
        const std::string out = (dir.path() / (name + ".csv")).string();
        ASSERT_EQ(run({cfg, "--out", out}), 0);
        for (const auto& r : rows_of(out)) hash[seed[0] - '1'][r.at("ray_set")] = r.at("ray_set_hash");
    }
    ASSERT_EQ(hash[0].size(), 5u);  // every set by default
    EXPECT_EQ(hash[0]["primary"], hash[1]["primary"]);
    EXPECT_EQ(hash[0]["shadow"], hash[1]["shadow"]);
    EXPECT_NE(hash[0]["ao"], hash[1]["ao"]);
    EXPECT_NE(hash[0]["diffuse"], hash[1]["diffuse"]);
    EXPECT_NE(hash[0]["random"], hash[1]["random"]);
}

TEST(RaySetsConfig, BadValuesAreIssuesWithTheirKeyPaths) {
    TempDir dir("accelbench-ray-sets-config-");
    const std::string cfg = write_file(dir.path(), "bad.yaml", R"(render: {threads: [1, 1]}
ray_sets:
  sets: [primary, diffusion, primary]
  ao: {samples: 0, distance: -1}
  diffuse: {depth: 2}
models: [{procedural: soup, triangles: 500}]
accelerators: [{name: bvh}]
)");
    const ConfigError e = load_error(cfg);
    const std::string all = all_issues(e);
    EXPECT_NE(all.find("render.threads[1]: thread count 1 is listed twice"), std::string::npos) << all;
    EXPECT_NE(all.find("ray_sets.sets[1]: unknown ray set 'diffusion'"), std::string::npos) << all;
    EXPECT_NE(all.find("ray_sets.sets[2]: ray set 'primary' is listed twice"), std::string::npos) << all;
    EXPECT_NE(all.find("ray_sets.ao.samples"), std::string::npos) << all;
    EXPECT_NE(all.find("ray_sets.ao.distance"), std::string::npos) << all;
    EXPECT_NE(all.find("ray_sets.diffuse.depth: unknown key"), std::string::npos) << all;
}

TEST(RaySetsConfig, ShippedConfigsExpandAsDocumented) {
    const std::string dir = registry().project_dir() + "/configs/";
    const Config rs = load_config(dir + "ray-sets.yaml", registry());
    // 2 models x 10 settings (7 structures, Embree robust=true, the two wbvh ablations) x 5
    // sets, and the extreme-case catalogue's cases once per setting
    const size_t cases = robustness_case_list().size();
    EXPECT_EQ(rs.models.size(), 2u + cases);
    EXPECT_EQ(expand(rs).size(), 100u + cases * 10u);
    const Config ts = load_config(dir + "thread-scaling.yaml", registry());
    EXPECT_EQ(expand(ts).size(), 14u * ts.thread_counts.size());  // 2 models x 7 structures
    EXPECT_EQ(ts.thread_counts.front(), 1);
}

}  // namespace
}  // namespace accelbench
