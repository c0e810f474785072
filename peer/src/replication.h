// Replication: the agreed version and its hash chain, the versions kept to answer fetches, and
// the ones that arrived ahead of a gap. Every peer (the merger too) advances only by accept(),
// which checks that a version follows the one held: its diff is based on it and its chain is
// hash_mix(our chain, digest(its decoded diff)). Pure logic: no sockets, no threads.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/mesh.h"
#include "messages.h"
#include "snapshot.h"

namespace csculpt::peer {

/// At most this many versions are buffered ahead of a gap.
constexpr std::size_t kHistory = 256;
/// Versions kept to answer fetches: the latest, up to this many bytes of diffs (a peer behind by
/// more gets a snapshot).
constexpr std::size_t kHistoryBytes = std::size_t{128} << 20;
/// The chains of this many versions are kept (8 bytes each): enough to find where two branches
/// forked after hours of partition.
constexpr std::size_t kChainsKept = std::size_t{1} << 20;
/// The chains a snapshot carries, so that its receiver finds the fork point (snapshot.h).
constexpr std::size_t kChainsSent = std::size_t{1} << 14;
/// The chain of a session's version 0.
constexpr std::uint64_t kGenesisChain = 0x243f6a8885a308d3ull;

/// The chain of the version whose (decoded) merged diff is `merged`, after `parent`.
std::uint64_t next_chain(std::uint64_t parent, const Diff& merged);

class Replication {
 public:
  std::uint64_t version() const { return version_; }
  std::uint64_t chain() const { return chain_; }

  /// Holds `version` with `chain` and nothing else (the session's start, or a snapshot: the
  /// versions kept before are another branch's, not ours to serve). `known`: the chains
  /// before it (a snapshot's), kept when they end at `version` with `chain`.
  void reset(std::uint64_t version, std::uint64_t chain, const ChainHistory& known = {});

  /// What a received version is to us.
  enum class Arrival {
    held,          ///< we hold it (or a later one) already
    next,          ///< it follows ours: accept() it
    gap,           ///< versions are missing in between: buffer() it and fetch
    other_branch,  ///< it follows a version we do not hold: we need a snapshot
  };
  Arrival classify(std::uint64_t version, std::uint64_t parent_chain) const;

  /// Keeps a version that arrived early (ahead of a gap, or before the snapshot while
  /// joining); at most kHistory are kept, a later copy of the same version replaces it.
  void buffer(VersionRecord r);
  /// The buffered version that follows ours now, if any (buffered ones we passed are dropped).
  std::optional<VersionRecord> take_next_buffered();

  /// Advances by `r`, which must follow ours: decodes its diff against `base` (the mesh of our
  /// version), checks its base version and hash chain, applies it to `base`, and keeps `r` to
  /// answer fetches. Returns the decoded diff. Throws InvalidInput, leaving everything as it
  /// was, for a version that does not follow ours or fails its chain.
  Diff accept(VersionRecord r, Mesh& base);
  /// accept()'s checks alone, changing nothing: `r`'s decoded diff, or InvalidInput.
  Diff check(const VersionRecord& r, const Mesh& base) const;
  /// The same for a version this peer merged, whose decoded diff (`merged`, the merger's
  /// encode gave it) and chain it made itself: nothing to decode or check again.
  void append(VersionRecord r, const Diff& merged, Mesh& base);
  /// The version accept() last kept.
  const VersionRecord& latest() const { return history_.back(); }

  /// Our chain at `version`, if we still hold it.
  std::optional<std::uint64_t> chain_at(std::uint64_t version) const;
  /// Our chains of the last `count` versions (ours included).
  ChainHistory recent_chains(std::size_t count) const;
  /// The latest version at which `theirs` and ours have the same chain: where two branches
  /// forked (ours, if theirs holds it). Nullopt when the two lists share no such version.
  std::optional<std::uint64_t> fork_point(const ChainHistory& theirs) const;
  /// Whether someone's `chain` at `version` is not ours there (unknown versions do not count).
  bool diverges(std::uint64_t version, std::uint64_t chain) const;
  /// The kept versions after `after`, oldest first, to answer a fetch; nullopt when some of
  /// them are no longer kept (the fetcher needs a snapshot).
  std::optional<std::vector<const VersionRecord*>> since(std::uint64_t after) const;

 private:
  std::uint64_t version_ = 0;
  std::uint64_t chain_ = 0;
  std::deque<VersionRecord> history_;  // the latest accepted, kHistoryBytes
  std::size_t history_bytes_ = 0;      // of history_'s diffs
  std::deque<std::uint64_t> chains_;   // at chains_first_, ..., version_
  std::uint64_t chains_first_ = 0;
  std::map<std::uint64_t, VersionRecord> buffered_;  // version -> arrived ahead of its turn
};

}  // namespace csculpt::peer
