// The results CSV: quoting, the column list, appending, what --resume keeps, and merge.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>

#include "accelbench/accel/baseline/embree_accel.h"
#include "accelbench/accel/registry.h"
#include "csv/csv.h"
#include "csv/provenance.h"
#include "csv/results.h"
#include "csv/run_inputs.h"
#include "harness_test_util.h"
#include "util/output_lock.h"

namespace accelbench {
namespace {

using namespace testing_util;
namespace fs = std::filesystem;

TEST(CsvTest, QuotesOnlyWhatNeedsIt) {
    EXPECT_EQ(csv_field("plain"), "plain");
    EXPECT_EQ(csv_field("a,b"), "\"a,b\"");
    EXPECT_EQ(csv_field("say \"hi\""), "\"say \"\"hi\"\"\"");
    EXPECT_EQ(csv_field("two\nlines"), "\"two\nlines\"");
    EXPECT_EQ(csv_line({"a", "", "c,d"}), "a,,\"c,d\"\n");
}

TEST(CsvTest, ReadsBackWhatItWritesAndNoticesATruncatedLine) {
    TempDir dir("accelbench-csv-test-");
    const std::vector<std::string> row = {"x,y", "say \"hi\"", "two\nlines", ""};
    const std::string text = csv_line({"a", "b", "c", "d"}) + csv_line(row) + "1,2,3,4\n5,6";
    const std::string path = write_file(dir.path(), "t.csv", text);
    const CsvData d = read_csv(path);
    EXPECT_EQ(d.header, (std::vector<std::string>{"a", "b", "c", "d"}));
    ASSERT_EQ(d.rows.size(), 2u);
    EXPECT_EQ(d.rows[0], row);
    EXPECT_TRUE(d.incomplete_tail);
    EXPECT_EQ(d.complete_bytes, text.size() - 3);
    write_file(dir.path(), "bad.csv", "a,b\n1,2,3\n");
    EXPECT_THROW(read_csv((dir.path() / "bad.csv").string()), std::runtime_error);
}

TEST(ResultsTest, TheIssueColumnsAndOneColumnPerParameterOfEveryAccelerator) {
    const auto cols = result_columns();
    for (const char* c : {"config",        "model",           "triangles",      "vertices",       "accel",
                          "params",        "status",          "message",        "repetitions",    "build_s_median",
                          "build_s_mean",  "build_s_stddev",  "build_s_ci_lo",  "build_s_ci_hi",  "render_s_median",
                          "render_s_mean", "render_s_stddev", "render_s_ci_lo", "render_s_ci_hi", "rays",
                          "hits",          "shadow_rays",     "shadow_hits",    "mrays_per_s",    "nodes",
                          "leaves",        "tree_depth",      "memory_bytes",   "sah_cost",       "prim_tests",
                          "node_visits",   "git_sha",         "git_dirty",      "compiler",       "build_type",
                          "cpu",           "render_threads",  "embree_version", "timestamp",      "isa",
                          "embree_isa",    "fp_mode",         "combo_id"})
        EXPECT_NE(std::find(cols.begin(), cols.end(), c), cols.end()) << c;
    // One column per parameter name of every accelerator, between `params` and `status`,
    // headed by the bare name.
    const auto first = std::find(cols.begin(), cols.end(), "params") + 1;
    const auto last = std::find(cols.begin(), cols.end(), "status");
    std::set<std::string> names;
    for (const auto& info : accelerator_registry())
        for (const auto& p : info.params) names.insert(p.name);
    EXPECT_EQ(size_t(last - first), names.size());
    for (const auto& n : names) {
        EXPECT_EQ(std::count(first, last, param_column(n)), 1) << n;
        EXPECT_EQ(column_header(param_column(n)), n);
    }
    EXPECT_EQ(std::set<std::string>(cols.begin(), cols.end()).size(), cols.size()) << "a column key appears twice";
    EXPECT_EQ(column_header("tree_depth"), "tree_depth");
    EXPECT_EQ(column_header(param_column("max_depth")), "max_depth");
    EXPECT_EQ(repetitions_path("results/runs/x-1.csv"), "results/runs/x-1.reps.csv");
}

// Every header text once, so that pandas (which renames a repeat `name.1`), csv.DictReader
// (which keeps the last) and spreadsheets read each column by its name.
TEST(ColumnTableTest, EveryHeaderTextIsThereOnce) {
    const auto table = result_column_table();
    EXPECT_NO_THROW(check_column_names(table));
    std::set<std::string> names;
    for (const auto& c : table) EXPECT_TRUE(names.insert(c.name).second) << c.name;
    EXPECT_EQ(column_headers(result_columns()).size(), names.size());
    for (const auto& c : table) {
        EXPECT_FALSE(c.text.empty()) << c.name;
        EXPECT_EQ(c.key() == c.name, c.kind != ColumnKind::Parameter) << c.name;
    }
    // The parameters keep their names; the measured and global columns took new ones.
    for (const char* kept : {"max_depth", "threads", "width"})
        EXPECT_EQ(std::count(names.begin(), names.end(), kept), 1) << kept;
    for (const auto& r : renamed_columns()) EXPECT_TRUE(names.count(r.new_name)) << r.new_name;
    // An old name after `status` marks a file from before the renames: no measured or global
    // column may take one again.
    for (const auto& c : table) {
        if (c.kind == ColumnKind::Parameter) continue;
        for (const auto& r : renamed_columns()) EXPECT_NE(c.name, r.old_name);
    }
}

TEST(ColumnTableTest, ATableWithANameTwiceIsRefusedNamingIt) {
    auto table = result_column_table();
    // A parameter named like a measured column: what the old header had.
    table.push_back({"tree_depth", ColumnKind::Number, "levels", "a second depth"});
    table.insert(table.begin() + 3, {"status", ColumnKind::Parameter, "", "parameter of x: y"});
    try {
        check_column_names(table);
        FAIL() << "a table with two names twice passed";
    } catch (const std::logic_error& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("'tree_depth' at columns"), std::string::npos) << what;
        EXPECT_NE(what.find("'status' at columns 4 "), std::string::npos) << what;
    }
}

// The header the harness wrote before the renames: each of max_depth, width and threads
// twice, the parameter's between params and status and the measured or global one after.
const std::string kOldHeader =
    "config,combo_id,accel,params,max_depth,threads,width,status,rays,max_depth,width,height,threads,isa\n";
const std::string kNewHeader =
    "config,combo_id,accel,label,params,max_depth,threads,width,status,rays,tree_depth,image_width,image_height,"
    "render_threads,isa,embree_isa,plugin_file,plugin_sha256,plugin_version\n";

TEST(ConvertTest, RenamesByPositionKeepingEveryValueAndTheRepetitions) {
    TempDir dir("accelbench-convert-test-");
    const std::string rows =
        "t,1,kdtree,max_depth=5,5,,,ok,10,5,64,48,2,sse2\n"
        "t,2,wbvh,width=4,,,4,ok,10,17,64,48,2,\"a,b\"\n"
        "t,3,lbvh,threads=3,,3,,skipped,,,,,1,sse2\n";
    const auto old_csv = write_file(dir.path(), "old.csv", kOldHeader + rows);
    write_file(dir.path(), "old.reps.csv", "combo_id,repetition\n1,1\n2,1\n");
    EXPECT_TRUE(is_old_results_header(read_csv(old_csv).header));
    const std::string new_csv = (dir.path() / "sub" / "new.csv").string();
    EXPECT_EQ(convert_results(old_csv, new_csv), 3u);
    // The label column is added after accel, the registry's label of each row.
    EXPECT_EQ(read_file(new_csv),
              kNewHeader +
                  "t,1,kdtree,kd-tree,max_depth=5,5,,,ok,10,5,64,48,2,sse2,unknown,,,\n"
                  "t,2,wbvh,\"wide BVH (4, SIMD)\",width=4,,,4,ok,10,17,64,48,2,\"a,b\",unknown,,,\n"
                  "t,3,lbvh,LBVH,threads=3,,3,,skipped,,,,,1,sse2,unknown,,,\n");
    EXPECT_EQ(read_file(repetitions_path(new_csv)), "combo_id,repetition\n1,1\n2,1\n");
    EXPECT_FALSE(is_old_results_header(read_csv(new_csv).header));
    // A file already new, and the output being the input, are refused.
    EXPECT_THROW(convert_results(new_csv, (dir.path() / "again.csv").string()), std::runtime_error);
    EXPECT_THROW(convert_results(old_csv, old_csv), std::runtime_error);
    EXPECT_EQ(read_file(old_csv), kOldHeader + rows);
    // An existing output, or its repetitions file, is never written over.
    const auto kept = write_file(dir.path(), "kept.csv", "a run's results\n");
    EXPECT_THROW(convert_results(old_csv, kept), std::runtime_error);
    EXPECT_EQ(read_file(kept), "a run's results\n");
    const std::string bare = (dir.path() / "bare.csv").string();
    write_file(dir.path(), "bare.reps.csv", "combo_id,repetition\n");
    EXPECT_THROW(convert_results(old_csv, bare), std::runtime_error);
    EXPECT_FALSE(std::filesystem::exists(bare));
}

TEST(ConvertTest, AFileWithCurrentNamesButNoLabelGetsTheRegistrysLabels) {
    TempDir dir("accelbench-convert-test-");
    const auto old_csv = write_file(dir.path(), "old.csv",
                                    "config,combo_id,accel,params,split,status,tree_depth\n"
                                    "t,1,bvh,split=sah,sah,ok,7\n"
                                    "t,2,gone,,,ok,3\n"
                                    "t,3,kdtree,max_depth=auto,,ok,9\n");
    EXPECT_TRUE(is_old_results_header(read_csv(old_csv).header));
    const std::string new_csv = (dir.path() / "new.csv").string();
    EXPECT_EQ(convert_results(old_csv, new_csv), 3u);
    // A structure the registry no longer has gets an empty label; "auto" stays the structure's.
    EXPECT_EQ(read_file(new_csv),
              "config,combo_id,accel,label,params,split,status,tree_depth\n"
              "t,1,bvh,BVH (binned SAH),split=sah,sah,ok,7\n"
              "t,2,gone,,,,ok,3\n"
              "t,3,kdtree,kd-tree,max_depth=auto,,ok,9\n");
}

// A file from before fp_mode and embree_isa: older rows traced in IEEE mode (the harness set
// no mode), and which kernels Embree ran is not known.
TEST(ConvertTest, AFileWithoutTheFloatingPointModeOrEmbreesIsaGetsIeeeAndUnknown) {
    TempDir dir("accelbench-convert-test-");
    const auto old_csv = write_file(dir.path(), "old.csv",
                                    "config,combo_id,accel,label,params,status,light,shading,cpu,isa,x\n"
                                    "t,1,bvh,BVH,,ok,true,false,c,avx2,7\n"
                                    "t,2,bvh,BVH,,skipped,,,c,avx2,\n");
    EXPECT_TRUE(is_old_results_header(read_csv(old_csv).header));
    EXPECT_NE(old_header_message(old_csv, read_csv(old_csv).header).find("fp_mode, embree_isa"), std::string::npos);
    const std::string new_csv = (dir.path() / "new.csv").string();
    EXPECT_EQ(convert_results(old_csv, new_csv), 2u);
    EXPECT_EQ(read_file(new_csv),
              "config,combo_id,accel,label,params,status,light,shading,fp_mode,cpu,isa,embree_isa,plugin_file,"
              "plugin_sha256,plugin_version,x\n"
              "t,1,bvh,BVH,,ok,true,false,ieee,c,avx2,unknown,,,,7\n"
              "t,2,bvh,BVH,,skipped,,,ieee,c,avx2,unknown,,,,\n");
    EXPECT_FALSE(is_old_results_header(read_csv(new_csv).header));
}

// A file from before compile_flags: the flags of the build that measured it are not known.
// Converted, its rows say `unknown`, a build of their own that merges with no known one.
TEST(ConvertTest, AFileFromBeforeTheFlagsGetsUnknownAndMixesWithNoKnownBuild) {
    TempDir dir("accelbench-convert-test-");
    const std::string prov = "git_sha,git_dirty,compiler,build_type,cpu,embree_version,isa,embree_isa";
    const std::string plugins = ",plugin_file,plugin_sha256,plugin_version\n";
    const auto old_csv = write_file(dir.path(), "old.csv",
                                    "config,combo_id,accel,label,params,status," + prov + plugins +
                                        "t,1,bvh,BVH,,ok,abc,false,gcc 12,RelWithDebInfo,c,3.13.5,avx2,avx2,,,\n");
    write_inputs(old_csv, {{"config", std::string(64, 'c'), "t"}});
    EXPECT_NE(old_header_message(old_csv, read_csv(old_csv).header).find("before the columns compile_flags"),
              std::string::npos);
    const std::string new_csv = (dir.path() / "new.csv").string();
    EXPECT_EQ(convert_results(old_csv, new_csv), 1u);
    const std::string header =
        "config,combo_id,accel,label,params,status,git_sha,git_dirty,compiler,build_type,compile_flags,cpu,"
        "embree_version,isa,embree_isa" +
        plugins;
    EXPECT_EQ(read_file(new_csv),
              header + "t,1,bvh,BVH,,ok,abc,false,gcc 12,RelWithDebInfo,unknown,c,3.13.5,avx2,avx2,,,\n");
    const auto known =
        write_file(dir.path(), "known.csv",
                   header + "t,2,bvh,BVH,,ok,abc,false,gcc 12,RelWithDebInfo,-O3,c,3.13.5,avx2,avx2,,,\n");
    write_inputs(known, {{"config", std::string(64, 'c'), "t"}});
    const std::string merged = (dir.path() / "merged.csv").string();
    try {
        merge_results(merged, {new_csv, known}, false);
        ADD_FAILURE() << "merged unknown flags with known ones";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("column compile_flags differs"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("'unknown' (" + new_csv + ")"), std::string::npos) << e.what();
    }
    EXPECT_EQ(merge_results(merged, {new_csv, known}, true), 2u);
}

TEST(ConvertTest, ResumeAndMergeOfAnOldFileSayWhatWasRenamedAndHowToConvert) {
    TempDir dir("accelbench-convert-test-");
    const auto old_csv = write_file(dir.path(), "old.csv", kOldHeader + "t,1,bvh,,,,,ok,1,3,8,8,1,sse2\n");
    std::vector<std::string> current = read_csv(write_file(dir.path(), "n.csv", kNewHeader)).header;
    auto expect_message = [&](auto&& f) {
        try {
            f();
            FAIL() << "an old header was accepted";
        } catch (const std::runtime_error& e) {
            const std::string what = e.what();
            for (const char* part : {"max_depth -> tree_depth", "width -> image_width", "height -> image_height",
                                     "threads -> render_threads", "accelbench convert-csv "})
                EXPECT_NE(what.find(part), std::string::npos) << part << " in: " << what;
            EXPECT_NE(what.find(old_csv), std::string::npos) << what;
        }
    };
    expect_message([&] { prepare_resume(old_csv, current, {"combo_id"}); });
    expect_message([&] { CsvAppender(old_csv, current); });
    expect_message([&] { merge_results((dir.path() / "m.csv").string(), {old_csv}, true); });
}

TEST(ResultsTest, AppenderWritesTheHeaderOnceAndRejectsUnknownColumns) {
    TempDir dir("accelbench-results-test-");
    const std::string path = (dir.path() / "sub" / "r.csv").string();
    {
        CsvAppender a(path, {"combo_id", "status", "message"});
        a.append({{"combo_id", "1"}, {"status", "ok"}});
        EXPECT_THROW(a.append({{"combo_id", "2"}, {"stauts", "ok"}}), std::logic_error);
    }
    {
        CsvAppender again(path, {"combo_id", "status", "message"});
        again.append({{"combo_id", "3"}, {"message", "a, b"}});
    }
    EXPECT_EQ(read_file(path), "combo_id,status,message\n1,ok,\n3,,\"a, b\"\n");
    EXPECT_THROW(CsvAppender(path, {"combo_id", "status"}), std::runtime_error);
}

TEST(ResultsTest, ResumeCutsATruncatedLineAndForgetsUnfinishedRepetitions) {
    TempDir dir("accelbench-results-test-");
    const std::vector<std::string> cols = {"combo_id", "status"}, rep_cols = {"combo_id", "repetition"};
    const std::string path = write_file(dir.path(), "r.csv", "combo_id,status\na,ok\nb,skipped\nc,o");
    // c's repetitions were written, its results row was cut short: c runs again.
    write_file(dir.path(), "r.reps.csv", "combo_id,repetition\na,1\na,2\nc,1\nc,2\n");
    const auto done = prepare_resume(path, cols, rep_cols);
    EXPECT_EQ(done, (std::set<std::string>{"a", "b"}));
    EXPECT_EQ(read_file(path), "combo_id,status\na,ok\nb,skipped\n");
    EXPECT_EQ(read_file((dir.path() / "r.reps.csv").string()), "combo_id,repetition\na,1\na,2\n");
    EXPECT_TRUE(prepare_resume((dir.path() / "none.csv").string(), cols, rep_cols).empty());
    EXPECT_THROW(prepare_resume(path, {"combo_id", "status", "new_column"}, rep_cols), std::runtime_error);
}

class MergeTest : public ::testing::Test {
protected:
    TempDir dir{"accelbench-merge-test-"};
    std::string shard(const std::string& name, const std::vector<std::pair<std::string, std::string>>& rows,
                      const std::string& flags = "-O3") {
        std::string text =
            "combo_id,status,git_sha,git_dirty,compiler,build_type,compile_flags,cpu,embree_version,isa,embree_isa\n";
        std::string reps = "combo_id,repetition\n";
        for (const auto& [id, sha] : rows) {
            text +=
                id + ",ok," + sha + ",false,gcc 12,RelWithDebInfo," + flags + ",\"Xeon, 2 cores\",3.13.5,sse2,avx2\n";
            reps += id + ",1\n";
        }
        write_file(dir.path(), name + ".reps.csv", reps);
        const std::string path = write_file(dir.path(), name + ".csv", text);
        write_inputs(path, {{"config", std::string(64, 'c'), "grid"}});
        return path;
    }
    std::string out() const { return (dir.path() / "merged.csv").string(); }
    // A run's results file with the instructions column, as make regress's timed and
    // callgrind runs write it; both runs of one config share their record of inputs.
    static constexpr const char* kInstructionsHeader =
        "combo_id,status,instructions,git_sha,git_dirty,compiler,build_type,compile_flags,cpu,embree_version,isa,"
        "embree_isa\n";
    std::string write_run(const std::string& name, const std::string& rows) {
        const std::string path = write_file(dir.path(), name, kInstructionsHeader + rows);
        write_inputs(path, {{"config", std::string(64, 'c'), "ci"}});
        return path;
    }
};

TEST_F(MergeTest, JoinsShardsAndTheirRepetitions) {
    const auto a = shard("a", {{"1", "abc"}, {"2", "abc"}});
    const auto b = shard("b", {{"3", "abc"}});
    EXPECT_EQ(merge_results(out(), {a, b}, false), 3u);
    const CsvData m = read_csv(out());
    ASSERT_EQ(m.rows.size(), 3u);
    EXPECT_EQ(m.rows[2][0], "3");
    EXPECT_EQ(m.rows[2][7], "Xeon, 2 cores");
    EXPECT_EQ(read_csv(repetitions_path(out())).rows.size(), 3u);
}

TEST_F(MergeTest, RefusesMixedProvenanceUnlessAllowed) {
    const auto a = shard("a", {{"1", "abc"}});
    const auto b = shard("b", {{"2", "def"}});
    try {
        merge_results(out(), {a, b}, false);
        FAIL() << "mixed provenance merged";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("column git_sha differs"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("--allow-mixed"), std::string::npos);
    }
    EXPECT_FALSE(fs::exists(out()));
    EXPECT_EQ(merge_results(out(), {a, b}, true), 2u);
}

// Two builds of one commit, build type and compiler differing only in their flags (-O2
// against -O3, an added -march=native) are two builds: merge and --take-column refuse them.
TEST_F(MergeTest, RefusesBuildsDifferingOnlyInFlagsUnlessAllowed) {
    const auto a = shard("a", {{"1", "abc"}});
    for (const std::string flags : {"-O2", "-O3 -march=native"}) {
        const auto b = shard("b", {{"2", "abc"}}, flags);
        try {
            merge_results(out(), {a, b}, false);
            ADD_FAILURE() << "merged -O3 with " << flags;
        } catch (const std::runtime_error& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("column compile_flags differs"), std::string::npos) << what;
            EXPECT_NE(what.find("'" + flags + "' (" + b + ")"), std::string::npos) << what;
        }
        EXPECT_FALSE(fs::exists(out()));
    }
    EXPECT_EQ(merge_results(out(), {a, shard("b", {{"2", "abc"}}, "-O2")}, true), 2u);
    const auto timed = write_run("timed.csv", "1,ok,,abc,false,gcc 12,RelWithDebInfo,-O3,x,3.13.5,sse2,avx2\n");
    const auto cg = write_run("cg.csv", "1,ok,100,abc,false,gcc 12,RelWithDebInfo,-O2,x,3.13.5,sse2,avx2\n");
    EXPECT_THROW(take_column((dir.path() / "t.csv").string(), timed, cg, "instructions", false), std::runtime_error);
    EXPECT_EQ(take_column((dir.path() / "t.csv").string(), timed, cg, "instructions", true), 1u);
}

TEST_F(MergeTest, RefusesACombinationInTwoInputs) {
    const auto a = shard("a", {{"1", "abc"}});
    const auto b = shard("b", {{"1", "abc"}});
    EXPECT_THROW(merge_results(out(), {a, b}, false), std::runtime_error);
}

// The timed run's rows with the instructions of a callgrind run, matched by combo_id.
TEST_F(MergeTest, TakeColumnCopiesOneColumnByComboId) {
    const std::string header = kInstructionsHeader;
    const std::string prov = ",abc,false,gcc 12,RelWithDebInfo,-O3,x,3.13.5,sse2,avx2\n";
    const auto timed = write_run("timed.csv", "1,ok," + prov + "2,ok," + prov + "3,skipped," + prov);
    write_file(dir.path(), "timed.reps.csv", "combo_id,repetition\n1,1\n");
    const auto cg = write_run("cg.csv", "2,ok,200" + prov + "1,ok,100" + prov + "3,skipped," + prov);
    EXPECT_EQ(take_column(out(), timed, cg, "instructions", false), 2u);
    EXPECT_EQ(read_file(out()), header + "1,ok,100" + prov + "2,ok,200" + prov + "3,skipped," + prov);
    EXPECT_EQ(read_file(repetitions_path(out())), "combo_id,repetition\n1,1\n");
    EXPECT_THROW(take_column(out(), timed, cg, "no_such_column", false), std::runtime_error);
    const auto other = write_run("other.csv", "1,ok,100,def,false,gcc 12,RelWithDebInfo,-O3,x,3.13.5,sse2,avx2\n");
    EXPECT_THROW(take_column(out(), timed, other, "instructions", false), std::runtime_error);
    const auto twice = write_run("twice.csv", "1,ok,100" + prov + "1,ok,101" + prov);
    EXPECT_THROW(take_column(out(), timed, twice, "instructions", false), std::runtime_error);
}

// Under valgrind Embree sees no AVX-512 and runs its AVX2 kernels: the callgrind run of the
// same build differs from the timed run in embree_isa only, and the timed run's value stays.
TEST_F(MergeTest, TakeColumnAcceptsAnotherEmbreeIsaAndKeepsTheTimedRuns) {
    const std::string header = kInstructionsHeader;
    const std::string prov = ",abc,false,gcc 12,RelWithDebInfo,-O3,x,3.13.5,sse2,";
    const auto timed = write_run("timed.csv", "1,ok," + prov + "avx512\n");
    const auto cg = write_run("cg.csv", "1,ok,100" + prov + "avx2\n");
    EXPECT_EQ(take_column(out(), timed, cg, "instructions", false), 1u);
    EXPECT_EQ(read_file(out()), header + "1,ok,100" + prov + "avx512\n");
    // Any other provenance column still refuses.
    const auto other = write_run("other.csv", "1,ok,100,abc,false,gcc 12,RelWithDebInfo,-O3,x,3.13.5,avx2,avx2\n");
    EXPECT_THROW(take_column(out(), timed, other, "instructions", false), std::runtime_error);
}

TEST_F(MergeTest, RefusesAShardARunIsStillWriting) {
    const auto a = shard("a", {{"1", "abc"}});
    const auto b = shard("b", {{"2", "abc"}});
    {
        const OutputLock running({repetitions_path(b)});
        EXPECT_THROW(
            try {
                merge_results(out(), {a, b}, true);
            } catch (const std::runtime_error& e) {
                EXPECT_NE(std::string(e.what()).find("being written"), std::string::npos) << e.what();
                throw;
            },
            std::runtime_error);
    }
    EXPECT_FALSE(fs::exists(out()));
    EXPECT_EQ(merge_results(out(), {a, b}, false), 2u);
    EXPECT_EQ(read_inputs(out()), read_inputs(a));
}

TEST_F(MergeTest, RefusesInputsWithoutARecordOrOfOtherContentsUnlessAllowed) {
    const auto a = shard("a", {{"1", "abc"}});
    const auto b = shard("b", {{"2", "abc"}});
    write_inputs(b, {{"config", std::string(64, 'd'), "grid"}});
    EXPECT_THROW(merge_results(out(), {a, b}, false), std::runtime_error);
    remove_inputs(b);
    EXPECT_THROW(merge_results(out(), {a, b}, false), std::runtime_error);
    EXPECT_THROW(take_column(out(), a, b, "status", false), std::runtime_error);
    EXPECT_FALSE(fs::exists(out()));
    EXPECT_EQ(merge_results(out(), {a, b}, true), 2u);
    EXPECT_FALSE(fs::exists(inputs_path(out())));  // unknown contents: no record
}

// The values every row records are the columns merge and the analysis compare, in the
// header's order: `accelbench provenance` (which the reproduce driver asks before resuming
// a run) then names exactly what the rows carry.
TEST(ProvenanceTest, ValuesAreTheProvenanceColumnsInHeaderOrder) {
    std::vector<std::string> names;
    for (const auto& [name, value] : provenance_values()) {
        names.push_back(name);
        EXPECT_FALSE(value.empty()) << name;
    }
    EXPECT_EQ(names, provenance_columns());
    std::vector<std::string> in_header;
    for (const auto& c : result_columns())
        if (std::find(names.begin(), names.end(), c) != names.end()) in_header.push_back(c);
    EXPECT_EQ(in_header, names);
}

// Embree's kernel ISA is read from its verbose report, which goes to stdout: the value is
// one of its x86 targets (this machine has at least SSE2), and stdout works afterwards.
TEST(ProvenanceTest, EmbreeKernelIsaIsATargetAndStdoutIsRestored) {
    ::testing::internal::CaptureStdout();
    const std::string isa = EmbreeAccel::kernel_isa();
    std::printf("after\n");
    const std::string printed = ::testing::internal::GetCapturedStdout();
    EXPECT_EQ(printed, "after\n");  // none of Embree's report leaks
    const std::vector<std::string> targets = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
    EXPECT_NE(std::find(targets.begin(), targets.end(), isa), targets.end()) << isa;
    EXPECT_EQ(provenance().embree_isa, isa);
}

// max_isa caps the device's kernels: its report lists no target above the cap, and a row
// records what its Embree ran — each Embree row its own, or every row the kernels of the
// run's Embree rows when they share one cap (ci.yaml's avx2).
TEST(ProvenanceTest, EmbreeMaxIsaCapsTheKernelsAndTheRowsSayWhichRan) {
    const std::vector<std::string> targets = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
    const auto rank = [&](const std::string& isa) { return std::find(targets.begin(), targets.end(), isa); };
    const std::string best = EmbreeAccel::kernel_isa();
    for (const std::string cap : {"sse2", "avx2"}) {
        const std::string capped = EmbreeAccel::kernel_isa(cap);
        ASSERT_NE(rank(capped), targets.end()) << cap;
        EXPECT_EQ(capped, rank(cap) < rank(best) ? cap : best) << cap;
    }
    const auto params = [](const std::string& accel, const std::map<std::string, std::string>& given) {
        const AcceleratorInfo& info = *find_accelerator(accel);
        return resolve_params(accel, info.params, given);
    };
    const ParamSet avx2 = params("embree", {{"max_isa", "avx2"}}), wbvh = params("wbvh", {});
    EXPECT_EQ(row_embree_isa("embree", avx2, std::nullopt), EmbreeAccel::kernel_isa("avx2"));
    EXPECT_EQ(row_embree_isa("embree", params("embree", {}), std::nullopt), best);
    EXPECT_EQ(row_embree_isa("wbvh", wbvh, std::nullopt), best);
    const auto shared = embree_isa_of_rows({"avx2", "avx2"});
    ASSERT_TRUE(shared.has_value());
    EXPECT_EQ(row_embree_isa("wbvh", wbvh, shared), EmbreeAccel::kernel_isa("avx2"));
    EXPECT_FALSE(embree_isa_of_rows({"auto", "avx2"}).has_value());
    EXPECT_FALSE(embree_isa_of_rows({}).has_value());
}

}  // namespace
}  // namespace accelbench
