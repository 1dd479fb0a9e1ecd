// The harness's folders are layers by role: util <- csv <- models <- config <- plan <- run <-
// sinks <- commands <- main.cpp. A file may include its own folder and the folders before
// it, never one after it, so that the tree shows the flow from a YAML file to a CSV row.
// Includes are written relative to harness/ ("csv/results.h"). bench/ stands beside
// commands: a benchmark program may use everything up to commands, and nothing includes it.
// The tests (harness/tests) may include every folder.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "include_scan.h"

namespace fs = std::filesystem;

namespace {

// main.cpp sits directly in harness/ and is the last layer; bench/ is beside commands.
const std::map<std::string, int> kLayer = {{"util", 0},  {"csv", 1},      {"models", 2}, {"config", 3},
                                           {"plan", 4},  {"run", 5},      {"sinks", 6},  {"commands", 7},
                                           {"bench", 7}, {"main.cpp", 8}, {"tests", 9}};

fs::path harness_dir() {
    const char* src = std::getenv("ACCELBENCH_SOURCE_DIR");
    return fs::path(src ? src : ".") / "harness";
}

}  // namespace

TEST(HarnessLayering, EveryIncludePointsToItsOwnFolderOrAnEarlierOne) {
    const fs::path root = harness_dir();
    ASSERT_TRUE(fs::is_directory(root)) << root;
    int files = 0;
    std::vector<std::string> violations;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
        if (!e.is_regular_file()) continue;
        const std::string ext = e.path().extension().string();
        if (ext != ".h" && ext != ".cpp") continue;
        const fs::path rel = fs::relative(e.path(), root);
        const std::string layer = rel.begin()->string();
        if (!kLayer.count(layer)) {
            violations.push_back(rel.string() + ": not in a role folder of harness/ (or not main.cpp)");
            continue;
        }
        ++files;
        for (const auto& inc : accelbench::testing::quoted_includes(e.path())) {
            const fs::path target(inc.path);
            const std::string where = rel.string() + ":" + std::to_string(inc.line) + " ";
            const std::string t_layer = target.begin()->string();
            if (t_layer == "accelbench") continue;  // the core library: below every harness folder
            if (layer == "tests" && target.parent_path().empty()) continue;  // the tests' own helpers
            if (target.parent_path().empty() || !kLayer.count(t_layer) || t_layer == "main.cpp") {
                violations.push_back(where + "includes " + target.string() + ", not a path inside a role folder");
                continue;
            }
            if (t_layer == "bench" || t_layer == "tests") {
                if (t_layer != layer) violations.push_back(where + "includes " + target.string() + " from " + t_layer);
                continue;
            }
            if (kLayer.at(t_layer) > kLayer.at(layer))
                violations.push_back(where + "(" + layer + ") includes a later folder: " + target.string());
        }
    }
    EXPECT_GT(files, 50);
    for (const std::string& v : violations) ADD_FAILURE() << v;
}
