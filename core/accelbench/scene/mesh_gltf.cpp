// glTF 2.0 (Khronos, "glTF 2.0 Specification", 2021), .gltf (JSON with its buffers in
// files beside it or in data: URIs) and .glb (one binary container), parsed by tinygltf
// (Debian's libtinygltf-dev); what is taken from the parsed model is ours and strict.
//
// Taken: the triangles of every mesh primitive the default scene's node hierarchy reaches
// (the file's `scene`, else its first), each placed by its node's world transform (the
// product of `matrix` or translation * rotation * scale down the hierarchy, spec 3.5), a
// mesh used by two nodes twice; and the first perspective camera met on that walk (depth
// first, children in order), looking down its node's -z with +y up (spec 3.10).
// Refused, in one line naming the file and the part: a file tinygltf cannot parse (its own
// message: a data: URI that does not decode, a missing buffer), an external file outside
// the glTF's folder, a primitive whose mode is not triangles, a POSITION that is not float
// VEC3, sparse accessors, data past its buffer view or buffer, an index out of range, a
// node hierarchy with a cycle, and a scene with no triangles. Not read: materials, images
// (never opened), animations, skins and morph targets (the rest pose is traced).
#include <tiny_gltf.h>

#include <filesystem>
#include <fstream>

#include "accelbench/scene/mesh_reading.h"

#ifndef ACCELBENCH_TINYGLTF_VERSION
#error "ACCELBENCH_TINYGLTF_VERSION (set by CMakeLists.txt from find_package(TinyGLTF)) is missing"
#endif

namespace accelbench {

std::string gltf_reader() { return std::string("tinygltf ") + ACCELBENCH_TINYGLTF_VERSION; }

namespace mesh_reading {
namespace {

namespace fs = std::filesystem;

// ---- files: only the glTF's own folder -----------------------------------------------

// tinygltf looks for an external file first in the base folder, then in the process's
// working directory; only the first is the file's business. A path that leaves the folder
// (a "../" or an absolute uri, a symbolic link out) is never opened, and remembered for
// the message.
struct Folder {
    std::string base;  // as given to tinygltf
    fs::path canonical;
    std::string outside;  // the first file refused for lying outside
};

bool inside(Folder& folder, const std::string& path, bool remember) {
    if (path.rfind(folder.base + "/", 0) != 0) return false;  // a working-directory attempt
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(path, ec);
    const fs::path rel = resolved.lexically_relative(folder.canonical);
    const bool ok = !ec && !rel.empty() && *rel.begin() != "..";
    if (!ok && remember && folder.outside.empty()) folder.outside = path.substr(folder.base.size() + 1);
    return ok;
}

bool file_exists(const std::string& path, void* user) {
    return inside(*static_cast<Folder*>(user), path, true) && fs::is_regular_file(path);
}

std::string same_path(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion

bool is_image(const std::string& path) {
    const std::string ext = lowercase(fs::path(path).extension().string());
    return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".ktx2" || ext == ".webp" || ext == ".dds";
}

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    if (!inside(*static_cast<Folder*>(user), path, true)) return *err = "outside the glTF's folder", false;
    if (is_image(path)) return *err = "images are not read (nothing here uses textures)", false;
    std::error_code ec;
    const uint64_t size = fs::file_size(path, ec);
    if (ec || size > kMaxMeshFileBytes) return *err = ec ? ec.message() : "larger than 4 GiB", false;
    out->resize(size_t(size));
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(out->data()), std::streamsize(size))) return *err = "reading failed", false;
    return true;
}

bool no_writing(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    *err = "the reader writes nothing";
    return false;
}

// Embedded images are left undecoded: only geometry is traced.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

// tinygltf's messages, one per line, as one line, cut at 400 characters (a message may
// quote a data: URI of megabytes).
std::string one_line(const std::string& text) {
    std::string out;
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        std::string_view part(text.data() + start, end - start);
        while (!part.empty() && std::isspace(static_cast<unsigned char>(part.back()))) part.remove_suffix(1);
        if (!part.empty()) out += (out.empty() ? "" : "; ") + std::string(part);
        start = end + 1;
    }
    return out.size() > 400 ? out.substr(0, 400) + "..." : out;
}

tinygltf::Model parse(std::string_view bytes, bool binary, const std::string& base) {
    Folder folder{base, fs::weakly_canonical(base), ""};
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks({file_exists, same_path, read_whole_file, no_writing, &folder});
    loader.SetImageLoader(skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    if (bytes.size() > std::numeric_limits<unsigned int>::max()) throw MeshError("larger than tinygltf reads (4 GiB)");
    const bool ok = binary
        ? loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                      unsigned(bytes.size()), base)
        : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), base);
    if (!folder.outside.empty())
        throw MeshError("external file " + shown(folder.outside) + " lies outside the glTF's folder");
    if (!ok) throw MeshError("glTF: " + one_line(err.empty() ? warn : err));
    return model;
}

// ---- transforms ------------------------------------------------------------------------

// Column-major 4x4, as glTF stores it: element (row r, column c) at [c * 4 + r].
using Mat4 = std::array<double, 16>;

constexpr Mat4 kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

Mat4 operator*(const Mat4& a, const Mat4& b) {
    Mat4 m{};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            for (int k = 0; k < 4; ++k) m[size_t(c * 4 + r)] += a[size_t(k * 4 + r)] * b[size_t(c * 4 + k)];
    return m;
}

// The node's own transform: its matrix, else T * R * S (spec 3.5.2).
Mat4 local_transform(const tinygltf::Node& n, size_t index) {
    const std::string place = "node " + number(index) + ": ";
    if (!n.matrix.empty()) {
        if (n.matrix.size() != 16)
            throw MeshError(place + "matrix has " + number(n.matrix.size()) + " numbers, not 16");
        Mat4 m;
        std::copy(n.matrix.begin(), n.matrix.end(), m.begin());
        return m;
    }
    const auto sized = [&](const std::vector<double>& v, size_t k, const char* what) {
        if (!v.empty() && v.size() != k) throw MeshError(place + what + " has " + number(v.size()) + " numbers");
        return !v.empty();
    };
    Mat4 t = kIdentity, r = kIdentity, s = kIdentity;
    if (sized(n.translation, 3, "translation")) std::copy(n.translation.begin(), n.translation.end(), t.begin() + 12);
    if (sized(n.scale, 3, "scale"))
        for (int k = 0; k < 3; ++k) s[size_t(k * 5)] = n.scale[size_t(k)];
    if (sized(n.rotation, 4, "rotation")) {
        const double x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
        r = {1 - 2 * (y * y + z * z),
             2 * (x * y + z * w),
             2 * (x * z - y * w),
             0,
             2 * (x * y - z * w),
             1 - 2 * (x * x + z * z),
             2 * (y * z + x * w),
             0,
             2 * (x * z + y * w),
             2 * (y * z - x * w),
             1 - 2 * (x * x + y * y),
             0,
             0,
             0,
             0,
             1};
    }
    return t * r * s;
}

Vec3 point_of(const Mat4& m, double x, double y, double z, double w) {
    const auto row = [&](int r) {
        return m[size_t(r)] * x + m[size_t(4 + r)] * y + m[size_t(8 + r)] * z + m[size_t(12 + r)] * w;
    };
    return {float(row(0)), float(row(1)), float(row(2))};
}

// ---- accessors -------------------------------------------------------------------------

// An accessor's elements in their buffer: the first one's bytes and the step between two.
struct Elements {
    const unsigned char* first = nullptr;
    size_t stride = 0;
    size_t count = 0;
};

const tinygltf::Accessor& accessor(const tinygltf::Model& model, int index, const std::string& place) {
    if (index < 0 || size_t(index) >= model.accessors.size())
        throw MeshError(place + "accessor " + std::to_string(index) + " does not exist");
    return model.accessors[size_t(index)];
}

Elements elements(const tinygltf::Model& model, int index, size_t element_bytes, const std::string& place) {
    const tinygltf::Accessor& a = accessor(model, index, place);
    const std::string at = place + "accessor " + number(size_t(index)) + ": ";
    if (a.sparse.isSparse) throw MeshError(at + "sparse accessors are not read");
    if (a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size())
        throw MeshError(at + "no buffer view (its data would be all zeros)");
    const tinygltf::BufferView& v = model.bufferViews[size_t(a.bufferView)];
    if (v.buffer < 0 || size_t(v.buffer) >= model.buffers.size()) throw MeshError(at + "its buffer does not exist");
    const std::vector<unsigned char>& data = model.buffers[size_t(v.buffer)].data;
    const size_t stride = v.byteStride ? v.byteStride : element_bytes;
    if (v.byteOffset > data.size() || v.byteLength > data.size() - v.byteOffset)
        throw MeshError(at + "its buffer view runs past its buffer (" + number(data.size()) + " bytes)");
    if (a.count > 0 &&
        (a.byteOffset > v.byteLength || (a.count - 1) > (v.byteLength - a.byteOffset) / stride ||
         a.byteOffset + (a.count - 1) * stride + element_bytes > v.byteLength))
        throw MeshError(at + number(a.count) + " elements run past its buffer view (" + number(v.byteLength) +
                        " bytes)");
    return {data.data() + v.byteOffset + a.byteOffset, stride, a.count};
}

const char* mode_name(int mode) {
    switch (mode) {
        case TINYGLTF_MODE_POINTS: return "points";
        case TINYGLTF_MODE_LINE: return "lines";
        case TINYGLTF_MODE_LINE_LOOP: return "line loop";
        case TINYGLTF_MODE_LINE_STRIP: return "line strip";
        case TINYGLTF_MODE_TRIANGLE_STRIP: return "triangle strip";
        case TINYGLTF_MODE_TRIANGLE_FAN: return "triangle fan";
        default: return "unknown";
    }
}

void add_primitive(const tinygltf::Model& model, const tinygltf::Primitive& p, const Mat4& world,
                   const std::string& place, FlatMesh& mesh) {
    if (p.mode != TINYGLTF_MODE_TRIANGLES)
        throw MeshError(place + "mode " + std::to_string(p.mode) + " (" + mode_name(p.mode) + "), not triangles (4)");
    const auto position = p.attributes.find("POSITION");
    if (position == p.attributes.end()) throw MeshError(place + "no POSITION attribute");
    const tinygltf::Accessor& pa = accessor(model, position->second, place);
    if (pa.type != TINYGLTF_TYPE_VEC3 || pa.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        throw MeshError(place + "POSITION is not float VEC3");
    const Elements positions = elements(model, position->second, 12, place);
    const uint64_t base = mesh.vertices.size();
    for (size_t i = 0; i < positions.count; ++i) {
        float xyz[3];
        std::memcpy(xyz, positions.first + i * positions.stride, sizeof xyz);
        mesh.add_vertex(point_of(world, xyz[0], xyz[1], xyz[2], 1),
                        [&] { return place + "vertex " + number(i) + ": "; });
    }
    std::vector<uint32_t> corners(3);
    const auto add = [&](uint64_t k, uint64_t index) {
        if (index >= positions.count)
            throw MeshError(place + "index " + number(index) + " (element " + number(k) + ") is out of range (" +
                            number(positions.count) + " vertices)");
        corners[size_t(k % 3)] = uint32_t(base + index);
        if (k % 3 == 2) mesh.add_face(corners);
    };
    if (p.indices < 0) {
        if (positions.count % 3) throw MeshError(place + number(positions.count) + " vertices, not a multiple of 3");
        for (uint64_t k = 0; k < positions.count; ++k) add(k, k);
        return;
    }
    const tinygltf::Accessor& ia = accessor(model, p.indices, place);
    const int ct = ia.componentType;
    const size_t bytes = ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ? 1
        : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT               ? 2
        : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT                 ? 4
                                                                     : 0;
    if (ia.type != TINYGLTF_TYPE_SCALAR || bytes == 0)
        throw MeshError(place + "indices are not unsigned byte, short or int scalars");
    const Elements indices = elements(model, p.indices, bytes, place);
    if (indices.count % 3) throw MeshError(place + number(indices.count) + " indices, not a multiple of 3");
    for (size_t k = 0; k < indices.count; ++k) {
        uint32_t index = 0;  // little-endian, as glTF stores it
        for (size_t b = 0; b < bytes; ++b) index |= uint32_t(indices.first[k * indices.stride + b]) << (8 * b);
        add(k, index);
    }
}

// The camera of node `n` at `world` (spec 3.10.1: it looks down its local -z, +y up).
std::optional<Camera> node_camera(const tinygltf::Model& model, const tinygltf::Node& n, const Mat4& world) {
    if (n.camera < 0) return std::nullopt;
    if (size_t(n.camera) >= model.cameras.size())
        throw MeshError("camera " + std::to_string(n.camera) + " does not exist");
    const tinygltf::Camera& c = model.cameras[size_t(n.camera)];
    if (c.type != "perspective") return std::nullopt;  // an orthographic view: the default view instead
    const double fov_deg = c.perspective.yfov * 180.0 / 3.14159265358979323846;
    if (!(fov_deg > 0 && fov_deg <= 179))
        throw MeshError("camera " + number(size_t(n.camera)) + ": yfov " + std::to_string(c.perspective.yfov) +
                        " radians is outside (0, 179] degrees");
    Camera cam;
    cam.eye = point_of(world, 0, 0, 0, 1);
    const Vec3 forward = point_of(world, 0, 0, -1, 0);
    if (!(length(forward) > 0.0f) || !is_finite(forward))
        throw MeshError("camera " + number(size_t(n.camera)) + ": its node's transform has no view direction");
    cam.look_at = cam.eye + normalize(forward);
    cam.up = point_of(world, 0, 1, 0, 0);
    cam.fov_deg = float(fov_deg);
    cam.aspect = float(c.perspective.aspectRatio > 0 ? c.perspective.aspectRatio : 0.0);
    return cam;
}

struct Walk {
    const tinygltf::Model& model;
    FlatMesh& mesh;
    std::optional<Camera> camera;
    std::vector<bool> on_path;  // the nodes between the root and here: a repeat is a cycle

    void node(int index, const Mat4& parent) {
        if (index < 0 || size_t(index) >= model.nodes.size())
            throw MeshError("node " + std::to_string(index) + " does not exist");
        const size_t i = size_t(index);
        if (on_path[i]) throw MeshError("node " + number(i) + ": the node hierarchy has a cycle");
        on_path[i] = true;
        const tinygltf::Node& n = model.nodes[i];
        const Mat4 world = parent * local_transform(n, i);
        if (!camera) camera = node_camera(model, n, world);
        if (n.mesh >= 0) {
            if (size_t(n.mesh) >= model.meshes.size())
                throw MeshError("mesh " + std::to_string(n.mesh) + " does not exist");
            const tinygltf::Mesh& m = model.meshes[size_t(n.mesh)];
            for (size_t p = 0; p < m.primitives.size(); ++p)
                add_primitive(
                    model, m.primitives[p], world,
                    "node " + number(i) + ", mesh " + number(size_t(n.mesh)) + ", primitive " + number(p) + ": ", mesh);
        }
        for (int child : n.children) node(child, world);
        on_path[i] = false;
    }
};

}  // namespace

std::optional<Camera> read_gltf(std::string_view bytes, bool binary, const std::string& folder, FlatMesh& mesh) {
    const tinygltf::Model model = parse(bytes, binary, folder);
    if (model.scenes.empty()) throw MeshError("no scene (the file lists none, so it shows nothing)");
    const size_t scene = model.defaultScene >= 0 ? size_t(model.defaultScene) : 0;
    if (scene >= model.scenes.size()) throw MeshError("the default scene " + number(scene) + " does not exist");
    Walk walk{model, mesh, std::nullopt, std::vector<bool>(model.nodes.size(), false)};
    for (int root : model.scenes[scene].nodes) walk.node(root, kIdentity);
    return walk.camera;
}

}  // namespace mesh_reading
}  // namespace accelbench
