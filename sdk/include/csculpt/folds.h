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
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"

namespace csculpt {

/// Counts the new folds of merges on one mesh, reusing its workspace: what a session's merger
/// runs after every merge.
class FoldCounter {
 public:
  /// `topology` (of the base's triangles, e.g. a Hierarchy's) must outlive the counter.
  explicit FoldCounter(const Topology& topology);

  /// New folds of a merge: faces flipped from `base` to `base + merged` but by none of
  /// `diffs` (each applied to `base` on its own) — creases or spikes no artist made.
  ///
  /// Sparse: only faces around the vertices whose position `merged` changes are looked at (a
  /// face none of whose vertices moved cannot flip), found through `topology.vertex_faces`,
  /// with merged positions found in O(1) through a per-vertex slot array kept between calls;
  /// the diffs are searched only for the faces the merge flipped. No allocation. Throws
  /// InvalidInput when `base` is not the topology's mesh or a diff indexes past it.
  std::uint32_t count_new_folds(const Mesh& base, std::span<const Diff* const> diffs,
                                const Diff& merged);

 private:
  const Topology* topology_;
  std::vector<std::uint32_t>
      slot_;  ///< per vertex: index among merged's changes; none between calls
};

/// One-off forms of FoldCounter::count_new_folds: with a topology (allocates the slot array),
/// or without (one pass over the triangles).
std::uint32_t count_new_folds(const Topology& topology, const Mesh& base,
                              std::span<const Diff* const> diffs, const Diff& merged);
std::uint32_t count_new_folds(const Mesh& base, std::span<const Diff* const> diffs,
                              const Diff& merged);

/// Pairs of faces sharing an edge whose normals have a negative dot product: a visible crease
/// or spike on `mesh` (assumes consistently oriented faces, as the built-in and Blender meshes
/// are). Counted once per shared edge; degenerate faces count in no pair.
std::uint32_t count_opposed_face_pairs(const Mesh& mesh);

}  // namespace csculpt
