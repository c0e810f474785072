// The cSculpt merge (paper §3.1): N concurrent edits of one base mesh become one merged
// edit. Positions merge as per-vertex isometries (dual quaternions) decomposed over the
// multiresolution hierarchy, blended per node by magnitude and recomposed coarse to fine;
// every other channel merges the same way as translations in its linear space.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"

namespace csculpt {

/// The paper's algorithm and the variants it is compared with (Fig. 3, Fig. 5).
enum class MergeMethod : std::uint32_t {
  /// isometries: each artist's displacement carried in the frames the other artists' edits
  /// give the surface (a detail turns and follows a coarse edit at its own height), hedged
  /// toward how a volumetric deformer would move it where the two readings differ, each
  /// intent counted once; exact where one artist acted (docs/merge-quality.md)
  full = 0,
  single_parent = 1,           ///< isometries, multiscale, a tree (K = 1)
  single_level_isometry = 2,   ///< isometries blended per vertex, no hierarchy
  multiscale_translation = 3,  ///< translations, multiscale, K parents (no rotation)
  weighted_translation = 4,    ///< translations blended per vertex by magnitude (paper eq. 1)
  average = 5,                 ///< mean of the translations
  sum = 6,                     ///< sum of the translations
  /// the paper's algorithm as written: isometries, multiscale, K blended parents, residuals
  /// blended per node by normalize(sum_j |q_j - 1| q_j); channels through the hierarchy too
  paper_blend = 7,
  /// the previous `full`: isometries, multiscale, K blended parents; residuals blended per
  /// node by magnitude and counted once per intent, recomposed coarse to fine
  hierarchy_blend = 8,
  /// `full` without the hedge toward the stacked reading: details ride the surface's turn
  /// alone (nearest the frame ideal; under a volumetric taper or Cast, further from the stack)
  frame_transport = 9,
};

/// The most diffs one merge takes (the C ABI's CSC_MAX_MERGE_DIFFS).
inline constexpr std::size_t max_merge_diffs = 64;

std::string_view to_string(MergeMethod method);
/// "full", "single-parent", ...; throws InvalidInput listing the valid names otherwise.
MergeMethod merge_method_from_string(std::string_view name);
std::span<const MergeMethod> all_merge_methods();

/// The working frame: positions are merged in coordinates centred on `center` and divided by
/// `scale`, so the magnitude that weighs the blend does not depend on the model's units or
/// placement. Every peer of a session must use the same frame (fit it once on the session's
/// first mesh); fit() takes the bounding box centre and diagonal.
struct MergeFrame {
  Vec3f center{0, 0, 0};
  float scale = 1;
  static MergeFrame fit(std::span<const Vec3f> positions);
};

struct MergeTimings {
  double isometry_ms = 0;   ///< per-vertex isometries / translations of every diff
  double decompose_ms = 0;  ///< averages up the hierarchy
  double blend_ms = 0;      ///< residuals, per-node blend and reconstruction
  double apply_ms = 0;      ///< writing the merged diff
  /// Hierarchy nodes the merge visited (every diff's and the merged ones, all levels) and
  /// an estimate of the bytes it read and wrote for them: the yardstick for `stream_ms`.
  std::uint64_t nodes_visited = 0;
  std::uint64_t bytes_touched = 0;
  /// Faces the merge would have folded although no diff folds them, drawn back before the
  /// result was written (`full` only; see fold_repair.h).
  std::uint64_t new_folds_repaired = 0;
  double fold_repair_ms =
      0;  ///< looking for them (every merge) and repairing them (part of blend_ms)
};

/// How a merge treats diffs that make the same change at a vertex.
enum class SameChange {
  /// As one intent, counted once (idempotence): two artists who made the same edit get it
  /// once. What a session's merge does.
  once,
  /// Added like any other: the diffs are known to be different intents (an artist's undo or
  /// redo against everything else that happened), so a matching change is a coincidence.
  add,
};

/// Stateful merger: holds the hierarchy and a workspace that is reused across merges, so
/// repeated merges on one mesh allocate nothing once warm. One merge at a time per Merger
/// (not thread-safe); separate Mergers may run concurrently.
///
/// Order independence: the result depends only on the base and the set of diffs, bit for bit
/// (diffs are put in a canonical order by content before any arithmetic).
class Merger {
 public:
  /// `hierarchy` must outlive the Merger and describe the base mesh's connectivity.
  /// `threads`: the size of its worker pool, the calling thread included; 0 = the machine's
  /// hardware threads (at most 8). Results are the same bits for every count.
  explicit Merger(const Hierarchy& hierarchy, unsigned threads = 0);
  ~Merger();
  Merger(const Merger&) = delete;
  Merger& operator=(const Merger&) = delete;

  /// Merges `diffs` (each from `base`) into one diff from `base`. Vertices that no diff
  /// touches keep their exact base values; the merged diff lists only changed values.
  /// Throws InvalidInput if a diff does not fit the base, for more than max_merge_diffs diffs, or
  /// if the base's triangles are not the hierarchy's (a sampled check: count, ends, 1024 samples).
  /// The work runs on the worker pool owned by this Merger.
  Diff merge(const Mesh& base, std::span<const Diff> diffs, MergeMethod method,
             const MergeFrame& frame);
  /// The same, for diffs held elsewhere (no copy): each pointer must be non-null.
  Diff merge(const Mesh& base, std::span<const Diff* const> diffs, MergeMethod method,
             const MergeFrame& frame, SameChange same = SameChange::once);
  Diff merge(const Mesh& base, std::span<const Diff> diffs,
             MergeMethod method = MergeMethod::full) {
    return merge(base, diffs, method, MergeFrame::fit(base.positions));
  }

  const MergeTimings& last_timings() const { return timings_; }
  const Hierarchy& hierarchy() const { return hierarchy_; }

 private:
  struct Workspace;
  struct Pass;  ///< one merge's steps (merge.cpp)
  const Hierarchy& hierarchy_;
  std::unique_ptr<Workspace> workspace_;
  MergeTimings timings_;
};

/// One-shot convenience: builds the hierarchy (K = `max_parents`, 1 for single-parent),
/// captures each edit's diff, merges, and returns the merged mesh.
Mesh merge_meshes(const Mesh& base, std::span<const Mesh> edits,
                  MergeMethod method = MergeMethod::full, std::uint32_t max_parents = 7);

}  // namespace csculpt
