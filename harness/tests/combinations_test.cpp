// Expansion (cartesian per accelerator, zipped groups, scalars, times the models), stable
// combination ids, skip rules and shards.
#include <gtest/gtest.h>

#include <set>

#include "harness_test_util.h"
#include "plan/combinations.h"

namespace accelbench {
namespace {

using namespace testing_util;

class CombinationsTest : public ::testing::Test {
protected:
    TempDir dir{"accelbench-combinations-test-"};
    Config load(const std::string& name, const std::string& text) {
        return load_config(write_file(dir.path(), name, text), registry());
    }
};

constexpr const char* kConfig = R"yaml(models: [stanford-bunny, {procedural: soup, triangles: 2000}]
accelerators:
  - {name: embree, params: {quality: [low, medium, high], robust: [false, true]}}
  - {name: brute_force, params: {"[max_triangles, force]": [[1000, false], [5000, true]]}}
  - {name: brute_force, params: {max_triangles: 7}}
skip:
  - {accel: brute_force, triangles_above: 5000, reason: "O(N*P) is too slow"}
  - {accel: embree, params: {quality: high}, model: "soup(triangles=2000)", reason: "not needed"}
)yaml";

TEST_F(CombinationsTest, CartesianPerAcceleratorZippedAndScalarTimesModels) {
    const Config c = load("a.yaml", kConfig);
    const auto all = expand(c);
    // Per model: embree 3 x 2 (its own axes only), brute_force 2 tuples, brute_force 1.
    ASSERT_EQ(all.size(), 2u * (6 + 2 + 1));
    // Models outer; within an accelerator the first axis turns slowest.
    EXPECT_EQ(all[0].name, "stanford-bunny/embree:quality=low,robust=false");
    EXPECT_EQ(all[1].name, "stanford-bunny/embree:quality=low,robust=true");
    EXPECT_EQ(all[2].name, "stanford-bunny/embree:quality=medium,robust=false");
    EXPECT_EQ(all[6].name, "stanford-bunny/brute_force:max_triangles=1000,force=false");
    EXPECT_EQ(all[7].name, "stanford-bunny/brute_force:max_triangles=5000,force=true");
    EXPECT_EQ(all[8].name, "stanford-bunny/brute_force:max_triangles=7");
    EXPECT_EQ(all[9].name, "soup(triangles=2000)/embree:quality=low,robust=false");
    for (const auto& x : all) EXPECT_EQ(x.model, &x < &all[9] ? 0u : 1u);
    // Canonical params carry every parameter, defaults included.
    EXPECT_EQ(all[8].params.canonical(), "max_triangles=7;force=false");
    // Embree's device threads follow the render threads unless given.
    EXPECT_EQ(all[0].given.at("threads"), "1");
    EXPECT_EQ(all[6].given.count("threads"), 0u);
    std::set<std::string> ids;
    for (const auto& x : all) ids.insert(x.id);
    EXPECT_EQ(ids.size(), all.size());
}

TEST_F(CombinationsTest, IdsDependOnTheMeasurementNotOnTheConfig) {
    const auto a = expand(load("a.yaml", kConfig));
    // Another config: other name, order and neighbours; the shared combination keeps its id.
    const auto b = expand(load("b.yaml", R"yaml(name: other
repetitions: 2
models: [{procedural: soup, triangles: 2000, seed: 1}, igea]
accelerators:
  - {name: brute_force, params: {max_triangles: [7, 8]}}
)yaml"));
    EXPECT_EQ(b[0].name, "soup(triangles=2000,seed=1)/brute_force:max_triangles=7");
    EXPECT_EQ(b[0].id, a[17].id);  // seed=1 is the default: the same scene
    EXPECT_NE(b[1].id, a[17].id);
    // Render settings are part of what is measured.
    const auto c = expand(load("c.yaml", R"yaml(render: {width: 320}
models: [{procedural: soup, triangles: 2000}]
accelerators: [{name: brute_force, params: {max_triangles: 7}}]
)yaml"));
    EXPECT_NE(c[0].id, a[17].id);
    const auto threads = expand(load("d.yaml", R"yaml(render: {threads: 2}
models: [stanford-bunny]
accelerators: [{name: embree}]
)yaml"));
    EXPECT_EQ(threads[0].given.at("threads"), "2");
}

TEST_F(CombinationsTest, RangesExpandLikeTheGridSearchExpectsAndGridIsIgnored) {
    const Config c = load("grid.yaml", R"yaml(name: grid
models: [{name: igea}]
accelerators:
  - name: embree
    params:
      threads: {from: 1, to: 12, scale: log2}   # 1 2 4 8
      quality: [low, high]
grid:
  objective: build + k * render
  anything: [the harness, does not read this]
)yaml");
    const auto all = expand(c);
    ASSERT_EQ(all.size(), 4u * 2u);
    EXPECT_EQ(all[0].name, "igea/embree:threads=1,quality=low");
    EXPECT_EQ(all[7].name, "igea/embree:threads=8,quality=high");
    const auto step = expand(load("step.yaml", R"yaml(models: [igea]
accelerators: [{name: embree, params: {threads: {from: 0, to: 5, step: 2}}}]
)yaml"));
    ASSERT_EQ(step.size(), 3u);
    EXPECT_EQ(step[2].given.at("threads"), "4");
}

TEST_F(CombinationsTest, RangeErrors) {
    const std::string p = write_file(dir.path(), "bad.yaml", R"yaml(models: [igea]
accelerators:
  - {name: embree, params: {threads: {from: 8, to: 1, step: 1}}}
  - {name: embree, params: {threads: {from: 1, to: 8, step: 1, scale: log2}}}
  - {name: embree, params: {threads: {from: 0, to: 8, scale: log2}}}
  - {name: embree, params: {threads: {from: 1, to: 2000, step: 500}}}
  - {name: embree, params: {threads: {from: 1, step: 1}}}
)yaml");
    const ConfigError e = load_error(p);
    EXPECT_TRUE(has_issue(e, 3, 38, "accelerators[0].embree.threads", "`from` (8) is above `to` (1)"));
    EXPECT_TRUE(has_issue(e, 4, 38, "accelerators[1].embree.threads", "exactly one of `step` or `scale`"));
    EXPECT_TRUE(has_issue(e, 5, 45, "accelerators[2].embree.threads.from", "a log2 range starts above 0"));
    EXPECT_TRUE(
        has_issue(e, 6, 38, "accelerators[3].embree.threads", "the range's value 1501: value 1501 is out of range"));
    EXPECT_TRUE(has_issue(e, 7, 38, "accelerators[4].embree.threads.to", "missing key 'to'"));
}

TEST_F(CombinationsTest, ASceneDependentDefaultCanBeNamedInAZippedGroup) {
    // The kd-tree's max_depth defaults to "auto" (computed from the scene): `auto` in a
    // config means "not given", so it pairs with explicit depths in one zipped group.
    const Config c = load("t2.yaml", R"yaml(models: [stanford-bunny]
accelerators:
  - {name: kdtree, params: {"[max_prims, max_depth]": [[10, auto], [1, 5]]}}
  - {name: kdtree, params: {max_prims: 1}}
)yaml");
    const auto all = expand(c);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_EQ(all[0].name, "stanford-bunny/kdtree:max_prims=10,max_depth=auto");
    EXPECT_EQ(all[0].given.count("max_depth"), 0u);
    EXPECT_FALSE(all[0].params.given("max_depth"));
    EXPECT_NE(all[0].params.canonical().find("max_depth=auto"), std::string::npos);
    EXPECT_EQ(all[1].given.at("max_depth"), "5");
    // Naming the default or leaving it out is the same combination.
    const auto same = expand(load("same.yaml", R"yaml(models: [stanford-bunny]
accelerators: [{name: kdtree, params: {max_prims: 10, max_depth: auto}}]
)yaml"));
    const auto omitted = expand(load("omitted.yaml", R"yaml(models: [stanford-bunny]
accelerators: [{name: kdtree, params: {max_prims: 10}}]
)yaml"));
    EXPECT_EQ(same[0].id, all[0].id);
    EXPECT_EQ(omitted[0].id, all[0].id);
}

TEST_F(CombinationsTest, TheSameCombinationTwiceIsAnError) {
    const Config c = load("a.yaml", R"yaml(models: [igea]
accelerators:
  - {name: embree, params: {quality: [low, medium]}}
  - {name: embree}
)yaml");
    try {
        expand(c);
        FAIL() << "expected a ConfigError";
    } catch (const ConfigError& e) {
        ASSERT_EQ(e.issues().size(), 1u);
        EXPECT_EQ(e.issues()[0].key_path, "accelerators[1]");
        EXPECT_EQ(e.issues()[0].mark.line, 4);
        EXPECT_NE(e.issues()[0].message.find("repeats models[0] x accelerators[0]"), std::string::npos)
            << e.issues()[0].message;
    }
}

TEST_F(CombinationsTest, RepetitionsAndWarmupOverridesForTheSlowOnes) {
    const Config c = load("a.yaml", R"yaml(repetitions: 5
warmup: 2
processes: 2
models: [igea, {name: stanford-bunny, repetitions: 3, processes: 3}]
accelerators:
  - {name: embree}
  - {name: brute_force, repetitions: 1, warmup: 0, processes: 1}
)yaml");
    const auto all = expand(c);
    ASSERT_EQ(all.size(), 4u);
    EXPECT_EQ(repetitions_of(c, all[0]), 5);  // igea / embree: the config's
    EXPECT_EQ(warmup_of(c, all[0]), 2);
    EXPECT_EQ(repetitions_of(c, all[1]), 1);  // the accelerator entry's wins
    EXPECT_EQ(warmup_of(c, all[1]), 0);
    EXPECT_EQ(repetitions_of(c, all[2]), 3);  // bunny / embree: the model's
    EXPECT_EQ(warmup_of(c, all[2]), 2);
    EXPECT_EQ(repetitions_of(c, all[3]), 1);
    EXPECT_EQ(processes_of(c, all[0]), 2);  // the config's
    EXPECT_EQ(processes_of(c, all[1]), 1);  // the accelerator entry's
    EXPECT_EQ(processes_of(c, all[2]), 3);  // the model's
    EXPECT_EQ(processes_of(c, all[3]), 1);
    // How much is measured is not what is measured: ids do not change.
    const auto plain = expand(load("b.yaml", "models: [igea]\naccelerators: [{name: brute_force}]\n"));
    EXPECT_EQ(plain[0].id, all[1].id);
}

TEST_F(CombinationsTest, SkipRules) {
    const Config c = load("a.yaml", kConfig);
    const auto all = expand(c);
    const uint64_t bunny = 69451, soup = 2000;
    EXPECT_FALSE(skip_reason(c, all[0], bunny));                     // embree low on the bunny
    EXPECT_FALSE(skip_reason(c, all[4], bunny));                     // embree high: rule 2 is for the soup
    EXPECT_EQ(skip_reason(c, all[6], bunny), "O(N*P) is too slow");  // brute_force, 69k > 5000
    EXPECT_EQ(skip_reason(c, all[8], bunny), "O(N*P) is too slow");
    EXPECT_FALSE(skip_reason(c, all[15], soup));             // brute_force, 2000 <= 5000
    EXPECT_FALSE(skip_reason(c, all[12], soup));             // soup, embree medium/true
    EXPECT_EQ(skip_reason(c, all[13], soup), "not needed");  // soup, embree high/false
    EXPECT_EQ(skip_reason(c, all[14], soup), "not needed");  // soup, embree high/true
    EXPECT_FALSE(skip_reason(c, all[6], 5000));              // "above" is strict
}

TEST_F(CombinationsTest, ShardsCoverEveryCombinationExactlyOnce) {
    const auto all = expand(load("a.yaml", kConfig));
    for (uint64_t n = 1; n <= 5; ++n) {
        std::map<std::string, int> seen;
        for (uint64_t i = 0; i < n; ++i)
            for (const auto& x : all)
                if (Shard{i, n}.contains(x)) ++seen[x.id];
        EXPECT_EQ(seen.size(), all.size()) << "n=" << n;
        for (const auto& [id, count] : seen) EXPECT_EQ(count, 1) << id << " n=" << n;
    }
}

TEST(ShardTest, ParsesAndRejects) {
    const Shard s = parse_shard("2/5");
    EXPECT_EQ(s.index, 2u);
    EXPECT_EQ(s.count, 5u);
    EXPECT_THROW(parse_shard("5/5"), std::invalid_argument);
    EXPECT_THROW(parse_shard("1/0"), std::invalid_argument);
    EXPECT_THROW(parse_shard("1"), std::invalid_argument);
    EXPECT_THROW(parse_shard("-1/3"), std::invalid_argument);
    EXPECT_THROW(parse_shard("a/3"), std::invalid_argument);
    // The number rule of configs: a leading zero and hexadecimal are named, not read.
    for (const char* text : {"01/4", "0/04", "0x1/4"}) {
        try {
            parse_shard(text);
            ADD_FAILURE() << text << " was read";
        } catch (const std::invalid_argument& e) {
            const std::string what = e.what();
            EXPECT_TRUE(what.find("leading zero") != std::string::npos || what.find("hexadecimal") != std::string::npos)
                << what;
        }
    }
    EXPECT_EQ(parse_shard("0/4").count, 4u);
}

TEST(ShardTest, FromSlurmArrayVariables) {
    unsetenv("SLURM_ARRAY_TASK_ID");
    unsetenv("SLURM_ARRAY_TASK_COUNT");
    unsetenv("SLURM_ARRAY_TASK_MIN");
    EXPECT_FALSE(shard_from_slurm());
    setenv("SLURM_ARRAY_TASK_ID", "3", 1);
    setenv("SLURM_ARRAY_TASK_COUNT", "4", 1);
    auto s = shard_from_slurm();
    ASSERT_TRUE(s);
    EXPECT_EQ(s->index, 3u);
    EXPECT_EQ(s->count, 4u);
    setenv("SLURM_ARRAY_TASK_MIN", "1", 1);  // --array=1-4
    s = shard_from_slurm();
    EXPECT_EQ(s->index, 2u);
    setenv("SLURM_ARRAY_TASK_ID", "5", 1);
    EXPECT_THROW(shard_from_slurm(), std::invalid_argument);
    unsetenv("SLURM_ARRAY_TASK_ID");
    unsetenv("SLURM_ARRAY_TASK_COUNT");
    unsetenv("SLURM_ARRAY_TASK_MIN");
}

}  // namespace
}  // namespace accelbench
