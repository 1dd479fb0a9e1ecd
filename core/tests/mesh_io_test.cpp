// load_mesh on tiny files of every format, written here byte by byte, so the expected
// counts, fan triangles and coordinates are known exactly.
#include "accelbench/scene/mesh_io.h"

#include "accelbench/base/temp_dir.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace accelbench {
namespace {

namespace fs = std::filesystem;
using Tri = std::array<uint32_t, 3>;

class MeshIoTest : public ::testing::Test {
protected:

    std::string write(const std::string& name, const std::string& bytes) {
        const std::string path = (dir_ / name).string();
        std::ofstream(path, std::ios::binary) << bytes;
        return path;
    }
    std::string write_gz(const std::string& name, const std::string& bytes) {
        const std::string path = (dir_ / name).string();
        gzFile out = gzopen(path.c_str(), "wb");
        gzwrite(out, bytes.data(), unsigned(bytes.size()));
        gzclose(out);
        return path;
    }
    // The message of the exception load_mesh throws (fails the test if it does not).
    std::string load_error(const std::string& path) {
        try {
            load_mesh(path);
        } catch (const std::runtime_error& e) {
            return e.what();
        }
        ADD_FAILURE() << "load_mesh('" << path << "') did not throw";
        return "";
    }

    TempDir temp_{"mesh_io_test-"};
    const fs::path& dir_ = temp_.path();
};

template <class T>
void put(std::string& bytes, T value) {
    bytes.append(reinterpret_cast<const char*>(&value), sizeof value);
}

// A unit quad in z = 0 and a triangle above it: 5 vertices, a quad and a triangle.
const char* const kAsciiPly =
    "ply\n"
    "format ascii 1.0\n"
    "comment tiny test mesh\n"
    "element vertex 5\n"
    "property float x\nproperty float y\nproperty float z\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n"
    "end_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 2.25\n"
    "4 0 1 2 3\n"
    "3 0 1 4\n";

std::string binary_ply() {
    std::string b =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\n"
        "property float x\nproperty float y\nproperty float z\n"
        "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[4][3] = {{0, 0, 0}, {1.5f, 0, 0}, {0, -2, 0}, {0, 0, 3.25f}};
    for (auto& p : v)
        for (float c : p) put(b, c);
    for (Tri t : {Tri{0, 1, 2}, Tri{0, 2, 3}}) {
        put(b, uint8_t(3));
        for (uint32_t i : t) put(b, int32_t(i));
    }
    return b;
}

// Two triangles of the unit square as binary STL; the reader merges equal corners.
std::string binary_stl() {
    std::string b(80, ' ');
    put(b, uint32_t(2));
    const float tris[2][3][3] = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
    for (auto& t : tris) {
        for (float n : {0.0f, 0.0f, 1.0f}) put(b, n);
        for (auto& p : t)
            for (float c : p) put(b, c);
        put(b, uint16_t(0));
    }
    return b;
}

TEST_F(MeshIoTest, ObjQuadAndPentagonAreFanTriangulated) {
    const std::string path = write("shapes.obj",
                                   "# a quad and a pentagon\n"
                                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                   "v 0 0 1\nv 2 0 1\nv 3 1 1\nv 1 2 1\nv -1 1 1\n"
                                   "f 1 2 3 4\n"
                                   "f 5/1/1 6/2/2 7/3/3 8/4/4 9/5/5\n");
    MeshLoadInfo info;
    const Scene s = load_mesh(path, &info);
    EXPECT_EQ(s.name, "shapes");
    EXPECT_EQ(info.format, "obj");
    EXPECT_FALSE(info.compressed);
    ASSERT_EQ(s.vertex_count(), 9u);
    ASSERT_EQ(s.triangle_count(), 5u);
    EXPECT_EQ(info.file_faces, 2u);
    EXPECT_EQ(info.polygons, 2u);
    const std::vector<Tri> expected = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}, {4, 7, 8}};
    EXPECT_EQ(s.triangles, expected);
    EXPECT_EQ(s.vertices[6], Vec3(3, 1, 1));
    EXPECT_EQ(s.bounds, Bounds3(Vec3(-1, 0, 0), Vec3(3, 2, 1)));
}

TEST_F(MeshIoTest, AsciiPly) {
    MeshLoadInfo info;
    const Scene s = load_mesh(write("tiny.ply", kAsciiPly), &info);
    EXPECT_EQ(s.name, "tiny");
    EXPECT_EQ(info.format, "ply");
    ASSERT_EQ(s.vertex_count(), 5u);
    const std::vector<Tri> expected = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}};
    EXPECT_EQ(s.triangles, expected);
    EXPECT_EQ(s.vertices[4], Vec3(0.5f, 0.5f, 2.25f));
    EXPECT_EQ(info.polygons, 1u);
}

TEST_F(MeshIoTest, BinaryPly) {
    const Scene s = load_mesh(write("binary.ply", binary_ply()));
    ASSERT_EQ(s.vertex_count(), 4u);
    const std::vector<Tri> expected = {{0, 1, 2}, {0, 2, 3}};
    EXPECT_EQ(s.triangles, expected);
    EXPECT_EQ(s.vertices[1], Vec3(1.5f, 0, 0));
    EXPECT_EQ(s.vertices[2], Vec3(0, -2, 0));
    EXPECT_EQ(s.vertices[3], Vec3(0, 0, 3.25f));
}

TEST_F(MeshIoTest, Off) {
    const Scene s = load_mesh(write("tiny.off",
                                    "OFF\n"
                                    "5 2 0\n"
                                    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 -4\n"
                                    "4 0 1 2 3\n"
                                    "3 3 2 4\n"));
    ASSERT_EQ(s.vertex_count(), 5u);
    const std::vector<Tri> expected = {{0, 1, 2}, {0, 2, 3}, {3, 2, 4}};
    EXPECT_EQ(s.triangles, expected);
    EXPECT_EQ(s.vertices[4], Vec3(0.5f, 0.5f, -4));
}

TEST_F(MeshIoTest, AsciiStl) {
    MeshLoadInfo info;
    const Scene s = load_mesh(write("square.stl",
                                    "solid square\n"
                                    "  facet normal 0 0 1\n    outer loop\n"
                                    "      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
                                    "    endloop\n  endfacet\n"
                                    "  facet normal 0 0 1\n    outer loop\n"
                                    "      vertex 0 0 0\n      vertex 1 1 0\n      vertex 0 1 0.5\n"
                                    "    endloop\n  endfacet\n"
                                    "endsolid square\n"),
                              &info);
    EXPECT_EQ(info.format, "stl");
    ASSERT_EQ(s.triangle_count(), 2u);
    ASSERT_EQ(s.vertex_count(), 4u);  // STL repeats corners; equal positions are one vertex
    EXPECT_EQ(s.vertex(0, 0), Vec3(0, 0, 0));
    EXPECT_EQ(s.vertex(1, 1), Vec3(1, 1, 0));
    EXPECT_EQ(s.vertex(1, 2), Vec3(0, 1, 0.5f));
}

TEST_F(MeshIoTest, BinaryStl) {
    const Scene s = load_mesh(write("square.stl", binary_stl()));
    ASSERT_EQ(s.triangle_count(), 2u);
    ASSERT_EQ(s.vertex_count(), 4u);
    EXPECT_EQ(s.vertex(0, 1), Vec3(1, 0, 0));
    EXPECT_EQ(s.vertex(1, 2), Vec3(0, 1, 0));
}

TEST_F(MeshIoTest, GzipCompressedFilesKeepTheirInnerFormat) {
    // Decompressed copies go to the temporary directory: make it ours, to see it emptied.
    const fs::path scratch = dir_ / "scratch";
    fs::create_directory(scratch);
    const char* old_tmpdir = std::getenv("TMPDIR");
    const std::string saved = old_tmpdir ? old_tmpdir : "";
    setenv("TMPDIR", scratch.c_str(), 1);

    MeshLoadInfo info;
    const Scene ply = load_mesh(write_gz("packed.ply.gz", kAsciiPly), &info);
    EXPECT_TRUE(info.compressed);
    EXPECT_EQ(info.format, "ply");
    EXPECT_EQ(ply.name, "packed");
    EXPECT_EQ(ply.triangle_count(), 3u);
    EXPECT_EQ(ply.vertices[4], Vec3(0.5f, 0.5f, 2.25f));

    const Scene stl = load_mesh(write_gz("packed.stl.gz", binary_stl()));
    EXPECT_EQ(stl.triangle_count(), 2u);
    const bool left_behind = !fs::is_empty(scratch);
    if (old_tmpdir) setenv("TMPDIR", saved.c_str(), 1);
    else unsetenv("TMPDIR");
    EXPECT_FALSE(left_behind) << "the decompressed copy was not removed from " << scratch;
}

// Three triangles on one edge (a non-manifold "complex edge") and two triangles meeting
// only at one vertex (a bowtie): a half-edge mesh drops or splits these; we keep them all.
TEST_F(MeshIoTest, NonManifoldFacesAreAllKept) {
    const char* const faces =
        "3 0 1 2\n3 1 0 3\n3 0 1 4\n"  // edge 0-1 shared by three faces
        "3 5 6 7\n3 5 8 9\n";          // vertex 5 shared by two otherwise separate faces
    std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 10\n"
        "property float x\nproperty float y\nproperty float z\n"
        "element face 5\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0\n1 0 0\n0.5 1 0\n0.5 -1 0\n0.5 0 1\n"
        "3 0 0\n4 1 0\n4 -1 0\n2 1 0\n2 -1 0\n";
    ply += faces;
    const Scene s = load_mesh(write("nonmanifold.ply", ply));
    ASSERT_EQ(s.vertex_count(), 10u);
    const std::vector<Tri> expected = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {5, 6, 7}, {5, 8, 9}};
    EXPECT_EQ(s.triangles, expected);

    const Scene obj = load_mesh(write("nonmanifold.obj",
                                      "v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0\nv 0.5 0 1\n"
                                      "v 3 0 0\nv 4 1 0\nv 4 -1 0\nv 2 1 0\nv 2 -1 0\n"
                                      "f 1 2 3\nf 2 1 4\nf 1 2 5\nf 6 7 8\nf 6 9 10\n"));
    EXPECT_EQ(obj.triangles, expected);
    EXPECT_EQ(obj.vertex_count(), 10u);
}

TEST_F(MeshIoTest, UnreferencedVerticesAreKept) {
    const Scene s = load_mesh(write("extra.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 9 9 9\nf 1 2 3\n"));
    EXPECT_EQ(s.vertex_count(), 4u);  // the file's count, not the used count
    EXPECT_EQ(s.triangle_count(), 1u);
}

TEST_F(MeshIoTest, MissingFile) {
    const std::string path = (dir_ / "nope.ply").string();
    const std::string error = load_error(path);
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find("file not found"), std::string::npos) << error;
}

TEST_F(MeshIoTest, UnsupportedExtension) {
    const std::string error = load_error(write("mesh.3ds", "whatever"));
    EXPECT_NE(error.find("mesh.3ds"), std::string::npos) << error;
    EXPECT_NE(error.find("unsupported file extension"), std::string::npos) << error;
}

TEST_F(MeshIoTest, TruncatedBinaryPly) {
    const std::string whole = binary_ply();
    const std::string path = write("cut.ply", whole.substr(0, whole.size() - 7));
    const std::string error = load_error(path);
    EXPECT_NE(error.find(path), std::string::npos) << error;
    EXPECT_NE(error.find("corrupt or truncated"), std::string::npos) << error;
}

TEST_F(MeshIoTest, TruncatedAsciiPly) {
    const std::string whole = kAsciiPly;
    // OpenMesh's ASCII reader returns success here (it repeats the last face it read).
    const std::string error = load_error(write("cut.ply", whole.substr(0, whole.find("3 0 1 4"))));
    EXPECT_NE(error.find("cut.ply"), std::string::npos) << error;
    EXPECT_NE(error.find("corrupt or truncated"), std::string::npos) << error;

    const std::string in_vertices = load_error(write("cut2.ply", whole.substr(0, whole.find("0.5 0.5 2.25"))));
    EXPECT_NE(in_vertices.find("corrupt or truncated"), std::string::npos) << in_vertices;
}

// After a failed read OpenMesh's ASCII reader would go on with uninitialised corner
// counts (and could loop for billions of corners): the first failed read must stop it.
TEST_F(MeshIoTest, AsciiPlyWithSomethingThatIsNotANumber) {
    for (const auto& [from, to] : {std::pair{"1 1 0", "1 x 0"}, std::pair{"4 0 1 2 3", "4 0 1 ? 3"},
                                   std::pair{"3 0 1 4", "three 0 1 4"}}) {
        std::string ply = kAsciiPly;
        ply.replace(ply.find(from), std::string(from).size(), to);
        const std::string error = load_error(write("garbage.ply", ply));
        EXPECT_NE(error.find("corrupt or truncated"), std::string::npos) << to << ": " << error;
    }
}

TEST_F(MeshIoTest, TruncatedOff) {
    const std::string error = load_error(write("cut.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n"));
    EXPECT_NE(error.find("cut.off"), std::string::npos) << error;
    EXPECT_NE(error.find("corrupt or truncated"), std::string::npos) << error;
}

TEST_F(MeshIoTest, FaceWithAVertexThatDoesNotExist) {
    std::string ply = kAsciiPly;
    ply.replace(ply.find("3 0 1 4"), 7, "3 0 1 7");
    const std::string error = load_error(write("badindex.ply", ply));
    EXPECT_NE(error.find("face 1 refers to vertex 7 but the file has 5 vertices"), std::string::npos) << error;
}

TEST_F(MeshIoTest, TruncatedBinaryStl) {
    const std::string whole = binary_stl();
    const std::string error = load_error(write("cut.stl", whole.substr(0, whole.size() - 10)));
    EXPECT_NE(error.find("corrupt STL: as binary it declares 2 triangles (184 bytes) but the file has 174 bytes"),
              std::string::npos)
        << error;
}

TEST_F(MeshIoTest, CorruptGzip) {
    std::string packed;
    {
        const std::string path = write_gz("tmp.ply.gz", kAsciiPly);
        std::ifstream in(path, std::ios::binary);
        packed.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::string error = load_error(write("cut.ply.gz", packed.substr(0, packed.size() / 2)));
    EXPECT_NE(error.find("cut.ply.gz"), std::string::npos) << error;
    EXPECT_NE(error.find("gzip"), std::string::npos) << error;

    const std::string plain = load_error(write("plain.ply.gz", kAsciiPly));
    EXPECT_NE(plain.find("is not gzip-compressed"), std::string::npos) << plain;
}

TEST_F(MeshIoTest, NotAPlyFile) {
    const std::string error = load_error(write("text.ply", "hello\nworld\n"));
    EXPECT_NE(error.find("not a PLY file"), std::string::npos) << error;
}

TEST_F(MeshIoTest, EmptyMesh) {
    const std::string error = load_error(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"));
    EXPECT_NE(error.find("points.obj"), std::string::npos) << error;
    EXPECT_NE(error.find("empty mesh (no triangles)"), std::string::npos) << error;
}

// OpenMesh's OBJ reader drops a face whose corners repeat; the load must fail, not lose it.
TEST_F(MeshIoTest, FaceDroppedByTheReaderIsAnError) {
    const std::string error = load_error(write("repeat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 2\n"));
    EXPECT_NE(error.find("the file has 2 faces but the reader delivered 1"), std::string::npos) << error;
}

TEST_F(MeshIoTest, DegenerateStlTriangleDroppedByTheReaderIsAnError) {
    const std::string error = load_error(write("flat.stl",
                                               "solid flat\n"
                                               "facet normal 0 0 1\nouter loop\n"
                                               "vertex 0 0 0\nvertex 1 0 0\nvertex 1 0 0\n"
                                               "endloop\nendfacet\n"
                                               "facet normal 0 0 1\nouter loop\n"
                                               "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                                               "endloop\nendfacet\n"
                                               "endsolid flat\n"));
    EXPECT_NE(error.find("the file has 2 faces but the reader delivered 1"), std::string::npos) << error;
    EXPECT_NE(error.find("same position"), std::string::npos) << error;
}

// Forty undefined materials make OpenMesh's OBJ reader print forty warnings; they are
// collected and the terminal sees one summary line.
TEST_F(MeshIoTest, ReaderWarningsBecomeOneSummaryLine) {
    std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    for (int i = 0; i < 40; ++i) obj += "usemtl missing" + std::to_string(i) + "\nf 1 2 3\n";
    const std::string path = write("noisy.obj", obj);
    MeshLoadInfo info;
    testing::internal::CaptureStderr();
    const Scene s = load_mesh(path, &info);
    const std::string printed = testing::internal::GetCapturedStderr();
    EXPECT_EQ(s.triangle_count(), 40u);
    EXPECT_GE(info.reader_messages, 40u);
    EXPECT_EQ(std::count(printed.begin(), printed.end(), '\n'), 1) << printed;
    EXPECT_NE(printed.find("noisy.obj"), std::string::npos) << printed;
}

}  // namespace
}  // namespace accelbench
