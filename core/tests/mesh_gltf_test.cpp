// load_mesh on glTF files written here (JSON with data: URIs or a .bin beside, and .glb
// containers), so counts, transforms and the camera are known by hand; the same triangles
// written as OBJ trace to the same hits.
#include <gtest/gtest.h>
#include "mesh_load_error.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/base/temp_dir.h"
#include "accelbench/scene/mesh_io.h"

namespace accelbench {
namespace {

namespace fs = std::filesystem;

// A quad (two triangles, four vertices, unsigned short indices) and one more triangle
// without indices, in one buffer: positions 0..47, indices 48..59, triangle 60..95.
std::string geometry_bytes(const std::vector<uint16_t>& indices = {0, 1, 2, 0, 2, 3}) {
    const float quad[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float tri[9] = {0, 0, 1, 1, 0, 1, 0, 1, 1};
    std::string b(96, '\0');
    std::memcpy(b.data(), quad, sizeof quad);
    std::memcpy(b.data() + 48, indices.data(), 2 * std::min<size_t>(indices.size(), 6));
    std::memcpy(b.data() + 60, tri, sizeof tri);
    return b;
}

std::string base64(const std::string& bytes) {
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < bytes.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(bytes[i])) << 16;
        if (i + 1 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 1])) << 8;
        if (i + 2 < bytes.size()) v |= uint32_t(uint8_t(bytes[i + 2]));
        for (int k6 = 0; k6 < 4; ++k6)
            out += i + size_t(k6) - 1 < bytes.size() || k6 < 2 ? k[(v >> (18 - 6 * k6)) & 63] : '=';
    }
    return out;
}

// The document's parts: nodes, scenes and cameras as JSON text, the buffer's uri (absent:
// the .glb's own chunk) and the primitive's mode.
struct Doc {
    std::string nodes = R"([{"mesh": 0}, {"mesh": 1}])";
    std::string scenes = R"([{"nodes": [0, 1]}])";
    std::string cameras = "[]";
    std::string uri;
    int mode = 4;
    std::string json(size_t buffer_bytes) const {
        const std::string u = uri.empty() ? "" : R"("uri": ")" + uri + R"(", )";
        return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": )" + scenes + R"(, "nodes": )" + nodes +
            R"(, "cameras": )" + cameras +
            R"(, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": )" +
            std::to_string(mode) + R"(}]}, {"primitives": [{"attributes": {"POSITION": 2}}]}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
                {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,1], "max": [1,1,1]}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12},
                  {"buffer": 0, "byteOffset": 60, "byteLength": 36}],
  "buffers": [{)" +
            u + R"("byteLength": )" + std::to_string(buffer_bytes) + "}]}";
    }
};

void put_u32(std::string& s, uint32_t v) { s.append(reinterpret_cast<const char*>(&v), 4); }

// The .glb container (spec 4.4): header, JSON chunk padded with spaces, BIN chunk with zeros.
std::string glb(const std::string& json, std::string bin) {
    std::string j = json;
    while (j.size() % 4) j += ' ';
    while (bin.size() % 4) bin += '\0';
    std::string out = "glTF";
    put_u32(out, 2);
    put_u32(out, uint32_t(12 + 8 + j.size() + 8 + bin.size()));
    put_u32(out, uint32_t(j.size()));
    put_u32(out, 0x4E4F534A);  // "JSON"
    out += j;
    put_u32(out, uint32_t(bin.size()));
    put_u32(out, 0x004E4942);  // "BIN"
    return out + bin;
}

class MeshGltfTest : public ::testing::Test {
protected:
    std::string write(const std::string& name, const std::string& bytes) {
        const fs::path path = dir_ / name;
        fs::create_directories(path.parent_path());
        std::ofstream(path, std::ios::binary) << bytes;
        return path.string();
    }
    std::string with_data_uri(Doc doc, const std::string& name, const std::string& bytes = geometry_bytes()) {
        doc.uri = "data:application/octet-stream;base64," + base64(bytes);
        return write(name, doc.json(bytes.size()));
    }
    std::string load_error(const std::string& path) { return mesh_load_error(path); }
    TempDir temp_{"mesh_gltf_test-"};
    const fs::path& dir_ = temp_.path();
};

TEST_F(MeshGltfTest, ExactTrianglesFromEveryContainer) {
    const std::string bytes = geometry_bytes();
    Doc external;
    external.uri = "geometry.bin";
    write("scene/geometry.bin", bytes);
    Doc in_glb;
    for (const std::string& path : {with_data_uri(Doc{}, "a.gltf"), write("scene/b.gltf", external.json(bytes.size())),
                                    write("c.glb", glb(in_glb.json(bytes.size()), bytes))}) {
        MeshLoadInfo info;
        const Scene s = load_mesh(path, &info);
        EXPECT_EQ(s.triangle_count(), 3u) << path;
        EXPECT_EQ(s.vertex_count(), 7u) << path;
        EXPECT_EQ(info.reader, gltf_reader());
        EXPECT_EQ(info.format, fs::path(path).extension().string().substr(1));
        EXPECT_FALSE(info.camera);
        EXPECT_EQ(s.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
        EXPECT_EQ(s.triangles[2], (std::array<uint32_t, 3>{4, 5, 6}));
    }
    EXPECT_EQ(mesh_reader("x.obj"), "accelbench");
    EXPECT_EQ(mesh_reader("x.GLB"), gltf_reader());
}

// Root: translation (1, 2, 3), rotation 90 degrees about z, scale 2; its child: a matrix
// moving by (0, 0, -5), holding the quad. A second root holds the quad again, untouched.
// By hand: p -> R(2 (p + (0, 0, -5))) + (1, 2, 3), R(x, y, z) = (-y, x, z).
TEST_F(MeshGltfTest, NodeTransformsAreAppliedAsTheSameMeshWrittenAsObj) {
    Doc doc;
    doc.nodes = R"([{"translation": [1, 2, 3], "rotation": [0, 0, 0.7071067811865476, 0.7071067811865476],
                     "scale": [2, 2, 2], "children": [1]},
                    {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,-5,1], "mesh": 0},
                    {"mesh": 0}])";
    doc.scenes = R"([{"nodes": [0, 2]}])";
    const Scene gltf = load_mesh(with_data_uri(doc, "t.gltf"));
    ASSERT_EQ(gltf.triangle_count(), 4u);  // the quad twice; the lone triangle is in no node
    const auto placed = [](float x, float y, float z) {
        return std::array<float, 3>{-2 * y + 1, 2 * x + 2, 2 * (z - 5) + 3};
    };
    std::string obj;
    for (const auto& p : {placed(0, 0, 0), placed(1, 0, 0), placed(1, 1, 0), placed(0, 1, 0)})
        obj += "v " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    obj += "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n";
    const Scene reference_obj = load_mesh(write("t.obj", obj));
    ASSERT_EQ(reference_obj.vertex_count(), gltf.vertex_count());
    for (size_t i = 0; i < gltf.vertex_count(); ++i)
        for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(gltf.vertices[i][k], reference_obj.vertices[i][k], 1e-6) << "vertex " << i;
    // Rays through both: the same triangles, the same distances.
    auto a = make_accelerator("reference", {}), b = make_accelerator("reference", {});
    a->build(gltf);
    b->build(reference_obj);
    std::vector<Ray> rays;
    for (float x = -3; x <= 3; x += 0.25f)
        for (float y = -1; y <= 4; y += 0.25f)
            rays.push_back({{x, y, 10}, 0, normalize(Vec3{0.01f, 0.02f, -1}), kInfinity});
    std::vector<Hit> ha(rays.size()), hb(rays.size());
    a->closest_hits(rays, ha);
    b->closest_hits(rays, hb);
    size_t hits = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        EXPECT_EQ(ha[i].prim, hb[i].prim) << i;
        if (ha[i].found()) {
            EXPECT_NEAR(ha[i].t, hb[i].t, 1e-4) << i;
        }
        hits += ha[i].found();
    }
    EXPECT_GT(hits, 20u);
}

TEST_F(MeshGltfTest, TheFirstPerspectiveCameraIsTakenWithItsNodesTransform) {
    Doc doc;
    // Node 0 holds an orthographic camera (not taken); node 2, under node 1 (moved to
    // (0, 0, 10)), a perspective one turned 90 degrees about y: it looks down -x.
    doc.nodes = R"([{"camera": 0}, {"translation": [0, 0, 10], "children": [2]},
                    {"camera": 1, "rotation": [0, 0.7071067811865476, 0, 0.7071067811865476]}, {"mesh": 0}])";
    doc.scenes = R"([{"nodes": [0, 1, 3]}])";
    doc.cameras = R"([{"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}},
                      {"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1}}])";
    MeshLoadInfo info;
    load_mesh(with_data_uri(doc, "cam.gltf"), &info);
    ASSERT_TRUE(info.camera);
    const Camera& c = *info.camera;
    EXPECT_NEAR(c.eye.x, 0, 1e-6);
    EXPECT_NEAR(c.eye.z, 10, 1e-6);
    EXPECT_NEAR(c.look_at.x, -1, 1e-6);
    EXPECT_NEAR(c.look_at.y, 0, 1e-6);
    EXPECT_NEAR(c.look_at.z, 10, 1e-6);
    EXPECT_NEAR(c.up.y, 1, 1e-6);
    EXPECT_NEAR(c.fov_deg, 0.8 * 180 / M_PI, 1e-4);
    EXPECT_FLOAT_EQ(c.aspect, 1.5f);
}

// Each refusal: one line, naming the file and the part.
TEST_F(MeshGltfTest, WhatCannotBeUsedIsRefusedInOneLine) {
    struct Case {
        std::string path, part;
    };
    std::vector<Case> cases;
    {
        Doc d;
        d.nodes = R"([{"name": "empty"}])";
        d.scenes = R"([{"nodes": [0]}])";
        cases.push_back({with_data_uri(d, "empty.gltf"), "no triangles"});
    }
    {
        Doc d;
        d.uri = "missing.bin";
        cases.push_back({write("missing.gltf", d.json(96)), "missing.bin"});
    }
    {
        Doc d;
        d.mode = 1;
        cases.push_back({with_data_uri(d, "lines.gltf"), "primitive 0: mode 1 (lines), not triangles"});
    }
    cases.push_back({with_data_uri(Doc{}, "range.gltf", geometry_bytes({0, 1, 2, 0, 2, 7})),
                     "index 7 (element 5) is out of range (4 vertices)"});
    {
        Doc d;
        d.uri = "data:application/octet-stream;base64,@@@@";
        cases.push_back({write("baddata.gltf", d.json(96)), "Failed to decode 'uri'"});
    }
    {
        write("outside.bin", geometry_bytes());
        Doc d;
        d.uri = "../outside.bin";
        cases.push_back({write("inner/out.gltf", d.json(96)), "'../outside.bin' lies outside the glTF's folder"});
    }
    for (const Case& c : cases) {
        const std::string e = load_error(c.path);
        EXPECT_NE(e.find("cannot load mesh '" + c.path + "'"), std::string::npos) << e;
        EXPECT_NE(e.find(c.part), std::string::npos) << e;
        EXPECT_EQ(e.find('\n'), std::string::npos) << e;
        std::printf("refused: %s\n", e.c_str());
    }
}

}  // namespace
}  // namespace accelbench
