#include "accelbench/scene/mesh_io.h"

#include "accelbench/base/temp_dir.h"

#include <zlib.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/OFFReader.hh>
#include <OpenMesh/Core/IO/reader/PLYReader.hh>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace accelbench {
namespace {

namespace fs = std::filesystem;
using OpenMesh::EdgeHandle;
using OpenMesh::FaceHandle;
using OpenMesh::HalfedgeHandle;
using OpenMesh::VertexHandle;

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
    throw std::runtime_error("cannot load mesh '" + path + "': " + reason);
}

std::string lowercase(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

// ---- what the file itself declares -------------------------------------------------
//
// OpenMesh's readers do not all report what they skip (the STL reader drops triangles
// whose corners coincide, the OBJ reader faces with repeated corners, the ASCII readers
// stop quietly at the end of a truncated file). So before reading we count, cheaply and
// independently, what the file says it holds, and after reading we compare.

struct FileCounts {
    std::optional<uint64_t> vertices;   // PLY and OFF headers, OBJ "v" lines; none for STL
    uint64_t faces = 0;                 // faces declared (PLY, OFF, binary STL) or present
    std::optional<uint64_t> triangles;  // when the scan sees every face's corner count
};

// PLY: the header's "element vertex N" and "element face N".
FileCounts scan_ply(const std::string& path, const std::string& shown) {
    std::ifstream in(path, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || line.substr(0, 3) != "ply")
        fail(shown, "not a PLY file (the first line is not 'ply')");
    FileCounts counts;
    counts.vertices = 0;
    for (int lines = 0; std::getline(in, line); ++lines) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line == "end_header") return counts;
        if (lines > 100000) break;
        std::istringstream words(line);
        std::string keyword, element;
        uint64_t count = 0;
        if (words >> keyword >> element >> count && keyword == "element") {
            if (element == "vertex") counts.vertices = count;
            if (element == "face") counts.faces = count;
        }
    }
    fail(shown, "corrupt PLY header (no 'end_header' line)");
}

// OFF: a header line "[ST][C][N]OFF", then "vertices faces edges" (ASCII only).
FileCounts scan_off(const std::string& path, const std::string& shown) {
    std::ifstream in(path);
    std::string header;
    std::getline(in, header);
    std::istringstream words(header);
    std::string keyword, binary;
    words >> keyword >> binary;
    if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0)
        fail(shown, "not an OFF file (the first line is not 'OFF')");
    if (binary == "BINARY") fail(shown, "binary OFF is not supported (ASCII OFF is)");
    FileCounts counts;
    uint64_t vertices = 0, faces = 0;
    if (!(in >> vertices >> faces))
        fail(shown, "corrupt OFF header (expected 'vertices faces edges' after the first line)");
    counts.vertices = vertices;
    counts.faces = faces;
    return counts;
}

// STL: binary when the size is exactly 84 + 50 bytes per declared triangle (the same rule
// OpenMesh's reader uses to choose); otherwise ASCII, one "facet" per triangle.
FileCounts scan_stl(const std::string& path, const std::string& shown) {
    const uint64_t size = fs::file_size(path);
    std::ifstream in(path, std::ios::binary);
    FileCounts counts;
    if (size >= 84) {
        char header[84];
        in.read(header, 84);
        const auto* b = reinterpret_cast<const unsigned char*>(header + 80);
        const uint64_t declared = uint64_t(b[0]) | uint64_t(b[1]) << 8 | uint64_t(b[2]) << 16 | uint64_t(b[3]) << 24;
        if (84 + 50 * declared == size) {
            counts.faces = declared;
            counts.triangles = declared;
            return counts;
        }
        in.seekg(0);
        std::string first;
        in >> first;
        if (lowercase(first) != "solid")
            fail(shown, "corrupt STL: as binary it declares " + std::to_string(declared) + " triangles (" +
                            std::to_string(84 + 50 * declared) + " bytes) but the file has " +
                            std::to_string(size) + " bytes, and it does not start with 'solid' as ASCII STL does");
    }
    in.clear();
    in.seekg(0);
    std::string word;
    while (in >> word)
        if (lowercase(word) == "facet") ++counts.faces;
    counts.triangles = counts.faces;
    return counts;
}

// OBJ: "v" lines and "f" lines, each face with n corners giving n - 2 triangles.
FileCounts scan_obj(const std::string& path) {
    std::ifstream in(path);
    FileCounts counts;
    counts.vertices = 0;
    counts.triangles = 0;
    std::string line, keyword, corner;
    while (std::getline(in, line)) {
        std::istringstream words(line);
        if (!(words >> keyword)) continue;
        if (keyword == "v") {
            ++*counts.vertices;
        } else if (keyword == "f") {
            ++counts.faces;
            uint64_t corners = 0;
            while (words >> corner) ++corners;
            if (corners >= 3) *counts.triangles += corners - 2;
        }
    }
    return counts;
}

// ---- the importer: OpenMesh's readers call it, we keep flat arrays --------------------

class FlatImporter final : public OpenMesh::IO::BaseImporter {
public:
    explicit FlatImporter(uint64_t file_bytes) : file_bytes_(file_bytes) {}

    std::vector<Vec3> vertices;
    std::vector<std::array<uint32_t, 3>> triangles;
    uint64_t faces = 0;      // every add_face call, valid or not
    uint64_t polygons = 0;   // faces with more than three corners
    uint64_t bad_faces = 0;  // faces we could not take (too few corners, bad index)
    std::string first_bad_face;

    VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
        vertices.push_back({p[0], p[1], p[2]});
        return VertexHandle(int(vertices.size() - 1));
    }
    VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3f(0, 0, 0)); }
    void set_point(VertexHandle vh, const OpenMesh::Vec3f& p) override {
        if (vh.is_valid() && size_t(vh.idx()) < vertices.size()) vertices[size_t(vh.idx())] = {p[0], p[1], p[2]};
    }

    // Every face the reader passes on is kept, whatever its neighbourhood: non-manifold
    // edges, repeated corners and unused vertices are the file's business, and a ray
    // tracer handles them. Polygons become a fan around their first corner.
    FaceHandle add_face(const VHandles& corners) override {
        const uint64_t face = faces++;
        if (corners.size() < 3) {
            note_bad_face("face " + std::to_string(face) + " has " + std::to_string(corners.size()) +
                          " corners (a face needs at least 3)");
            return FaceHandle();
        }
        for (const VertexHandle& vh : corners) {
            if (!vh.is_valid() || size_t(vh.idx()) >= vertices.size()) {
                note_bad_face("face " + std::to_string(face) + " refers to vertex " + std::to_string(vh.idx()) +
                              " but the file has " + std::to_string(vertices.size()) + " vertices");
                return FaceHandle();
            }
        }
        if (corners.size() > 3) ++polygons;
        const auto index = [&](size_t k) { return uint32_t(corners[k].idx()); };
        for (size_t k = 1; k + 1 < corners.size(); ++k) triangles.push_back({index(0), index(k), index(k + 1)});
        return FaceHandle(int(face));
    }

    // Headers can lie (a corrupt count): reserve no more than the file could hold.
    void reserve(unsigned int nV, unsigned int, unsigned int nF) override {
        vertices.reserve(std::min<uint64_t>(nV, file_bytes_ / 6));
        triangles.reserve(std::min<uint64_t>(nF, file_bytes_ / 4));
    }

    size_t n_vertices() const override { return vertices.size(); }
    size_t n_faces() const override { return faces; }
    size_t n_edges() const override { return 0; }

    // Everything below is attribute data (normals, colours, texture coordinates) or
    // half-edge connectivity, which a flat triangle soup does not keep.
    HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
    FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
    void set_face_texindex(FaceHandle, int) override {}
    void set_halfedge(VertexHandle, HalfedgeHandle) override {}
    void set_normal(VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_normal(VertexHandle, const OpenMesh::Vec3d&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_color(VertexHandle, const OpenMesh::Vec4f&) override {}
    void set_texcoord(VertexHandle, const OpenMesh::Vec2f&) override {}
    void set_status(VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_next(HalfedgeHandle, HalfedgeHandle) override {}
    void set_face(HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(HalfedgeHandle, const OpenMesh::Vec2f&) override {}
    void set_texcoord(VertexHandle, const OpenMesh::Vec3f&) override {}
    void set_texcoord(HalfedgeHandle, const OpenMesh::Vec3f&) override {}
    void set_status(HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec3f&) override {}
    void set_color(EdgeHandle, const OpenMesh::Vec4f&) override {}
    void set_status(EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3f&) override {}
    void set_normal(FaceHandle, const OpenMesh::Vec3d&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3uc&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4uc&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec3f&) override {}
    void set_color(FaceHandle, const OpenMesh::Vec4f&) override {}
    void set_status(FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
    void add_texture_information(int, std::string) override {}

private:
    void note_bad_face(std::string what) {
        if (bad_faces++ == 0) first_bad_face = std::move(what);
    }
    uint64_t file_bytes_;
};

// ---- OpenMesh's log output ---------------------------------------------------------
//
// The readers write to omerr()/omlog() (which forward to std::cerr/std::clog) and, in
// places, to std::cerr directly — per face, for a file with many odd faces. While a file
// is read, both standard streams write into a buffer instead; the caller then prints at
// most one summary line. The redirection is process-wide, hence the lock in load_mesh.
class CapturedReaderOutput {
public:
    CapturedReaderOutput() : cerr_(std::cerr.rdbuf(text_.rdbuf())), clog_(std::clog.rdbuf(text_.rdbuf())) {}
    ~CapturedReaderOutput() { release(); }
    CapturedReaderOutput(const CapturedReaderOutput&) = delete;
    CapturedReaderOutput& operator=(const CapturedReaderOutput&) = delete;

    // Restores the streams; returns the non-empty lines that were written.
    std::vector<std::string> release() {
        if (cerr_) {
            ::omerr().flush();
            ::omlog().flush();
            std::cerr.rdbuf(cerr_);
            std::clog.rdbuf(clog_);
            cerr_ = clog_ = nullptr;
        }
        std::vector<std::string> lines;
        std::istringstream in(text_.str());
        for (std::string line; std::getline(in, line);)
            if (line.find_first_not_of(" \t\r") != std::string::npos) lines.push_back(line);
        return lines;
    }

private:
    std::ostringstream text_;
    std::streambuf* cerr_;
    std::streambuf* clog_;
};

// ---- gzip --------------------------------------------------------------------------

void gunzip(const std::string& from, const fs::path& to) {
    gzFile in = gzopen(from.c_str(), "rb");
    if (!in) fail(from, "cannot open it for reading");
    std::ofstream out(to, std::ios::binary);
    std::vector<char> buffer(1 << 18);
    std::string error;
    for (bool first = true;; first = false) {
        const int n = gzread(in, buffer.data(), unsigned(buffer.size()));
        if (first && gzdirect(in)) {
            error = "it is named .gz but is not gzip-compressed";
            break;
        }
        if (n < 0) {
            int code = 0;
            error = std::string("corrupt gzip data (") + gzerror(in, &code) + ")";
            break;
        }
        if (n == 0) break;
        out.write(buffer.data(), n);
    }
    // gzclose_r reports a stream that ended in the middle (a truncated download).
    const int closed = gzclose_r(in);
    if (error.empty() && closed != Z_OK) error = "truncated or corrupt gzip data";
    if (!error.empty()) fail(from, error);
    if (!out.flush()) fail(from, "cannot write the decompressed copy to " + to.string());
}

// Runs OpenMesh's reader for the format. PLY and OFF are read from a stream we own that
// throws at its first failed read. Their ASCII readers do not check each read: past the
// end of a truncated file, or after a word that is not a number, every further read leaves
// its variable as it was, so they repeat the last face, or take an uninitialised corner
// count and loop for billions of corners. Stopping at the first failure turns all of that
// into one clear error. A complete file is read to its last face without a failed read.
// (OBJ and STL are line-based: their readers parse each line on its own and run to the end
// of the file by design; the counts checked afterwards catch what a cut file loses.)
bool read_with_openmesh(const std::string& format, const std::string& path, FlatImporter& importer,
                        bool& stream_failed) {
    OpenMesh::IO::Options options;  // positions and faces only
    if (format != "ply" && format != "off") return OpenMesh::IO::IOManager().read(path, importer, options);

    std::ifstream in(path, std::ios::binary);
    in.exceptions(std::ios::failbit | std::ios::badbit);
    // The readers switch omerr() off while they read faces and back on at the end; an
    // exception skips the second half.
    const bool omerr_was_enabled = ::omerr().is_enabled();
    bool parsed = false;
    try {
        if (format == "ply") {
            parsed = OpenMesh::IO::PLYReader().read(in, importer, options);
        } else {
            // As IOManager does: the header check sets the reader's options (binary, normals,
            // colours) that read() then follows.
            OpenMesh::IO::_OFFReader_& reader = OpenMesh::IO::OFFReader();
            parsed = reader.can_u_read(path) && reader.read(in, importer, options);
        }
    } catch (const std::exception&) {  // std::ios_base::failure (of either library ABI)
        stream_failed = true;
        parsed = true;  // the reader did not reject the file; report the failed read
    }
    if (omerr_was_enabled) ::omerr().enable();
    return parsed;
}

}  // namespace

Scene load_mesh(const std::string& path, MeshLoadInfo* info_out) {
    std::error_code ec;
    if (!fs::exists(path, ec)) fail(path, "file not found");
    if (!fs::is_regular_file(path, ec)) fail(path, "not a regular file");
    if (!std::ifstream(path, std::ios::binary)) fail(path, "file cannot be opened for reading");

    // "name.ply.gz" -> compressed, format "ply", scene name "name".
    fs::path inner = fs::path(path).filename();
    MeshLoadInfo info;
    if (lowercase(inner.extension().string()) == ".gz") {
        info.compressed = true;
        inner = inner.stem();
    }
    info.format = lowercase(inner.extension().string());
    if (!info.format.empty()) info.format.erase(0, 1);
    if (info.format != "obj" && info.format != "ply" && info.format != "off" && info.format != "stl")
        fail(path, "unsupported file extension (supported: .obj .ply .off .stl, each optionally .gz)");

    std::optional<TempDir> temp;
    std::string readable = path;
    if (info.compressed) {
        temp.emplace("accelbench-mesh-");
        readable = (temp->path() / inner).string();
        gunzip(path, readable);
    }

    FileCounts declared;
    if (info.format == "ply") declared = scan_ply(readable, path);
    else if (info.format == "off") declared = scan_off(readable, path);
    else if (info.format == "stl") declared = scan_stl(readable, path);
    else declared = scan_obj(readable);

    FlatImporter importer(fs::file_size(readable));
    bool parsed = false, stream_failed = false;
    std::vector<std::string> messages;
    {
        static std::mutex reader_lock;
        std::lock_guard<std::mutex> lock(reader_lock);
        CapturedReaderOutput captured;
        parsed = read_with_openmesh(info.format, readable, importer, stream_failed);
        messages = captured.release();
    }
    info.reader_messages = messages.size();
    const std::string first_message = messages.empty() ? "" : " (OpenMesh: " + messages.front() + ")";

    if (!parsed) fail(path, "OpenMesh's " + info.format + " reader rejected the file: corrupt or truncated" + first_message);
    if (stream_failed)
        fail(path, "corrupt or truncated: the file ended, or held something other than a number, before the "
                   "reader had read everything the header declares" + first_message);
    if (importer.bad_faces > 0)
        fail(path, "corrupt mesh: " + importer.first_bad_face +
                       (importer.bad_faces > 1 ? " (and " + std::to_string(importer.bad_faces - 1) + " more bad faces)" : ""));
    if (declared.vertices && *declared.vertices != importer.vertices.size())
        fail(path, "corrupt or truncated: the file declares " + std::to_string(*declared.vertices) +
                       " vertices but the reader delivered " + std::to_string(importer.vertices.size()));
    if (declared.faces != importer.faces) {
        const std::string hint = info.format == "stl" ? " (OpenMesh's STL reader skips triangles with two corners at the same position)"
                               : info.format == "obj" ? " (OpenMesh's OBJ reader skips faces with fewer than 3 distinct corners)"
                               : "";
        fail(path, "faces were lost: the file has " + std::to_string(declared.faces) +
                       " faces but the reader delivered " + std::to_string(importer.faces) + hint + first_message);
    }
    if (declared.triangles && *declared.triangles != importer.triangles.size())
        fail(path, "the file's faces make " + std::to_string(*declared.triangles) + " triangles but " +
                       std::to_string(importer.triangles.size()) + " were loaded (the reader dropped corners)");
    if (importer.triangles.empty()) fail(path, "empty mesh (no triangles)");

    Scene scene;
    scene.name = inner.stem().string();
    scene.vertices = std::move(importer.vertices);
    scene.triangles = std::move(importer.triangles);
    try {
        scene.finalize();
    } catch (const std::exception& e) {
        fail(path, e.what());
    }

    info.file_faces = declared.faces;
    info.polygons = importer.polygons;
    info.triangles = scene.triangle_count();
    info.vertices = scene.vertex_count();
    if (!messages.empty())
        std::cerr << "accelbench: OpenMesh printed " << messages.size() << " message line(s) while reading '" << path
                  << "' (first: " << messages.front() << ")\n";
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
        if (c.find('\n') != std::string::npos) throw std::invalid_argument("write_ply: a comment with a newline");
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
