// Fold-overs: faces a merge turned inside out. One definition for the SDK, the sessions, the
// command line and the evaluation (shared/eval/score_merge.py, `flipped` and the CASE/folds
// rows), so every number called "new_folds" means the same thing.
//
// A face is *flipped* from positions P to positions Q when dot(n_P, n_Q) < 0, with n the
// unnormalised normal (v1 - v0) x (v2 - v0) computed in double precision in the order numpy
// computes it: its normal turned by more than 90 degrees. A degenerate face (zero normal on
// either side) is never flipped.
#pragma once

#include <cstdint>
#include <span>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"

namespace csculpt {

/// New folds of a merge: faces flipped from `base` to `base + merged` but by none of `diffs`
/// (each applied to `base` on its own) — creases or spikes no artist made.
///
/// Sparse: only faces around the vertices whose position `merged` changes are looked at (a
/// face none of whose vertices moved cannot flip), found through `topology.vertex_faces`;
/// positions are looked up in the diffs by binary search. No allocation, so it can run after
/// every session merge. `topology` must be the one of `base`'s triangles.
std::uint32_t count_new_folds(const Topology& topology, const Mesh& base,
                              std::span<const Diff* const> diffs, const Diff& merged);

/// The same without a topology: one pass over the triangles (and one bitmap of the vertices
/// `merged` moved). For one-off use; a session keeps a Topology and calls the overload above.
std::uint32_t count_new_folds(const Mesh& base, std::span<const Diff* const> diffs,
                              const Diff& merged);

/// Pairs of faces sharing an edge whose normals have a negative dot product: a visible crease
/// or spike on `mesh` (assumes consistently oriented faces, as the built-in and Blender meshes
/// are). Counted once per shared edge; degenerate faces count in no pair.
std::uint32_t count_opposed_face_pairs(const Mesh& mesh);

}  // namespace csculpt
