// The library's folders are layers: base <- scene <- accel <- render <- verify. A file may
// include its own layer and the layers before it, never one after it, so that the tree
// shows the architecture (README, "Layout"). Inside accel, a structure's folder
// (accel/bvh, accel/kdtree, accel/baseline) includes only the interface (accel/*.h) and
// its own folder; only the factory, accel/registry.cpp, knows the structures. Nothing
// under core/ includes the harness. plugin/ holds the plugins' C header, which includes
// nothing of ours: a bottom layer beside base.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "include_scan.h"

namespace fs = std::filesystem;

namespace {

const std::map<std::string, int> kLayer = {{"plugin", 0}, {"base", 0},   {"scene", 1},
                                           {"accel", 2},  {"render", 3}, {"verify", 4}};

// "accel/bvh/bvh.h" -> {"accel", "accel/bvh"}; "base/geometry.h" -> {"base", "base"}.
std::pair<std::string, std::string> layer_and_folder(const fs::path& rel) {
    const std::string layer = rel.begin()->string();
    return {layer, rel.parent_path().generic_string()};
}

fs::path library_dir() {
    const char* src = std::getenv("ACCELBENCH_SOURCE_DIR");
    return fs::path(src ? src : ".") / "core" / "accelbench";
}

}  // namespace

TEST(Layering, EveryIncludePointsToItsOwnLayerOrBelow) {
    const fs::path root = library_dir();
    ASSERT_TRUE(fs::is_directory(root)) << root;
    int files = 0;
    std::vector<std::string> violations;
    for (const auto& e : fs::recursive_directory_iterator(root)) {
        if (!e.is_regular_file()) continue;
        const fs::path rel = fs::relative(e.path(), root);
        if (rel.parent_path().empty()) {
            violations.push_back(rel.string() + ": a file directly in core/accelbench (belongs in a layer)");
            continue;
        }
        const auto [layer, folder] = layer_and_folder(rel);
        ASSERT_TRUE(kLayer.count(layer)) << "unknown layer folder " << layer << " (" << rel << ")";
        ++files;
        for (const auto& inc : accelbench::testing::quoted_includes(e.path())) {
            const std::string where = rel.string() + ":" + std::to_string(inc.line) + " ";
            const std::string prefix = "accelbench/";
            if (inc.path.rfind(prefix, 0) != 0) {
                violations.push_back(where + "includes a header outside the library: " + inc.path);
                continue;
            }
            const fs::path target(inc.path.substr(prefix.size()));
            if (target.parent_path().empty() || !kLayer.count(target.begin()->string())) {
                violations.push_back(where + "includes " + target.string() + ", not in a layer");
                continue;
            }
            const auto [t_layer, t_folder] = layer_and_folder(target);
            if (kLayer.at(t_layer) > kLayer.at(layer))
                violations.push_back(where + "(" + layer + ") includes a later layer: " + target.string());
            // Structures know the interface and themselves; only the registry knows them all.
            const bool in_structure = layer == "accel" && folder != "accel";
            const bool to_structure = t_layer == "accel" && t_folder != "accel";
            if (to_structure && folder != t_folder && rel.generic_string() != "accel/registry.cpp" && layer == "accel")
                violations.push_back(where + "a structure folder includes another's: " + target.string());
            if (in_structure && t_folder == "accel" && target.filename() == "registry.h")
                violations.push_back(where + "a structure includes the factory (registry.h)");
        }
    }
    EXPECT_GT(files, 40);
    for (const std::string& v : violations) ADD_FAILURE() << v;
}
