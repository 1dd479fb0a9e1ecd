// Model transforms for scaling experiments: one real model at many sizes.
//
// Decimation (OpenMesh's quadric-error Decimater, Garland & Heckbert 1997) shrinks the
// 871k Stanford dragon to 10k..300k triangles; Loop subdivision (Loop 1987) grows the
// bunny to 278k and 1.1M. Both keep the model's shape and its view, so only the triangle
// count changes between sizes — which is what a scaling plot needs.
//
// Both go through an OpenMesh half-edge TriMesh, which refuses faces that would make an
// edge or vertex non-manifold ("complex edge") and faces with a repeated corner. No face
// is lost: such a face is added with its own copies of its corners (as OpenMesh's readers
// do), a component of its own, and counted in MeshTransformInfo. Subdivision divides it
// like every face (a face with a repeated corner into zero-area faces); decimation never
// collapses an edge of a lone triangle (OpenMesh's is_collapse_ok), so it stays as it is.
// Both transforms are deterministic: the same input gives the same output, vertex for
// vertex.
#pragma once

#include <cstddef>
#include <cstdint>

#include "accelbench/scene/scene.h"

namespace accelbench {

struct MeshTransformInfo {
    uint64_t source_triangles = 0;
    // Faces the half-edge mesh refused on the source's vertices, added with their own copies
    // of their corners (none is dropped): non-manifold ones, and ones with a repeated corner.
    uint64_t detached_faces = 0;
    uint64_t degenerate_faces = 0;
    uint64_t triangles = 0;  // of the result
    uint64_t vertices = 0;   // of the result (only vertices some triangle uses)
};

// Collapses edges in order of least quadric error until at most `target_triangles`
// remain (or no collapse is legal). Throws std::invalid_argument when target_triangles is
// 0 or not below the scene's triangle count. The result is finalized and keeps the name.
Scene decimate(const Scene& scene, size_t target_triangles, MeshTransformInfo* info = nullptr);

// `levels` rounds of Loop subdivision: each turns every triangle into four (so the result
// has exactly 4^levels times the source's triangles). Throws
// std::invalid_argument unless 1 <= levels <= 4. The result is finalized.
Scene loop_subdivide(const Scene& scene, int levels, MeshTransformInfo* info = nullptr);

}  // namespace accelbench
