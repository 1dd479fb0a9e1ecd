#include "accelbench/scene/mesh_io.h"

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "accelbench/scene/mesh_reading.h"

namespace accelbench {
namespace {

namespace fs = std::filesystem;
using namespace mesh_reading;

// ---- reading the bytes ---------------------------------------------------------------

std::string read_file(const std::string& path) {
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    if (ec) fail(path, "cannot read its size (" + ec.message() + ")");
    if (size > kMaxMeshFileBytes) fail(path, "larger than 4 GiB, the limit (files are read into memory whole)");
    std::ifstream in(path, std::ios::binary);
    std::string bytes(size_t(size), '\0');
    if (!in.read(bytes.data(), std::streamsize(size)) || in.gcount() != std::streamsize(size))
        fail(path, "reading it failed");
    return bytes;
}

std::string file_kind(fs::file_type type) {
    switch (type) {
        case fs::file_type::directory: return "a directory";
        case fs::file_type::fifo: return "a FIFO";
        case fs::file_type::socket: return "a socket";
        case fs::file_type::block: return "a block device";
        case fs::file_type::character: return "a character device";
        default: return "not a file";
    }
}

}  // namespace

Scene parse_mesh(std::string_view bytes, const std::string& format, const std::string& shown_as,
                 MeshLoadInfo* info_out) {
    FlatMesh mesh;
    std::optional<Camera> camera;
    const bool gltf = format == "gltf" || format == "glb";
    try {
        if (format == "obj") read_obj(bytes, mesh);
        else if (format == "ply") read_ply(bytes, mesh);
        else if (format == "off") read_off(bytes, mesh);
        else if (format == "stl") read_stl(bytes, mesh);
        else if (gltf) {
            const std::string folder = fs::path(shown_as).parent_path().string();
            camera = read_gltf(bytes, format == "glb", folder.empty() ? "." : folder, mesh);
        } else throw MeshError("unsupported format '" + format + "' (supported: obj ply off stl gltf glb)");
    } catch (const MeshError& e) {
        fail(shown_as, e.what());
    }
    if (mesh.triangles.empty()) fail(shown_as, "empty mesh (no triangles)");

    Scene scene;
    fs::path stem = fs::path(shown_as).filename();
    if (lowercase(stem.extension().string()) == ".gz") stem = stem.stem();
    scene.name = stem.stem().string();
    scene.vertices = std::move(mesh.vertices);
    scene.triangles = std::move(mesh.triangles);
    scene.finalize();  // cannot fail: every index and vertex was checked
    if (info_out) {
        info_out->format = format;
        info_out->reader = mesh_reader(shown_as);
        info_out->camera = camera;
        info_out->file_faces = mesh.faces;
        info_out->polygons = mesh.polygons;
        info_out->triangles = scene.triangle_count();
        info_out->vertices = scene.vertex_count();
    }
    return scene;
}

std::string mesh_format(const std::string& path, bool* compressed) {
    // "name.ply.gz" -> compressed, format "ply".
    fs::path inner = fs::path(path).filename();
    const bool gz = lowercase(inner.extension().string()) == ".gz";
    if (gz) inner = inner.stem();
    if (compressed) *compressed = gz;
    std::string format = lowercase(inner.extension().string());
    if (!format.empty()) format.erase(0, 1);
    for (const char* known : {"obj", "ply", "off", "stl", "gltf", "glb"})
        if (format == known) return format;
    return "";
}

std::string mesh_reader(const std::string& path) {
    const std::string format = mesh_format(path);
    return format == "gltf" || format == "glb" ? gltf_reader() : "accelbench";
}

Scene load_mesh(const std::string& path, MeshLoadInfo* info_out) {
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) fail(path, "file not found");
    if (!fs::is_regular_file(status)) fail(path, "not a regular file (" + file_kind(status.type()) + ")");
    if (!std::ifstream(path, std::ios::binary)) fail(path, "file cannot be opened for reading");

    bool compressed = false;
    const std::string format = mesh_format(path, &compressed);
    if (format.empty())
        fail(path, "unsupported file extension (supported: .obj .ply .off .stl .gltf .glb, each optionally .gz)");

    const std::string bytes = compressed ? gunzip(path) : read_file(path);
    MeshLoadInfo info;
    Scene scene = parse_mesh(bytes, format, path, &info);
    info.compressed = compressed;
    if (info_out) *info_out = info;
    return scene;
}

// Written by hand: OpenMesh's PLY writer takes a half-edge mesh, which would drop the faces
// our importer keeps (see mesh_io.h), and writes no header comments.
void write_ply(const Scene& scene, const std::string& path, const std::vector<std::string>& comments) {
    static_assert(std::endian::native == std::endian::little, "write_ply writes the host's bytes as little-endian");
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + path);
    out << "ply\nformat binary_little_endian 1.0\n";
    for (const auto& c : comments) {
        if (c.find('\n') != std::string::npos || c.find('\r') != std::string::npos)
            throw std::invalid_argument("write_ply: a comment with a line break");
        out << "comment " << c << "\n";
    }
    out << "element vertex " << scene.vertex_count() << "\nproperty float x\nproperty float y\nproperty float z\n"
        << "element face " << scene.triangle_count() << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Vec3& v : scene.vertices) {
        const float xyz[3] = {v.x, v.y, v.z};
        out.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
    }
    for (const auto& t : scene.triangles) {
        char face[1 + 3 * sizeof(int32_t)];
        face[0] = 3;
        for (int k = 0; k < 3; ++k) {
            const int32_t i = int32_t(t[size_t(k)]);
            std::memcpy(face + 1 + k * sizeof(int32_t), &i, sizeof i);
        }
        out.write(face, sizeof face);
    }
    out.close();
    if (!out) throw std::runtime_error("writing " + path + " failed");
}

// The header is plain text lines; OpenMesh's PLY reader skips its comments.
std::vector<std::string> read_ply_comments(const std::string& path) {
    std::vector<std::string> comments;
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line != "ply") return comments;
    while (std::getline(in, line) && line != "end_header")
        if (line.rfind("comment ", 0) == 0) comments.push_back(line.substr(8));
    return comments;
}

}  // namespace accelbench
