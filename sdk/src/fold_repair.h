// Internal: the last step of `full`'s position merge — no fold-overs the artists did not make.
//
// Carrying every displacement in the other edits' frames keeps details on bends and twists,
// but where two strong edits overlap (a grab dragged over another artist's bump, a bend closed
// on a detail) the combination can turn faces inside out although no artist's own edit did: a
// visible crease or spike (folds.h has the definition every count uses). Such a face is
// repaired where it appears. Where a coarse edit carried a detail that folds (its own crumpling
// ridden a little further), each folded face is first nudged open by the least move of its
// vertices. Then around its vertices the merged positions are drawn back toward the
// frames' own reading where the hedge toward the stacked reading moved them, then toward plain
// addition of the edits there (the frames that carried one edit into another undone). What
// still folds is ended two ways from the same start, and the repair keeps the one that leaves
// fewer folds, then moves the merge less: smoothing the displacement field first, or drawing
// the region toward the shape the edit moving it most gives it (placed where the merge put it)
// first, each followed by the other; whatever is left is smoothed over a region that widens
// until it ends. Each acts fully at the fold and less with each ring of neighbours, more strongly
// on each attempt and over the neighbours of any face still folded; each phase ends at its best
// attempt (its start, if none did better). It is local (rings around the faces), leaves every
// vertex away from them bit-identical, and runs in the canonical order of the merge (so peers
// agree bitwise). Where nothing folds it costs one face test around each moved vertex and
// allocates nothing.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"
#include "csculpt/vec3.h"
#include "worker_pool.h"

namespace csculpt::detail {

/// In repair_new_folds' `sole`: a vertex whose merged position is no one diff's edit.
constexpr std::uint8_t kNoSoleEdit = 0xff;

/// Scratch reused across merges (no allocation once warm). Indices are into the moved list.
struct FoldRepairScratch {
  std::vector<std::uint32_t> slot;   ///< per vertex: index in the moved list; kNone between calls
  std::vector<std::uint32_t> folds;  ///< faces currently folded anew
  /// The repair's state at one moment: every moved vertex's position, the folds left, the seeds.
  struct Snapshot {
    std::vector<Vec3f> positions;
    std::vector<std::uint32_t> folds;
    std::vector<std::uint8_t> seed;
  };
  Snapshot best;                                        ///< at the phase's best attempt
  Snapshot pulled;                                      ///< where the pulls left it
  Snapshot tail;                                        ///< where smoothing first ended
  std::vector<std::vector<std::uint32_t>> chunk_folds;  ///< the first search's, per chunk
  std::vector<std::uint8_t> seed;       ///< per moved vertex: on a folded face in some attempt
  std::vector<std::uint32_t> ring;      ///< per moved vertex: rings from the nearest seed, or kNone
  std::vector<std::uint32_t> part;      ///< per moved vertex in the region: its connected part
  std::vector<std::uint32_t> dominant;  ///< per part: the diff moving it most
  std::vector<std::uint8_t> keeps;      ///< per part: that diff is kept by the relax phase
  std::vector<double> energy;           ///< per diff: squared displacement over one part
  std::vector<Vec3d> offset;            ///< per part: the merge's mean displacement from the
                                        ///< dominant diff at its seeds (the dominant remedy)
  std::vector<std::uint32_t> count;     ///< per part: its seeds
  std::vector<std::uint32_t> region, frontier, next;
  std::vector<Vec3f> start;      ///< per moved vertex: its position when the current phase began
  std::vector<Vec3f> merged;     ///< per moved vertex: where the transport put it
  std::vector<double> strength;  ///< per moved vertex: its own pull at full fade (a face pull)
  std::vector<double> pull;      ///< per moved vertex: the pull it takes, faded from the seeds
  std::vector<double> reached, grown;  ///< per moved vertex: the spread of strengths, per ring
  std::vector<Vec3d> relaxed;          ///< per region vertex: its smoothed displacement in a sweep
  std::vector<std::uint32_t> seam_first;    ///< per seam group: where its members start in
  std::vector<std::uint32_t> seam_members;  ///< ... this list of moved vertices, by group
  std::vector<std::uint8_t> seam_closed;    ///< per seam group: all members at one position
};

/// Repairs the new folds of the positions `moved` (one per vertex of `vertices`, increasing;
/// every other vertex at its base position) in place. `diffs` are the merge's inputs.
/// `seam_of` (empty, or one per vertex of the list) numbers the groups of vertices at one base
/// position (split seams; kNone when alone): a group the merge left closed stays closed. Returns
/// the number of new folds found before the repair. The search for them runs over `pool` in
/// chunks of `grain`; the repair itself, rare and local, on the calling thread. `carrying`
/// (empty, or diffs x diffs: how much diff i's frame carried diff j, the transport's w_ij)
/// lets the smoothing keep a coarse edit that carried the details folding on it. `sole` (empty,
/// or one per vertex of the list): the diff whose edited position `moved` holds exactly, or
/// kNoSoleEdit; the first search skips the faces whose vertices all hold one diff's edit or the
/// base, which are that diff's faces (most of a merge where few edits overlap). `framed`
/// (empty, or one per vertex of the list): the positions the frames alone gave, before the
/// hedge (frame_transport.h); the first phase pulls back toward them.
std::uint32_t repair_new_folds(const Topology& topology, std::span<const Vec3f> base,
                               std::span<const std::uint32_t> vertices,
                               std::span<const Diff* const> diffs,
                               std::span<const std::uint32_t> seam_of, std::span<Vec3f> moved,
                               FoldRepairScratch& scratch, WorkerPool& pool, std::size_t grain,
                               std::span<const double> carrying = {},
                               std::span<const std::uint8_t> sole = {},
                               std::span<const Vec3f> framed = {});

}  // namespace csculpt::detail
