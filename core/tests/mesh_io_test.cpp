// load_mesh on tiny files of every format, written here byte by byte, so the expected
// counts, fan triangles and coordinates are known exactly.
#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/mesh_reading.h"
#include "mesh_load_error.h"

#include "accelbench/base/temp_dir.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
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
    std::string load_error(const std::string& path) { return mesh_load_error(path); }

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

template <class T>
void put_at(std::string& bytes, size_t at, T value) {
    std::memcpy(bytes.data() + at, &value, sizeof value);
}

// The ASCII PLY's mesh in the other text formats.
const char* const kOff = "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 2.25\n4 0 1 2 3\n3 0 1 4\n";
const char* const kObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 2.25\nf 1 2 3 4\nf 1 2 5\n";

std::string ascii_stl() {
    return "solid square\n"
           "  facet normal 0 0 1\n    outer loop\n"
           "      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
           "    endloop\n  endfacet\n"
           "  facet normal 0 0 1\n    outer loop\n"
           "      vertex 0 0 0\n      vertex 1 1 0\n      vertex 0 1 0.5\n"
           "    endloop\n  endfacet\n"
           "endsolid square\n";
}

void expect_same_mesh(const Scene& a, const Scene& b, const std::string& what) {
    EXPECT_EQ(a.triangles, b.triangles) << what;
    ASSERT_EQ(a.vertex_count(), b.vertex_count()) << what;
    for (size_t i = 0; i < a.vertex_count(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]) << what << ", vertex " << i;
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
    MeshLoadInfo info;
    const Scene ply = load_mesh(write_gz("packed.ply.gz", kAsciiPly), &info);
    EXPECT_TRUE(info.compressed);
    EXPECT_EQ(info.format, "ply");
    EXPECT_EQ(ply.name, "packed");
    EXPECT_EQ(ply.triangle_count(), 3u);
    EXPECT_EQ(ply.vertices[4], Vec3(0.5f, 0.5f, 2.25f));
    const Scene stl = load_mesh(write_gz("packed.stl.gz", binary_stl()));
    EXPECT_EQ(stl.triangle_count(), 2u);
    expect_same_mesh(load_mesh(write("plain.obj", kObj)), load_mesh(write_gz("packed.OBJ.GZ", kObj)), "obj.gz");
    expect_same_mesh(load_mesh(write("plain.off", kOff)), load_mesh(write_gz("packed.off.gz", kOff)), "off.gz");
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

// ---- truncation: a file cut short is refused, never loaded with what is left ----------

// The ASCII formats that declare their counts (PLY, OFF) and ASCII STL (which must end
// with endsolid): every prefix of a valid file, cut anywhere before its last word, is
// refused; binary PLY and STL at every length. (OBJ declares nothing: a file cut between
// two lines is a shorter file, one cut inside a face's last index a different one.)
TEST_F(MeshIoTest, EveryPrefixOfAFileIsRefused) {
    const std::string stl_text = ascii_stl();
    const std::vector<std::pair<std::string, std::string>> files = {{"cut.ply", kAsciiPly},
                                                                    {"cut.off", kOff},
                                                                    {"cut.stl", stl_text},
                                                                    {"cutb.ply", binary_ply()},
                                                                    {"cutb.stl", binary_stl()}};
    for (const auto& [name, whole] : files) {
        const bool binary = name.find('b') != std::string::npos && name != "cut.ply";
        size_t must_refuse = binary ? whole.size() : whole.find_last_not_of(" \r\n");  // last word's last byte
        if (name == "cut.stl") must_refuse = whole.rfind("endsolid") + 8;
        SCOPED_TRACE(name);
        const std::string format = name.substr(name.size() - 3);
        const Scene full = parse_mesh(whole, format, name);
        for (size_t length = 0; length < must_refuse; ++length) {
            try {
                parse_mesh(std::string_view(whole).substr(0, length), format, name);
                ADD_FAILURE() << name << " cut to " << length << " bytes loaded";
            } catch (const std::runtime_error& e) {
                ASSERT_EQ(std::string(e.what()).rfind("cannot load mesh '" + name + "': ", 0), 0u) << e.what();
            }
        }
        // What follows the last word (line ending, blanks) is not needed.
        for (size_t length = must_refuse + (binary ? 0 : 1); length <= whole.size(); ++length)
            expect_same_mesh(full, parse_mesh(std::string_view(whole).substr(0, length), format, name),
                             name + " cut to " + std::to_string(length));
    }
}

TEST_F(MeshIoTest, TruncationIsNamedWithItsPlace) {
    const std::string whole = kAsciiPly;
    // A vertex cut after its x: refused, not completed with zeros.
    std::string cut = whole.substr(0, whole.find("0.5 0.5 2.25") + 3);
    std::string error = load_error(write("cut.ply", cut));
    EXPECT_NE(error.find("line 15: vertex 4, property y: the line ends before this property"), std::string::npos)
        << error;
    error = load_error(write("cut.ply", whole.substr(0, whole.find("3 0 1 4"))));
    EXPECT_NE(error.find("the file ends before face 2 (of 2 faces the header declares): it is cut short"),
              std::string::npos)
        << error;
    const std::string binary = binary_ply();
    error = load_error(write("cut.ply", binary.substr(0, binary.size() - 7)));
    EXPECT_NE(error.find("the file ends inside face 2 (of 2 faces the header declares): it is cut short"),
              std::string::npos)
        << error;
    error = load_error(write("cut.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n"));
    EXPECT_NE(error.find("the file ends before face 2 (of 2): it is cut short"), std::string::npos) << error;
    error = load_error(write("cut.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1\n"));
    EXPECT_NE(error.find("line 5: vertex 2: 2 numbers on the line"), std::string::npos) << error;
    const std::string stl = binary_stl();
    error = load_error(write("cut.stl", stl.substr(0, stl.size() - 10)));
    EXPECT_NE(error.find("binary STL (byte 80 is '\\x02', which ASCII STL cannot hold): its header declares 2 "
                         "triangles, 184 bytes, but the file has 174 bytes: it is cut short"),
              std::string::npos)
        << error;
    error = load_error(write("cut.stl", ascii_stl().substr(0, ascii_stl().find("vertex 1 1 0") + 10)));
    EXPECT_NE(error.find("the file ends in triangle 1: it is cut short"), std::string::npos) << error;
    error = load_error(write("cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1\n"));
    EXPECT_NE(error.find("line 3: vertex 3: a 'v' statement has 2 numbers"), std::string::npos) << error;
}

// ---- line endings: LF, CR LF, a lone CR and a mix load the same mesh --------------------

std::string with_endings(const std::string& text, const std::string& style) {
    std::string out;
    int line = 0;
    for (char c : text) {
        if (c != '\n') {
            out += c;
            continue;
        }
        const std::string mixed[3] = {"\n", "\r\n", "\r"};
        out += style == "mixed" ? mixed[line++ % 3] : style;
    }
    return out;
}

TEST_F(MeshIoTest, EveryLineEndingLoadsEveryFace) {
    const std::vector<std::pair<std::string, std::string>> files = {
        {"e.ply", kAsciiPly}, {"e.off", kOff}, {"e.stl", ascii_stl()}, {"e.obj", kObj}};
    for (const auto& [name, text] : files) {
        const Scene lf = load_mesh(write(name, text));
        for (const std::string style : {"\r\n", "\r", "mixed"}) {
            const std::string converted = with_endings(text, style);
            expect_same_mesh(lf, load_mesh(write(name, converted)),
                             name + " " +
                                 (style == "mixed"    ? "mixed"
                                      : style == "\r" ? "CR"
                                                      : "CRLF"));
            // and without a line ending at the very end
            expect_same_mesh(lf, load_mesh(write(name, converted.substr(0, converted.find_last_not_of("\r\n") + 1))),
                             name + " no final ending");
        }
    }
    // A binary PLY's data starts right after "end_header" and the header's line ending,
    // even when that is a lone CR followed by a data byte 0x0A.
    std::string header =
        "ply\rformat binary_little_endian 1.0\relement vertex 3\rproperty float x\rproperty float y\r"
        "property float z\relement face 1\rproperty list uchar int vertex_indices\rend_header\r";
    std::string cr = header;
    const float xyz[9] = {std::bit_cast<float>(0x0000000Au), 0, 0, 1, 0, 0, 0, 1, 0};  // first byte is '\n'
    for (float c : xyz) put(cr, c);
    put(cr, uint8_t(3));
    for (int32_t v : {0, 1, 2}) put(cr, v);
    const Scene s = load_mesh(write("cr.ply", cr));
    ASSERT_EQ(s.vertex_count(), 3u);
    EXPECT_EQ(std::bit_cast<uint32_t>(s.vertices[0].x), 0x0000000Au);
    EXPECT_EQ(s.vertices[1], Vec3(1, 0, 0));
    const std::string crlf = with_endings(binary_ply().substr(0, binary_ply().find("end_header") + 11), "\r\n") +
        binary_ply().substr(binary_ply().find("end_header") + 11);
    expect_same_mesh(load_mesh(write("b.ply", binary_ply())), load_mesh(write("crlf.ply", crlf)),
                     "binary PLY, CRLF header");
    // A header in LF whose end_header line ends in CR LF: where the data starts is ambiguous.
    std::string mixed = binary_ply();
    mixed.insert(mixed.find("end_header") + 10, "\r");
    EXPECT_NE(load_error(write("ambiguous.ply", mixed)).find("line 9: 'end_header' does not end like the 'ply' line"),
              std::string::npos);
}

// ---- comments, continuations and optional forms where the formats allow them ------------

TEST_F(MeshIoTest, ObjCommentsAndLineContinuations) {
    const Scene plain = load_mesh(write("plain.obj", kObj));
    const Scene annotated =
        load_mesh(write("annotated.obj",
                        "# a comment line\n"
                        "o tiny   # an object name, then a comment\n"
                        "v 0 0 0 # trailing comment\n"
                        "v 1 \\\n  0 0\n"        // a vertex continued on the next line
                        "v 1 1 0 1.0\n"          // with w
                        "v 0 1 0 0.5 0.5 0.5\n"  // with a colour
                        "v 0.5 0.5 +2.25\n"
                        "vt 0 0\nvn 0 0 1\n"
                        "g group\nusemtl none\ns off\n"
                        "f 1/1/1 2//1 \\\n 3/1 \\\n 4\n"  // a face over three lines, every corner form
                        "\n   \t\n"
                        "f -5 -4 -1\n"));  // relative indices: 1 2 5
    expect_same_mesh(plain, annotated, "commented OBJ");
    // A continuation on the last line is a file cut short.
    EXPECT_NE(load_error(write("c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\")).find("line 4: a line continuation"),
              std::string::npos);
}

TEST_F(MeshIoTest, PlyCommentsAndObjInfo) {
    std::string ply = kAsciiPly;
    ply.replace(ply.find("element vertex"), 0, "obj_info made by hand\ncomment\n");
    ply.replace(ply.find("property float y"), 0, "comment between properties\n");
    ply.replace(ply.find("end_header"), 0, "obj_info num_cols 1\n");
    expect_same_mesh(load_mesh(write("a.ply", kAsciiPly)), load_mesh(write("b.ply", ply)), "PLY with comments");
    // Extra elements and properties of every type are read and skipped, lists too.
    const Scene extra = load_mesh(write(
        "extra.ply",
        "ply\nformat ascii 1.0\nelement material 1\nproperty uchar red\nproperty list int float64 weights\n"
        "element vertex 3\nproperty int8 flag\nproperty double z\nproperty float64 y\nproperty int16 x\n"
        "property uint confidence\nelement face 1\nproperty uint8 flags\nproperty list uint16 uint32 vertex_index\n"
        "end_header\n255 2 0.5 -1e300\n-1 0 0 0 4000000000\n0 0 0 1 7\n0 0 1 -32768 0\n7 3 0 1 2\n"));
    ASSERT_EQ(extra.vertex_count(), 3u);
    EXPECT_EQ(extra.vertices[2], Vec3(-32768, 1, 0));
    EXPECT_EQ(extra.triangles, (std::vector<Tri>{{0, 1, 2}}));
}

TEST_F(MeshIoTest, OffHeaderFormsCommentsAndColours) {
    const Scene plain = load_mesh(write("plain.off", kOff));
    // No keyword (the Geomview manual: "recommended but optional"); counts on the
    // keyword's line; comments anywhere; blank lines.
    std::string no_keyword = kOff;
    no_keyword.erase(0, 4);
    expect_same_mesh(plain, load_mesh(write("nokeyword.off", no_keyword)), "OFF without keyword");
    expect_same_mesh(
        plain,
        load_mesh(
            write("oneline.off",
                  "# made by hand\nOFF 5 2 0 # counts on the keyword's line\n\n0 0 0\n1 0 0 # a vertex\n1 1 0\n0 1 0\n"
                  "# between\n0.5 0.5 2.25\n4 0 1 2 3\n3 0 1 4 # last face\n")),
        "OFF one-line header");
    // Per-vertex normals (N), colours (C, 3 or 4 numbers), texture coordinates (ST); face
    // colours of 0 to 4 numbers (3 0 1 4 7: a triangle with colour-map index 7).
    expect_same_mesh(
        plain,
        load_mesh(write("full.off",
                        "STCNOFF\n5 2 10\n0 0 0 0 0 1 255 0 0 255 0 0\n1 0 0 0 0 1 255 0 0 1 0\n1 1 0 0 0 1 0 1 0 1 1\n"
                        "0 1 0 0 0 1 0 0 1 1 0 1\n0.5 0.5 2.25 0 0 1 1 1 1 1 0.5 0.5\n4 0 1 2 3 1 0 0\n3 0 1 4 7\n")),
        "STCNOFF");
    expect_same_mesh(
        plain,
        load_mesh(write("c.off",
                        "COFF\n5 2 0\n0 0 0 1 1 1\n1 0 0 1 1 1 1\n1 1 0 1 1 1\n0 1 0 1 1 1\n0.5 0.5 2.25 1 1 1\n"
                        "4 0 1 2 3 0.1 0.2 0.3 0.4\n3 0 1 4\n")),
        "COFF");
    EXPECT_NE(load_error(write("4.off", "4OFF\n3 1 0\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n")).find("4OFF and nOFF"),
              std::string::npos);
    EXPECT_NE(load_error(write("b.off", "OFF BINARY\n")).find("binary OFF is not supported"), std::string::npos);
    EXPECT_NE(load_error(write("n.off", "NOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"))
                  .find("line 3: vertex 0: 3 numbers on the line, 'NOFF' vertices have 6"),
              std::string::npos);
}

TEST_F(MeshIoTest, StlSolidNamesCaseAndLayout) {
    const Scene plain = load_mesh(write("plain.stl", ascii_stl()));
    expect_same_mesh(
        plain,
        load_mesh(write("named.stl",
                        "SOLID my part, version 2 (made by hand)\n"
                        "FACET NORMAL 0 0 1 OUTER LOOP VERTEX 0 0 0 VERTEX 1 0 0 VERTEX 1 1 0 ENDLOOP ENDFACET\n"
                        "  facet normal nan nan nan\n\touter\nloop\n vertex 0 0 0\n vertex 1 1 0\n vertex 0 1 +0.5\n"
                        "endloop\nendfacet\nendsolid\n")),
        "STL in capitals, one line per triangle, no endsolid name");
    // Two solids one after the other: one mesh of both.
    std::string two = ascii_stl() + ascii_stl();
    const Scene both = load_mesh(write("two.stl", two));
    EXPECT_EQ(both.triangle_count(), 4u);
    EXPECT_EQ(both.vertex_count(), 4u);
    // A binary STL whose 80-byte header starts with "solid" is binary (its size says so).
    std::string solid_header = binary_stl();
    solid_header.replace(0, 12, "solid binary");
    expect_same_mesh(load_mesh(write("b.stl", binary_stl())), load_mesh(write("sb.stl", solid_header)),
                     "binary STL named solid");
}

// ---- malformed input: refused, naming file, place and cause -----------------------------

TEST_F(MeshIoTest, MalformedInputIsRefusedWithPlaceAndCause) {
    struct Case {
        std::string name, bytes, expected;
    };
    const std::string ply = kAsciiPly;
    const auto edit = [](std::string text, const std::string& from, const std::string& to) {
        text.replace(text.find(from), from.size(), to);
        return text;
    };
    const std::vector<Case> cases = {
        // OBJ
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
         "line 4: face 1 refers to vertex 4 but the file has 3 vertices (OBJ counts from 1)"},
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
         "line 4: face 1: corner '0': vertex index 0 (OBJ counts from 1)"},
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "line 4: face 1: refers to vertex -4 but only 3 precede it"},
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "line 4: face 1 has 2 corners (a face needs at least 3)"},
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/\n",
         "line 4: face 1: corner '3/' is not v, v/vt, v/vt/vn or v//vn"},
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "line 4: face 1: corner 'x': 'x' is not an index"},
        {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nfoo 1 2\n", "line 5: unknown statement 'foo' (not OBJ)"},
        {"a.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", "line 2: vertex 2: a coordinate is not finite (1, nan, 0)"},
        {"a.obj", "v 0 0 0\nv 1 0 inf\nv 0 1 0\nf 1 2 3\n", "line 2: vertex 2: a coordinate is not finite"},
        {"a.obj", "v 0 0 0\nv 1 0 1e39\nv 0 1 0\nf 1 2 3\n",
         "line 2: vertex 2: coordinate '1e39' is too large for a float"},
        {"a.obj", "v 0 0 0\nv 1 0 1e19\nv 0 1 0\nf 1 2 3\n",
         "line 2: vertex 2: a coordinate of magnitude 1.844e18 or more"},
        {"a.obj", "v 0 0 0\nv 1 0 0,5\nv 0 1 0\nf 1 2 3\n", "line 2: vertex 2: coordinate '0,5' is not a number"},
        {"a.obj", "v 0 0 0\nv 1 0 0x1p3\nv 0 1 0\nf 1 2 3\n", "line 2: vertex 2: coordinate '0x1p3' is not a number"},
        // PLY
        {"a.ply", edit(ply, "1 1 0", "1 x 0"), "line 13: vertex 2, property y: 'x' is not a number"},
        {"a.ply", edit(ply, "1 1 0", "1 nan 0"), "line 13: vertex 2: a coordinate is not finite (1, nan, 0)"},
        {"a.ply", edit(ply, "1 1 0", "1 1 0 7"), "line 13: vertex 2 has 1 more values than its properties"},
        {"a.ply", edit(ply, "4 0 1 2 3", "4 0 1 ? 3"),
         "line 16: face 1, property vertex_indices: '?' is not a value of its integer type"},
        {"a.ply", edit(ply, "3 0 1 4", "three 0 1 4"),
         "line 17: face 2, property vertex_indices: 'three' is not a value of its integer type (0 to 255)"},
        {"a.ply", edit(ply, "3 0 1 4", "3 0 1 7"),
         "line 17: face 2 refers to vertex 7 but the file has 5 vertices (PLY counts from 0)"},
        {"a.ply", edit(ply, "3 0 1 4", "3 0 1 -1"), "line 17: face 2 refers to vertex -1"},
        {"a.ply", edit(ply, "3 0 1 4", "2 0 1"), "line 17: face 2 has 2 corners (a face needs at least 3)"},
        {"a.ply", edit(ply, "3 0 1 4", "4 0 1 4"),
         "line 17: face 2, property vertex_indices: the list has 4 values but the line holds 3"},
        {"a.ply", edit(ply, "3 0 1 4\n", "3 0 1 4\n3 0 1 2\n"), "line 18: more data after the last element"},
        {"a.ply", edit(ply, "format ascii 1.0", "format ascii 2.0"), "line 2: unsupported PLY version '2.0'"},
        {"a.ply", edit(ply, "format ascii", "format text"), "line 2: unknown format 'text'"},
        {"a.ply", edit(ply, "property float y", "property real y"), "line 6: expected 'property TYPE NAME'"},
        {"a.ply", edit(ply, "property float y", "property float x"), "line 6: a second property 'x'"},
        {"a.ply", edit(ply, "property float y\n", ""), "element vertex has no scalar property y"},
        {"a.ply", edit(ply, "element vertex 5", "element vertex -5"), "line 4: expected 'element NAME COUNT'"},
        {"a.ply", edit(ply, "comment tiny", "remark tiny"), "line 3: unknown header line 'remark'"},
        {"a.ply", edit(ply, "end_header", "end_heade"), "line 10: unknown header line 'end_heade'"},
        {"a.ply", edit(ply, "vertex_indices", "corners"), "element face has no list property vertex_indices"},
        {"a.ply", "ply\n", "no 'end_header' line"},
        {"a.ply", "PLY\nformat ascii 1.0\n", "not a PLY file (the first line is not 'ply')"},
        // OFF
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
         "line 6: face 1: refers to vertex 3 but the file has 3 vertices (OFF counts from 0)"},
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "line 6: face 1 has 2 corners"},
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n",
         "line 6: face 1: it has 4 corners but the line holds 3 indices"},
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 1 1 1 1 1\n",
         "line 6: face 1: 5 numbers after its corners"},
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 -inf 0\n0 1 0\n3 0 1 2\n", "line 4: vertex 1: a coordinate is not finite"},
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0 0\n0 1 0\n3 0 1 2\n",
         "line 4: vertex 1: 4 numbers on the line, 'OFF' vertices have 3"},
        {"a.off", "OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "line 2: 'NVertices NFaces NEdges' has 2 of its 3"},
        {"a.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "line 7: more data after the last face"},
        {"a.off", "XOFF\n3 1 0\n", "line 1: not an OFF header keyword 'XOFF'"},
        {"a.off", "hello\n", "line 1: not an OFF file: expected 'NVertices NFaces NEdges'"},
        // STL
        {"a.stl", edit(ascii_stl(), "vertex 1 0 0", "vertex 1 0"),
         "line 6: triangle 1, corner 2: coordinate 'vertex' is not a number"},
        {"a.stl", edit(ascii_stl(), "endloop", "endlop"), "line 7: triangle 1: expected 'endloop', found 'endlop'"},
        {"a.stl", edit(ascii_stl(), "vertex 0 1 0.5", "vertex 0 1e40 0.5"),
         "line 13: triangle 2, corner 3: coordinate '1e40' is too large for a float"},
        {"a.stl", edit(ascii_stl(), "vertex 0 1 0.5", "vertex 0 NaN 0.5"),
         "line 13: triangle 2, corner 3: a coordinate is not finite"},
        {"a.stl", edit(ascii_stl(), "endsolid square\n", ""), "the file ends without 'endsolid': it is cut short"},
        {"a.stl", ascii_stl() + "garbage\n",
         "line 17: expected 'solid' or the end of the file after 'endsolid', found 'garbage'"},
        {"a.stl", "hello world\n",
         "corrupt STL: it does not start with 'solid' as ASCII STL does and is too short for binary STL"},
    };
    for (const Case& c : cases) {
        const std::string path = write(c.name, c.bytes);
        const std::string error = load_error(path);
        EXPECT_EQ(error.rfind("cannot load mesh '" + path + "': ", 0), 0u) << error;
        EXPECT_NE(error.find(c.expected), std::string::npos) << "expected: " << c.expected << "\n     got: " << error;
    }
    // Binary: the byte offset of the element or triangle.
    std::string b = binary_ply();
    const size_t data = b.find("end_header\n") + 11;
    put_at(b, data + 4, std::numeric_limits<float>::quiet_NaN());
    EXPECT_NE(
        load_error(write("nan.ply", b)).find("byte " + std::to_string(data) + ": vertex 0: a coordinate is not finite"),
        std::string::npos);
    b = binary_ply();
    put_at(b, data + 48 + 13 + 1, int32_t(4));  // face 2's second corner
    EXPECT_NE(load_error(write("idx.ply", b))
                  .find("byte " + std::to_string(data + 48 + 13) + ": face 2 refers to vertex 4 but the file has 4"),
              std::string::npos);
    b = binary_ply() + "x";
    EXPECT_NE(load_error(write("tail.ply", b)).find(": 1 bytes after the last element"), std::string::npos);
    b = binary_ply();
    b.replace(b.find("element face 2"), 14, "element face 9");
    EXPECT_NE(load_error(write("count.ply", b))
                  .find("the file ends inside face 3 (of 9 faces the header declares): it is cut short"),
              std::string::npos);
    // A count no file of this size could hold is refused before anything is read.
    b = binary_ply();
    b.replace(b.find("element face 2"), 14, "element face 4000000000");
    EXPECT_NE(load_error(write("count.ply", b))
                  .find("the header declares 4000000000 faces, at least 1 bytes each, but only 26 bytes follow"),
              std::string::npos);
    b = binary_stl();
    put_at(b, 84 + 50 + 12 + 12 + 8, std::numeric_limits<float>::infinity());
    EXPECT_NE(load_error(write("inf.stl", b)).find("byte 134: triangle 2, corner 2: a coordinate is not finite"),
              std::string::npos);
}

TEST_F(MeshIoTest, BigEndianPly) {
    std::string b =
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const auto big = [&](auto value) {
        char raw[sizeof value];
        std::memcpy(raw, &value, sizeof value);
        std::reverse(raw, raw + sizeof value);
        b.append(raw, sizeof raw);
    };
    for (float c : {0.f, 0.f, 0.f, 1.5f, 0.f, 0.f, 0.f, -2.f, 0.f}) big(c);
    b += char(3);
    for (int32_t v : {0, 1, 2}) big(v);
    const Scene s = load_mesh(write("big.ply", b));
    EXPECT_EQ(s.vertices[1], Vec3(1.5f, 0, 0));
    EXPECT_EQ(s.vertices[2], Vec3(0, -2, 0));
    EXPECT_EQ(s.triangles, (std::vector<Tri>{{0, 1, 2}}));
}

// A directory or a FIFO where a mesh is expected is "not a regular file", not missing.
TEST_F(MeshIoTest, DirectoryAndFifoAreNotRegularFiles) {
    const fs::path dir = dir_ / "folder.ply";
    fs::create_directory(dir);
    EXPECT_NE(load_error(dir.string()).find("'" + dir.string() + "': not a regular file (a directory)"),
              std::string::npos);
    const fs::path fifo = dir_ / "pipe.obj";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    EXPECT_NE(load_error(fifo.string()).find("not a regular file (a FIFO)"), std::string::npos);
}

TEST_F(MeshIoTest, CorruptGzip) {
    std::string packed;
    {
        const std::string path = write_gz("tmp.ply.gz", kAsciiPly);
        std::ifstream in(path, std::ios::binary);
        packed.assign(std::istreambuf_iterator<char>(in), {});
    }
    for (size_t cut : {packed.size() / 2, packed.size() - 4, size_t(10)}) {
        const std::string error = load_error(write("cut.ply.gz", packed.substr(0, cut)));
        EXPECT_NE(error.find("cut.ply.gz"), std::string::npos) << error;
        EXPECT_NE(error.find("gzip"), std::string::npos) << cut << ": " << error;
    }
    const std::string plain = load_error(write("plain.ply.gz", kAsciiPly));
    EXPECT_NE(plain.find("is not gzip-compressed"), std::string::npos) << plain;
    // A valid gzip stream of a corrupt mesh names the .gz file and the place inside.
    std::string bad = kAsciiPly;
    bad.replace(bad.find("1 1 0"), 5, "1 1 z");
    EXPECT_NE(load_error(write_gz("bad.ply.gz", bad)).find("bad.ply.gz': line 13: vertex 2, property z"),
              std::string::npos);
}

TEST_F(MeshIoTest, EmptyMesh) {
    const std::string error = load_error(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"));
    EXPECT_NE(error.find("points.obj"), std::string::npos) << error;
    EXPECT_NE(error.find("empty mesh (no triangles)"), std::string::npos) << error;
    for (const char* name : {"e.obj", "e.ply", "e.off", "e.stl"}) EXPECT_FALSE(load_error(write(name, "")).empty());
}

// Faces with repeated corners (degenerate triangles) are the file's content: kept, as
// the ray tracer handles them (OpenMesh's readers dropped them).
TEST_F(MeshIoTest, DegenerateFacesAreKept) {
    const Scene obj = load_mesh(write("repeat.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 2\n"));
    EXPECT_EQ(obj.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 1, 1}}));
    const Scene stl = load_mesh(write("flat.stl",
                                      "solid flat\n"
                                      "facet normal 0 0 1\nouter loop\n"
                                      "vertex 0 0 0\nvertex 1 0 0\nvertex 1 0 0\n"
                                      "endloop\nendfacet\n"
                                      "facet normal 0 0 1\nouter loop\n"
                                      "vertex 0 0 0\nvertex -0 1 0\nvertex 0 1 0\n"  // -0 and 0: one position
                                      "endloop\nendfacet\n"
                                      "endsolid flat\n"));
    EXPECT_EQ(stl.triangles, (std::vector<Tri>{{0, 1, 1}, {0, 2, 2}}));
    EXPECT_EQ(stl.vertex_count(), 3u);
}

// ---- no face dropped silently -------------------------------------------------------

// A backslash at the end of a comment is the comment's: the next line is a statement.
TEST_F(MeshIoTest, ObjCommentEndingInBackslashDoesNotContinue) {
    const Scene s = load_mesh(write("c.obj",
                                    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 2.25\n"
                                    "# a path C:\\models\\\n"
                                    "f 1 2 3 4\n"
                                    "g x # another \\\n"
                                    "f 1 2 5\n"));
    expect_same_mesh(load_mesh(write("plain.obj", kObj)), s, "OBJ with comments ending in '\\'");
}

// One-line ASCII STL: the facets on the solid line are facets, not the solid's name.
TEST_F(MeshIoTest, StlFacetsOnTheSolidLineAreRead) {
    std::string one_line = ascii_stl();
    std::replace(one_line.begin(), one_line.end(), '\n', ' ');
    const Scene s = load_mesh(write("one.stl", one_line));
    expect_same_mesh(load_mesh(write("plain.stl", ascii_stl())), s, "one-line STL");
    // Unnamed, and a second solid on the endsolid line (after the first one's name).
    std::string unnamed =
        "solid facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 1 1 0 endloop "
        "endfacet endsolid a solid b facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 1 0 "
        "vertex 0 1 0.5 endloop endfacet endsolid b";
    expect_same_mesh(load_mesh(write("plain2.stl", ascii_stl())), load_mesh(write("unnamed.stl", unnamed)),
                     "unnamed one-line STL of two solids");
}

// A binary STL whose header starts with "solid" and whose count does not match its size
// is named as the binary file it is, with the size and count.
TEST_F(MeshIoTest, BinaryStlWithSolidHeaderAndWrongCountNamesTheCount) {
    std::string b = binary_stl();
    b.replace(0, 12, "solid binary");
    put_at(b, 80, uint32_t(3));
    const std::string error = load_error(write("wrong.stl", b));
    EXPECT_NE(error.find("binary STL"), std::string::npos) << error;
    EXPECT_NE(error.find("declares 3 triangles"), std::string::npos) << error;
    EXPECT_NE(error.find("the file has 184 bytes"), std::string::npos) << error;
    EXPECT_EQ(error.find("expected"), std::string::npos) << error;
    // Cut inside a triangle, header "solid", too.
    b = binary_stl();
    b.replace(0, 5, "solid");
    const std::string cut = load_error(write("cut.stl", b.substr(0, b.size() - 7)));
    EXPECT_NE(cut.find("binary STL"), std::string::npos) << cut;
    EXPECT_NE(cut.find("declares 2 triangles"), std::string::npos) << cut;
}

// OFF with NEdges missing: the counts line is named, not the first vertex.
TEST_F(MeshIoTest, OffMissingNEdgesIsNamedOnTheCountsLine) {
    const std::string error = load_error(write("e.off", "OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    EXPECT_NE(error.find("line 2: 'NVertices NFaces NEdges' has 2 of its 3 numbers"), std::string::npos) << error;
    const std::string inline_error = load_error(write("f.off", "OFF 3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    EXPECT_NE(inline_error.find("line 1: 'NVertices NFaces NEdges' has 2 of its 3 numbers"), std::string::npos)
        << inline_error;
}

std::string gzip_bytes(const std::string& bytes) {
    uLongf size = compressBound(uLong(bytes.size())) + 32;
    std::string out(size, '\0');
    z_stream s{};
    deflateInit2(&s, 6, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY);
    s.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
    s.avail_in = uInt(bytes.size());
    s.next_out = reinterpret_cast<Bytef*>(out.data());
    s.avail_out = uInt(out.size());
    deflate(&s, Z_FINISH);
    out.resize(s.total_out);
    deflateEnd(&s);
    return out;
}

// Members of a gzip file in a row are one file (RFC 1952, as gzip -d reads them); bytes
// after the last member that are not a member are refused, with their offset.
TEST_F(MeshIoTest, GzipMembersAreReadAndTrailingBytesRefused) {
    const std::string ply = kAsciiPly;
    const size_t half = ply.find("end_header");
    const std::string two = gzip_bytes(ply.substr(0, half)) + gzip_bytes(ply.substr(half));
    expect_same_mesh(load_mesh(write("a.ply", ply)), load_mesh(write("two.ply.gz", two)), "two gzip members");
    const std::string one = gzip_bytes(ply);
    for (const std::string& tail : {std::string("junk"), std::string(8, '\0'), std::string("\x1f")}) {
        const std::string error = load_error(write("tail.ply.gz", one + tail));
        EXPECT_NE(error.find("tail.ply.gz': gzip: " + std::to_string(tail.size()) + " bytes after the gzip data"),
                  std::string::npos)
            << error;
        EXPECT_NE(error.find("byte " + std::to_string(one.size())), std::string::npos) << error;
    }
}

// A gzip of `size` zero bytes, written in pieces (the inflated bytes are never held).
void write_zeros_gz(const std::string& path, uint64_t size) {
    gzFile out = gzopen(path.c_str(), "wb9");
    const std::string piece(1u << 20, '\0');
    for (uint64_t done = 0; done < size; done += piece.size()) gzwrite(out, piece.data(), unsigned(piece.size()));
    gzclose(out);
}

long max_rss_kib() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss;
}

// A gzip bomb is refused as soon as its inflated size passes the limit, without holding
// the inflated bytes: the process's peak memory grows far less than the limit.
TEST_F(MeshIoTest, GzipBombIsRefusedWithoutBufferingToTheLimit) {
    const std::string path = (dir_ / "bomb.ply.gz").string();
    write_zeros_gz(path, uint64_t(256) << 20);
    const long before = max_rss_kib();
    try {
        mesh_reading::gunzip(path, uint64_t(64) << 20);
        ADD_FAILURE() << "a 256 MiB inflation passed a 64 MiB limit";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("decompresses to more than 67108864 bytes"), std::string::npos)
            << e.what();
    }
    EXPECT_LT(max_rss_kib() - before, 32 * 1024) << "KiB of peak memory grown while refusing the bomb";
    // Under the limit it is read whole and exactly.
    const std::string zeros = mesh_reading::gunzip(path, uint64_t(256) << 20);
    EXPECT_EQ(zeros.size(), size_t(256) << 20);
    EXPECT_EQ(zeros.find_first_not_of('\0'), std::string::npos);
}

// One vertex policy: a NaN vertex no face uses is refused by the readers and by
// Scene::finalize alike, each naming the vertex.
TEST_F(MeshIoTest, AnUnusedNanVertexIsRefusedByReadersAndScenesAlike) {
    const std::string error = load_error(write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nf 1 2 3\n"));
    EXPECT_NE(error.find("line 4: vertex 4: a coordinate is not finite"), std::string::npos) << error;
    Scene s;
    s.name = "unused";
    s.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {std::nanf(""), 0, 0}};
    s.triangles = {{0, 1, 2}};
    try {
        s.finalize();
        ADD_FAILURE() << "an unused NaN vertex was accepted";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("vertex 3 is not finite"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace accelbench
