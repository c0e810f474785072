// The merger's role: the submits it holds for the next version (one per author, the latest
// sequence), and the merge that turns them into that version's record (merged diff as sent,
// hash chain, strokes, conflicts, attribution). Pure logic: no sockets, no threads.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/folds.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/wire.h"
#include "messages.h"

namespace csculpt::peer {

/// The session's wire options: the position tolerance is relative to the session's fixed
/// frame (the first mesh's bounding-box diagonal), not recomputed from each version's mesh.
EncodeOptions session_wire_options(const EncodeOptions& wire, const MergeFrame& frame);

/// An author's edit since the agreed version, as the merger holds it.
struct PendingSubmit {
  std::uint64_t sequence = 0;  ///< the author's numbering: a later one replaces an earlier
  std::uint32_t strokes = 0;   ///< strokes it carries (counted when merged)
  Diff diff;                   ///< decoded against the agreed version's mesh
};

/// Submits by author: the latest of each for one version.
using Submits = std::map<PeerId, PendingSubmit>;

/// A merge's result: the version to publish and what it cost.
struct MergeOutcome {
  VersionRecord record;
  Diff decoded;  ///< the record's diff as every peer decodes it (Replication::append)
  std::uint32_t merged_strokes = 0;
};

class MergerRole {
 public:
  /// Merges on `hierarchy` (the session mesh's connectivity).
  explicit MergerRole(std::shared_ptr<const Hierarchy> hierarchy);

  /// A submit by `author` of `diff_bytes` (a DiffMessage) at agreed version `version` with
  /// mesh `base`. False (ignored) when based on another version: the author rebases and sends
  /// again when it sees ours. Throws InvalidInput for a malformed diff or one whose values the
  /// session refuses from a host (host_values.h: non-finite, out of reach, out of range).
  bool accept(PeerId author, std::span<const std::uint8_t> diff_bytes, std::uint32_t strokes,
              const Mesh& base, std::uint64_t version, const MergeFrame& frame);
  bool empty() const { return pending_.empty(); }
  /// The held submits, which the role then forgets: the next merge's inputs, merged by merge()
  /// on the merge worker's thread while this role takes the next ones.
  Submits take_pending() { return std::exchange(pending_, {}); }
  /// Forgets what `author` sent (it left) or everything (the version moved on, the merger
  /// changed).
  void forget(PeerId author) { pending_.erase(author); }
  void clear() { pending_.clear(); }

  /// Merges `submits` (take_pending(), not empty) into the version after `version` (chain
  /// `chain`, mesh `base`). The record's diff is encoded with `wire`; its chain is that of the
  /// decoded diff, which every peer (this one too) applies. Touches only the merge's own state
  /// (not the held submits): accept(), forget() and clear() may run on another thread
  /// meanwhile.
  MergeOutcome merge(Submits submits, const Mesh& base, std::uint64_t version, std::uint64_t chain,
                     const MergeFrame& frame, const EncodeOptions& wire);

  /// The new folds (csculpt/folds.h) the last merge made on `base` (the mesh it merged on),
  /// counted once its version is on its way: a quality measure, not on an edit's path (2 ms
  /// of a large stroke's merge at 320K faces). Forgets that merge's inputs; 0 when there were
  /// fewer than two.
  std::uint32_t count_last_folds(const Mesh& base);
  /// Forgets the last merge's inputs uncounted (its version was never published).
  void forget_last() { last_inputs_.clear(); }

 private:
  std::shared_ptr<const Hierarchy> hierarchy_;  // kept alive for merger_ and folds_
  Merger merger_;
  FoldCounter folds_;  // the merge's quality count
  Submits pending_;    // author -> its latest submit for this version
  // the last merge's inputs and result, until count_last_folds
  Submits last_inputs_;
  Diff last_merged_;
};

}  // namespace csculpt::peer
