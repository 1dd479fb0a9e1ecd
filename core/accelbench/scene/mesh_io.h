// Loading triangle meshes from files: OBJ, PLY (ASCII and binary), OFF and STL (ASCII
// and binary), each optionally gzip-compressed (".ply.gz").
//
// Parsing is OpenMesh's (its IO readers), but the result never goes through a half-edge
// mesh: OpenMesh's TriMesh/PolyMesh refuse faces that would make an edge non-manifold
// ("complex edge") and duplicate vertices to repair others, so a scanned model would lose
// faces or gain vertices and no longer be the model the report measured. Our importer
// takes vertices and faces straight into flat arrays, in file order, triangulating
// polygons as a fan, and the loader then checks that the triangles match what the file
// declares: a mesh is loaded whole or not at all.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accelbench/scene/scene.h"

namespace accelbench {

// What a load found, for logs and for checking counts against a registry.
struct MeshLoadInfo {
    std::string format;           // "obj", "ply", "off" or "stl" (the inner format of a .gz)
    bool compressed = false;      // the file was gzip-compressed
    uint64_t file_faces = 0;      // faces (polygons) the file declares or contains
    uint64_t polygons = 0;        // of those, faces with more than three corners
    uint64_t triangles = 0;       // after fan triangulation; equals the scene's count
    uint64_t vertices = 0;        // equals the file's vertex count (STL: distinct positions)
    uint64_t reader_messages = 0; // lines OpenMesh's reader printed (collected, not shown)
};

// Loads every triangle of the file at `path` into a finalized Scene named after the file's
// stem ("dragon_vrip" for "dragon_vrip.ply.gz"). Throws std::runtime_error naming the path
// and the reason for: a missing or unreadable file, an unsupported extension, a corrupt or
// truncated file, a face the reader dropped or that refers to a vertex that does not
// exist, and a mesh with no triangles.
//
// OpenMesh's readers report through its global log streams; load_mesh collects those
// lines and prints at most one summary line to stderr. It serialises concurrent calls
// (those streams are process-wide), so loads do not run in parallel.
Scene load_mesh(const std::string& path, MeshLoadInfo* info = nullptr);

// Writes the scene as a binary little-endian PLY (float x, y, z; uchar-counted int
// indices), with one `comment` header line per entry of `comments` (no newlines in them),
// so load_mesh reads back exactly these vertices and triangles. Throws
// std::runtime_error naming the path when writing fails.
void write_ply(const Scene& scene, const std::string& path, const std::vector<std::string>& comments = {});

// The `comment` lines of a PLY file's header, without the keyword; empty when the file is
// missing or not a PLY.
std::vector<std::string> read_ply_comments(const std::string& path);

}  // namespace accelbench
