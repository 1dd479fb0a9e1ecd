// The derived-model cache: a transformed registry model is made once, read back from
// models/derived/ identically, and rebuilt when the source model changes.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>

#include "accelbench/scene/mesh_io.h"
#include "harness_test_util.h"
#include "plan/derived_model.h"
#include "util/sha256.h"

namespace accelbench {
namespace {

using namespace testing_util;
namespace fs = std::filesystem;

// An octahedron (8 triangles, closed) as an OBJ, scaled by `s`.
std::string octahedron_obj(int s) {
    const std::string p = std::to_string(s), m = std::to_string(-s);
    return "v " + p + " 0 0\nv " + m + " 0 0\nv 0 " + p + " 0\nv 0 " + m + " 0\nv 0 0 " + p + "\nv 0 0 " + m +
        "\nf 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
}

class DerivedModelTest : public ::testing::Test {
protected:
    TempDir project{"accelbench-derived-test-"};

    // A project whose registry has one model, the octahedron at scale `s`, in models/.
    ModelRegistry registry_with(int s) {
        fs::create_directories(project.path() / "models");
        const std::string obj = write_file(project.path() / "models", "octa.obj", octahedron_obj(s));
        const std::string yaml = write_file(project.path(), "models.yaml",
                                            "models:\n  - {name: octa, file: octa.obj, sha256: " + sha256_file(obj) +
                                                ", triangles: 8, vertices: 6, source: test, credit: test}\n");
        setenv("ACCELBENCH_PROJECT_DIR", project.path().c_str(), 1);
        ModelRegistry r = ModelRegistry::load(yaml);
        unsetenv("ACCELBENCH_PROJECT_DIR");
        return r;
    }
};

TEST_F(DerivedModelTest, MakesCachesAndReusesTheSubdividedModel) {
    const ModelRegistry r = registry_with(1);
    const ModelTransformSpec t{ModelTransformSpec::Kind::Subdivide, 2};
    const std::string path = derived_model_path(r, r.entries()[0], t);
    EXPECT_EQ(path, (project.path() / "models" / "derived" / "octa-subdivide-2.ply").string());
    EXPECT_FALSE(fs::exists(path));

    const Scene made = load_derived_scene(r, r.entries()[0], t);
    EXPECT_EQ(made.name, "octa@subdivide=2");
    EXPECT_EQ(made.triangle_count(), 8u * 16u);
    ASSERT_TRUE(fs::exists(path));
    const auto written = fs::last_write_time(path);

    const Scene cached = load_derived_scene(r, r.entries()[0], t);
    EXPECT_EQ(fs::last_write_time(path), written);  // read, not rebuilt
    EXPECT_EQ(cached.name, made.name);
    EXPECT_EQ(cached.triangles, made.triangles);
    ASSERT_EQ(cached.vertices.size(), made.vertices.size());
    for (size_t i = 0; i < made.vertices.size(); ++i) EXPECT_EQ(cached.vertices[i].x, made.vertices[i].x);
}

TEST_F(DerivedModelTest, ChangedSourceInvalidatesTheCache) {
    const ModelTransformSpec t{ModelTransformSpec::Kind::Subdivide, 1};
    const ModelRegistry small = registry_with(1);
    const Scene a = load_derived_scene(small, small.entries()[0], t);
    const ModelRegistry big = registry_with(2);  // same name, new file and checksum
    const Scene b = load_derived_scene(big, big.entries()[0], t);
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    EXPECT_EQ(b.bounds.upper.x, 2 * a.bounds.upper.x);  // made again from the new source
    const auto comments = read_ply_comments(derived_model_path(big, big.entries()[0], t));
    EXPECT_NE(std::find(comments.begin(), comments.end(), "source_sha256 " + big.entries()[0].sha256), comments.end());
}

TEST_F(DerivedModelTest, DecimatesToTheTarget) {
    const ModelRegistry r = registry_with(1);
    // An edge collapse of a closed mesh removes two triangles: 8 -> 6 -> 4.
    const Scene d = load_derived_scene(r, r.entries()[0], {ModelTransformSpec::Kind::Decimate, 4});
    EXPECT_EQ(d.triangle_count(), 4u);
    EXPECT_EQ(d.name, "octa@decimate=4");
}

TEST_F(DerivedModelTest, PartFilesOfDeadWritersAreRemovedOthersKept) {
    // A writer killed mid-write (at the time limit) leaves <path>.part<pid>: the next maker of
    // that model removes it; the part file of a live process (our parent) is left alone.
    const ModelRegistry r = registry_with(1);
    const ModelTransformSpec t{ModelTransformSpec::Kind::Subdivide, 1};
    const std::string path = derived_model_path(r, r.entries()[0], t);
    fs::create_directories(fs::path(path).parent_path());
    const pid_t child = fork();
    if (child == 0) _exit(0);
    ASSERT_GT(child, 0);
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);  // reaped: no process has that pid now
    const std::string dead = path + ".part" + std::to_string(child);
    // This process's own part file is the one the maker writes and renames; the parent is live.
    const std::string live = path + ".part" + std::to_string(getppid());
    const std::string other = path + ".partial-notes";
    for (const auto& f : {dead, live, other})
        write_file(fs::path(f).parent_path(), fs::path(f).filename().string(), "x");
    load_derived_scene(r, r.entries()[0], t);
    EXPECT_FALSE(fs::exists(dead));
    EXPECT_TRUE(fs::exists(live));
    EXPECT_TRUE(fs::exists(other));
    EXPECT_TRUE(fs::exists(path));
}

}  // namespace
}  // namespace accelbench
