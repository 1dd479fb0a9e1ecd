// Loading triangle meshes from files: OBJ, PLY (ASCII and binary), OFF and STL (ASCII
// and binary), each optionally gzip-compressed (".ply.gz"), and glTF 2.0 scenes (.gltf
// and .glb, read through tinygltf: mesh_gltf.cpp says what is taken from them).
//
// The readers are our own, strict, and follow each format's specification (the rules and
// limits are listed in docs/configs.md, "Mesh files"): a file is loaded whole and exactly
// as written, or refused with a message naming the file, the place (line, or face / vertex
// number) and the cause — never loaded differently. Vertices and faces go straight into
// flat arrays in file order (no half-edge mesh, which would refuse or split non-manifold
// faces), polygons become a fan around their first corner.
//
// Places in messages: "line N" counts lines from 1 (a line ends at LF, CR LF or a lone
// CR); "face N" is the file's N-th face counting from 1, before triangulation (STL:
// "triangle N"); "byte N" is an offset from the file's start (binary files); a vertex is
// named by the index the file's faces use for it (OBJ counts from 1, PLY and OFF from 0).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "accelbench/scene/camera.h"
#include "accelbench/scene/scene.h"

namespace accelbench {

// What a load found, for logs and for checking counts against a registry.
struct MeshLoadInfo {
    std::string format;       // "obj", "ply", "off", "stl", "gltf" or "glb" (the inner format of a .gz)
    std::string reader;       // what read it: "accelbench" (our own readers) or "tinygltf 2.7.0"
    bool compressed = false;  // the file was gzip-compressed
    uint64_t file_faces = 0;  // faces (polygons) the file holds
    uint64_t polygons = 0;    // of those, faces with more than three corners
    uint64_t triangles = 0;   // after fan triangulation; equals the scene's count
    uint64_t vertices = 0;    // equals the file's vertex count (STL: distinct positions)
    // glTF: the first perspective camera met walking the default scene's nodes, placed by
    // its node's transform; nullopt for the other formats and for a glTF without one.
    std::optional<Camera> camera;
};

// The reader of glTF files with its version, as MeshLoadInfo::reader names it.
std::string gltf_reader();

// The format load_mesh reads `path` as, from its extension ("ply" for "a.PLY.gz", setting
// *compressed); "" for an extension it does not read.
std::string mesh_format(const std::string& path, bool* compressed = nullptr);
// What reads the file at `path` (MeshLoadInfo::reader), known from its name alone.
std::string mesh_reader(const std::string& path);

// The largest (decompressed) file load_mesh reads: files are read into memory whole.
constexpr uint64_t kMaxMeshFileBytes = uint64_t(4) << 30;

// Loads every triangle of the file at `path` into a finalized Scene named after the file's
// stem ("dragon_vrip" for "dragon_vrip.ply.gz"); a glTF's triangles are those its default
// scene's nodes place, in world space. Throws std::runtime_error
// "cannot load mesh 'PATH': PLACE: CAUSE" for: a missing file or one that is not a regular
// file, an unsupported extension, corrupt gzip data, anything the format does not allow or
// that is cut short, a vertex that is not finite or has a coordinate of magnitude
// kMaxCoordinate or more, a face referring to a vertex that does not exist, and a mesh
// with no triangles.
Scene load_mesh(const std::string& path, MeshLoadInfo* info = nullptr);

// The reader behind load_mesh, on a file's (uncompressed) bytes: `format` is "obj", "ply",
// "off", "stl", "gltf" or "glb"; `shown` names the file in messages and its stem names the
// scene (a glTF's external buffers are read from `shown`'s folder). Throws as load_mesh does.
Scene parse_mesh(std::string_view bytes, const std::string& format, const std::string& shown,
                 MeshLoadInfo* info = nullptr);

// Writes the scene as a binary little-endian PLY (float x, y, z; uchar-counted int
// indices), with one `comment` header line per entry of `comments` (no newlines in them),
// so load_mesh reads back exactly these vertices and triangles. Throws
// std::runtime_error naming the path when writing fails.
void write_ply(const Scene& scene, const std::string& path, const std::vector<std::string>& comments = {});

// The `comment` lines of a PLY file's header, without the keyword; empty when the file is
// missing or not a PLY.
std::vector<std::string> read_ply_comments(const std::string& path);

}  // namespace accelbench
