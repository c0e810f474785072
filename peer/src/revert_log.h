// What a host needs to step its agreed mesh back to an earlier version: the values each applied
// version overwrote. When a network partition heals, the branch this peer followed loses to
// another (replication.h); the versions it had since the fork are then carried over to the
// surviving branch as edits from the fork point instead of being dropped (Session's snapshot
// rebase). Pure logic.
#pragma once

#include <cstdint>
#include <deque>

#include "csculpt/diff.h"
#include "csculpt/mesh.h"

namespace csculpt::peer {

/// The latest versions' overwritten values kept, in bytes: far more than a five-minute
/// partition of a busy session needs (a few MiB at 20K faces).
constexpr std::size_t kRevertLogBytes = std::size_t{256} << 20;

class RevertLog {
 public:
  explicit RevertLog(std::size_t max_bytes = kRevertLogBytes) : max_bytes_(max_bytes) {}

  /// `merged`, the diff of `version`, is about to be applied to `base` (the mesh of
  /// version - 1): keeps the values it overwrites. A version that does not follow the latest
  /// one kept starts the log again.
  void record(std::uint64_t version, const Diff& merged, const Mesh& base);

  /// The base, stepped back to `from` (the mesh of `from_version`, where revert() reached),
  /// became `to`, a snapshot of `version`: one step from `version` back to `from_version`,
  /// so that a later fork before the snapshot can still be stepped back to. The versions kept
  /// after `from_version` were the branch that lost, and go.
  void jumped(std::uint64_t from_version, const Mesh& from, std::uint64_t version, const Mesh& to);

  /// Steps `mesh`, the mesh of `version`, back to `target` <= version (the values of the
  /// versions after it undone, newest first). Returns the version reached: `target`; earlier,
  /// when a snapshot's step spans `target` (a state both branches held, so nothing is lost by
  /// carrying more); later, where the log stops when it does not reach that far (`version`
  /// itself when it does not end there).
  std::uint64_t revert(Mesh& mesh, std::uint64_t version, std::uint64_t target) const;

  void clear();
  bool empty() const { return entries_.empty(); }

 private:
  /// A step back: from `version` to `previous` (version - 1, or a snapshot's fork base), the
  /// values to write.
  struct Entry {
    std::uint64_t version;
    std::uint64_t previous;
    Diff old;
  };
  void push(Entry e);

  std::size_t max_bytes_;
  std::deque<Entry> entries_;
  std::size_t bytes_ = 0;
};

}  // namespace csculpt::peer
