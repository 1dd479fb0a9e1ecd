#include "accelbench/scene/mesh_transform.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <array>
#include <limits>
#include <stdexcept>
#include <string>

namespace accelbench {

namespace {

// Double-precision points: quadrics and subdivision masks are sums of many products, and
// the result is rounded to float once, when it is flattened again.
struct TransformTraits : public OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
};
using HalfEdgeMesh = OpenMesh::TriMesh_ArrayKernelT<TransformTraits>;

// OpenMesh reports a refused face on its error log stream; such faces are detached and
// counted instead (to_half_edge), so the stream is muted while faces are added.
class MutedOpenMeshErrors {
public:
    MutedOpenMeshErrors() : was_enabled_(omerr().is_enabled()) { omerr().disable(); }
    ~MutedOpenMeshErrors() {
        if (was_enabled_) omerr().enable();
    }

private:
    bool was_enabled_;
};

// Every source face becomes a face of the half-edge mesh. One that would make an edge or a
// vertex non-manifold is added again with its own copies of its corners, as OpenMesh's own
// readers do (OpenMesh/Core/IO/importer/ImporterT.hh, add_face: "separate non-manifold
// faces"): it is then a component of its own. A face with a repeated corner is given copies
// straight away (never offered with its repeated vertex: a half-edge from a vertex to
// itself is no edge), three corners at two or one position, a face of zero area that the
// transforms carry along like any other.
HalfEdgeMesh to_half_edge(const Scene& scene, MeshTransformInfo& info) {
    using VertexHandle = HalfEdgeMesh::VertexHandle;
    HalfEdgeMesh mesh;
    mesh.reserve(scene.vertex_count(), 3 * scene.triangle_count(), scene.triangle_count());
    for (const Vec3& v : scene.vertices) mesh.add_vertex(HalfEdgeMesh::Point(v.x, v.y, v.z));
    info.source_triangles = scene.triangle_count();
    MutedOpenMeshErrors muted;
    for (const auto& t : scene.triangles) {
        std::array<VertexHandle, 3> v = {VertexHandle(int(t[0])), VertexHandle(int(t[1])), VertexHandle(int(t[2]))};
        const bool degenerate = t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
        if (!degenerate && mesh.add_face(v[0], v[1], v[2]).is_valid()) continue;
        ++(degenerate ? info.degenerate_faces : info.detached_faces);
        for (VertexHandle& h : v) {
            const HalfEdgeMesh::Point p = mesh.point(h);  // a copy: add_vertex may move the points
            h = mesh.add_vertex(p);
        }
        if (!mesh.add_face(v[0], v[1], v[2]).is_valid())
            throw std::logic_error("mesh transform: a face of three new vertices was refused");
    }
    return mesh;
}

// Back to flat arrays in OpenMesh's (deterministic) order, keeping only vertices some face
// uses: vertices left isolated (a detached face's originals that no other face uses, or
// removed by decimation) are not part of the model.
Scene flatten(const HalfEdgeMesh& mesh, const std::string& name, MeshTransformInfo& info) {
    Scene out;
    out.name = name;
    constexpr uint32_t unused = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> index(mesh.n_vertices(), unused);
    for (const auto f : mesh.faces()) {
        if (mesh.has_face_status() && mesh.status(f).deleted()) continue;
        std::array<uint32_t, 3> tri{};
        int corner = 0;
        for (const auto v : mesh.fv_range(f)) {
            uint32_t& i = index[size_t(v.idx())];
            if (i == unused) {
                const auto p = mesh.point(v);
                i = uint32_t(out.vertices.size());
                out.vertices.push_back({float(p[0]), float(p[1]), float(p[2])});
            }
            tri[size_t(corner++)] = i;
        }
        out.triangles.push_back(tri);
    }
    out.finalize();
    info.triangles = out.triangle_count();
    info.vertices = out.vertex_count();
    return out;
}

}  // namespace

Scene decimate(const Scene& scene, size_t target_triangles, MeshTransformInfo* info) {
    if (target_triangles == 0 || target_triangles >= scene.triangle_count())
        throw std::invalid_argument("decimate: target " + std::to_string(target_triangles) +
                                    " triangles must be in [1, " + std::to_string(scene.triangle_count()) + ") for '" +
                                    scene.name + "'");
    MeshTransformInfo local;
    MeshTransformInfo& i = info ? *info : local;
    i = {};
    HalfEdgeMesh mesh = to_half_edge(scene, i);
    mesh.request_vertex_status();
    mesh.request_edge_status();
    mesh.request_face_status();
    // The decimater needs face normals to reject collapses that would flip a face.
    mesh.request_face_normals();
    mesh.update_face_normals();
    {
        OpenMesh::Decimater::DecimaterT<HalfEdgeMesh> decimater(mesh);
        OpenMesh::Decimater::ModQuadricT<HalfEdgeMesh>::Handle quadric;
        decimater.add(quadric);
        // Binary mode: the quadric error only orders collapses, it bounds none of them,
        // so decimation goes on until the face target is met.
        decimater.module(quadric).unset_max_err();
        if (!decimater.initialize()) throw std::runtime_error("decimate: OpenMesh's decimater did not initialize");
        decimater.decimate_to_faces(0, target_triangles);
    }
    mesh.garbage_collection();
    return flatten(mesh, scene.name, i);
}

Scene loop_subdivide(const Scene& scene, int levels, MeshTransformInfo* info) {
    if (levels < 1 || levels > 4)
        throw std::invalid_argument("loop_subdivide: levels must be in [1, 4], got " + std::to_string(levels));
    MeshTransformInfo local;
    MeshTransformInfo& i = info ? *info : local;
    i = {};
    HalfEdgeMesh mesh = to_half_edge(scene, i);
    OpenMesh::Subdivider::Uniform::LoopT<HalfEdgeMesh> loop;
    loop.attach(mesh);
    if (!loop(size_t(levels)))
        throw std::runtime_error("loop_subdivide: OpenMesh's Loop subdivider failed on '" + scene.name + "'");
    loop.detach();
    return flatten(mesh, scene.name, i);
}

}  // namespace accelbench
