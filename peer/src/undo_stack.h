// The host side's per-artist undo inside a session: an artist undoes (and redoes) their own
// strokes while everyone else's merged work stays, even where others bent or twisted the
// region since.
//
// Undoing a stroke is a merge, the same 3-way merge the rebase uses: on the base S (the
// stroke's surroundings as they stood right after it), "mine" moves the stroke's vertices back
// to their values before it and "theirs" is everything that happened since (S to the host's
// mesh now). The merge carries the stroke's removal in the frame the later edits gave the
// surface (docs/merge-quality.md), so a bump undone under a colleague's twist goes away along
// the twisted surface instead of leaving a dent where it used to be. Subtracting the stroke's
// translation would not: it fails as soon as someone rotates the region.
//
// A record keeps only the stroke's vertices and their one-ring (every face incident to a
// stroke vertex, so the per-vertex rotations there are the real ones): S outside it is taken
// to be the mesh as it is now, which changes nothing the merge reads at the stroke.
// Redo is the same merge from the undone state. When nothing but the stroke's own wire
// rounding changed the surroundings, the values are written back exactly.
#pragma once

#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt::peer {

class UndoStack {
 public:
  /// `tolerance`: how far (per coordinate, mesh units) the surroundings may have moved with
  /// nobody editing them (the wire rounding of the submit) and still count as unchanged.
  void set_tolerance(float position_tolerance, float channel_tolerance);

  /// Records a stroke the host just ended on `local`: `vertices` it changed and their values
  /// before it (`before`: per vertex the position, then every channel's values in `local`'s
  /// channel order). Drops the strokes that could be redone and, past the depth or memory
  /// budget, the oldest. Throws InvalidInput on an index out of range or repeated, a size
  /// mismatch or a non-finite value.
  void record(const Mesh& local, const Topology& topology, std::span<const std::uint32_t> vertices,
              std::span<const float> before);

  /// Undoes the latest done stroke in `local` (merging as the header says); `changed` gets the
  /// vertices whose values changed. False when there is nothing to undo.
  bool undo(Mesh& local, Merger& merger, const MergeFrame& frame,
            std::vector<std::uint32_t>& changed);
  /// Redoes the latest undone stroke the same way.
  bool redo(Mesh& local, Merger& merger, const MergeFrame& frame,
            std::vector<std::uint32_t>& changed);

  std::size_t undo_depth() const { return done_; }
  std::size_t redo_depth() const { return records_.size() - done_; }
  void clear();

  static constexpr std::size_t kMaxStrokes = 100;
  static constexpr std::size_t kMaxBytes = std::size_t{256} << 20;

 private:
  struct Record {
    std::vector<std::uint32_t> vertices;  ///< the stroke's, increasing
    std::vector<std::uint32_t> in_ring;   ///< per stroke vertex, its index in `ring`
    std::vector<float> before;            ///< stride floats per stroke vertex
    std::vector<std::uint32_t> ring;      ///< the stroke's vertices and their one-ring
    std::vector<float> after;             ///< stride floats per ring vertex, right after it
    std::size_t bytes() const;
  };
  /// The ring's values in the state a step starts from: right after the stroke (undoing) or
  /// with the stroke's vertices back before it (redoing).
  static std::vector<float> start_state(const Record& r, bool undoing, std::size_t stride);
  void step(const Record& r, bool undoing, Mesh& local, Merger& merger, const MergeFrame& frame,
            std::vector<std::uint32_t>& changed) const;
  bool unchanged_since(const Record& r, std::span<const float> start, const Mesh& local) const;
  void trim();

  std::deque<Record> records_;
  std::size_t done_ = 0;  ///< records_[0 .. done_) are done; the rest can be redone
  std::size_t bytes_ = 0;
  float position_tolerance_ = 0, channel_tolerance_ = 0;
};

}  // namespace csculpt::peer
