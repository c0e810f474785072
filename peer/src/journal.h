// The on-disk journal of one peer (docs/journal.md): a directory with the session's identity
// (`session`), the agreed mesh at some version (`snapshot`) and an append-only `log` of what
// came after it: every agreed version as accepted, this peer's latest unmerged edit, the
// members' endpoints. Every record is framed with its length, type and a checksum, so a torn
// or corrupted tail is detected and dropped, never misread. The log is compacted into a new
// snapshot past a bound. No sockets, no threads: the network thread owns one.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "csculpt/peer/session.h"
#include "messages.h"

namespace csculpt::peer {

/// Who this peer is in which session: enough to come back as the same member.
struct JournalMeta {
  Invite invite;  ///< session id and CURVE secrets; endpoint: this peer's latest
  PeerId self = 0;
  std::string name;
};

/// This peer's latest unmerged edit: a DiffMessage from `base_version` (as submitted).
struct OwnEdit {
  std::uint64_t base_version = 0;
  std::uint32_t strokes = 0;  ///< strokes not yet acknowledged, this edit's included
  Bytes diff;
};

/// What a journal directory holds, as load_journal read it.
struct JournalState {
  JournalMeta meta;
  std::uint64_t version = 0;  ///< the snapshot's version and chain
  std::uint64_t chain = 0;
  Bytes snapshot;                       ///< encode_snapshot bytes
  std::vector<VersionRecord> versions;  ///< the versions after the snapshot, chained, in order
  std::optional<OwnEdit> own;           ///< the latest, if any came after the snapshot
  std::map<PeerId, std::string> members;
  std::uint64_t log_bytes = 0;      ///< of valid records (the log is cut there when reopened)
  std::uint64_t dropped_bytes = 0;  ///< a torn or corrupt tail after them
  std::string dropped_reason;       ///< why it was dropped ("" when nothing was)
};

/// Reads a journal directory. Throws IoError or InvalidInput naming the file for a missing
/// directory, a missing or corrupt `session` or `snapshot` file, or a log of another session.
/// A bad record in the log ends it there (dropped_bytes, dropped_reason).
JournalState load_journal(const std::string& dir);

/// Writes the snapshot of a compaction under way (Journal::begin_compaction), or a joiner's
/// first (Journal::adopt_snapshot), to `dir`, synced, under a name of its own (`snapshot.next`):
/// no append touches it, so it runs beside the network thread while that goes on appending.
/// One writer at a time. Throws IoError.
void write_compaction_snapshot(const std::string& dir, std::span<const std::uint8_t> snapshot,
                               std::uint64_t version, std::uint64_t chain);
/// Removes what write_compaction_snapshot wrote for a compaction given up (reset() came first).
void discard_compaction_snapshot(const std::string& dir);

struct JournalLimits {
  /// The log is compacted into a new snapshot past either bound.
  std::uint64_t max_log_bytes = std::uint64_t{64} << 20;
  std::uint64_t max_log_versions = 1024;
};

class Journal {
 public:
  /// A new journal in `dir` (created if missing): writes `session`. Throws IoError, and
  /// InvalidInput if `dir` already holds a journal with a snapshot (resume it instead).
  static Journal create(const std::string& dir, const JournalMeta& meta, JournalLimits limits);
  /// Appends to the journal `state` was loaded from: the log is cut after its valid records and
  /// `session` rewritten with `meta` (a new endpoint).
  static Journal reopen(const std::string& dir, const JournalState& state, const JournalMeta& meta,
                        JournalLimits limits);
  ~Journal();
  Journal(Journal&& other) noexcept;
  Journal& operator=(Journal&& other) noexcept;

  /// A new snapshot at `version` (the first, one received, or a compaction) and an empty log
  /// after it carrying the latest own edit and the members over. Both files are written to a
  /// temporary, synced and renamed.
  void reset(std::span<const std::uint8_t> snapshot, std::uint64_t version, std::uint64_t chain);
  /// Appends and syncs (fdatasync) before returning: an agreed version, this peer's own edit
  /// (superseding earlier ones), a member's endpoint (skipped when unchanged).
  void append_version(const VersionRecord& r);
  void append_own(const OwnEdit& own);
  void append_member(PeerId peer, const std::string& endpoint);
  /// Whether the log is past a bound and no compaction is under way (then begin_compaction,
  /// or reset() with a snapshot of the current version).
  bool wants_compaction() const;
  /// A compaction whose snapshot, of `version` (the last appended), is written beside the
  /// network thread by write_compaction_snapshot: at 320K faces a snapshot took ~370 ms to
  /// encode and sync, at millions of faces seconds, and a network thread that long silent is
  /// taken for gone. The log goes on as before meanwhile; the versions appended are also kept
  /// for the new log. reset() gives the compaction up.
  void begin_compaction(std::uint64_t version, std::uint64_t chain);
  /// The version of the compaction under way, if any.
  std::optional<std::uint64_t> compacting() const;
  /// Once write_compaction_snapshot returned: the new log (its head, the versions appended
  /// since, the own edit if based on the snapshot's version or one after it, the members)
  /// written and synced, then both renamed into place as reset() does.
  void finish_compaction();
  /// The snapshot write_compaction_snapshot wrote of `version` put into place at once, with a
  /// fresh log after it: a joiner's first snapshot, written as it arrived, off the network
  /// thread. Needs no compaction under way (its writer uses the same file).
  void adopt_snapshot(std::uint64_t version, std::uint64_t chain);
  const std::string& dir() const { return dir_; }
  /// Whether a snapshot was written (before it, there is nothing to resume).
  bool has_snapshot() const { return has_snapshot_; }
  std::uint64_t log_bytes() const { return log_bytes_; }

 private:
  Journal(std::string dir, JournalLimits limits);
  void append(std::uint32_t type, std::span<const std::uint8_t> payload);
  void open_log(std::uint64_t truncate_at);
  void install(const std::string& snapshot_path, std::uint64_t version, std::uint64_t chain,
               std::span<const Bytes> versions, std::uint64_t last_version);

  struct Compaction {
    std::uint64_t version = 0, chain = 0;
    std::vector<Bytes> versions;  ///< framed version records appended since
    std::uint64_t last_version = 0;
  };

  std::string dir_;
  JournalLimits limits_;
  int log_fd_ = -1;
  bool has_snapshot_ = false;
  std::uint64_t log_bytes_ = 0, log_versions_ = 0;
  std::optional<OwnEdit> own_;  // carried over into the log after a new snapshot
  std::map<PeerId, std::string> members_;
  std::optional<Compaction> compaction_;
};

}  // namespace csculpt::peer
