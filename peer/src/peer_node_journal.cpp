// The network thread's side of the journal (journal.h): what PeerNode writes on each event, and
// how it starts again from a journal. Each write is synced before the node goes on, so a
// version reaches the host (and counts as acknowledged) only once it is on disk. A
// compaction's snapshot is encoded and written beside the network thread.
#include <algorithm>
#include <chrono>
#include <optional>
#include <string>

#include "csculpt/error.h"
#include "peer_node.h"

namespace csculpt::peer {
namespace {

JournalLimits limits_of(const SessionOptions& o) {
  return {o.journal_max_log_bytes, o.journal_max_log_versions};
}

}  // namespace

/// Runs `write` on the journal, if there is one, timed into the statistics; a failure ends
/// journaling (an error event), never the session.
template <class Write>
void PeerNode::journal(Write&& write) {
  if (!journal_) return;
  const Clock::time_point start = Clock::now();
  try {
    write(*journal_);
  } catch (const std::exception& e) {
    journal_.reset();
    return event(EventKind::error, self_, std::string(e.what()) + "; journaling stopped");
  }
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  host_.update_stats([&](SessionStats& s) {
    ++s.journal_writes;
    s.journal_ms_sum += ms;
    s.journal_ms_max = std::max(s.journal_ms_max, ms);
  });
}

void PeerNode::create_journal() {
  if (options_.journal.empty()) return;
  Invite me = invite_;
  me.endpoint = transport_.endpoint();
  journal_.emplace(
      Journal::create(options_.journal, {me, self_, options_.name}, limits_of(options_)));
}

/// A snapshot of our version and a fresh log after it.
void PeerNode::snapshot_into(Journal& j) {
  // With the chains before it, so a resumed peer still finds where another branch forked.
  j.reset(host_.encode_snapshot_of(base_, replication_.recent_chains(kChainsSent)),
          replication_.version(), replication_.chain());
  host_.update_stats([](SessionStats& s) { ++s.journal_snapshots; });
}

void PeerNode::journal_snapshot() {
  journal([&](Journal& j) { snapshot_into(j); });
}

void PeerNode::adopt_journal_snapshot() {
  journal([&](Journal& j) {
    j.adopt_snapshot(replication_.version(), replication_.chain());
    host_.update_stats([](SessionStats& s) { ++s.journal_snapshots; });
  });
}

void PeerNode::journal_version(const VersionRecord& r) {
  journal([&](Journal& j) {
    j.append_version(r);
    // A compaction given up (reset) may still be writing: the next version tries again.
    if (j.wants_compaction() && !compaction_writer_.busy()) begin_compaction(j);
  });
}

void PeerNode::begin_compaction(Journal& j) {
  const std::uint64_t version = replication_.version(), chain = replication_.chain();
  j.begin_compaction(version, chain);
  compaction_writer_.start([&host = host_, &base = base_, copied = begin_base_copy(),
                            chains = replication_.recent_chains(kChainsSent), dir = j.dir(),
                            version, chain] {
    const Snapshot snap =
        copy_then_count_down(*copied, [&] { return host.snapshot_of(base, chains); });
    write_compaction_snapshot(dir, encode_snapshot(snap), version, chain);
    return version;
  });
}

void PeerNode::finish_compaction() {
  std::optional<std::uint64_t> written;
  try {
    written = compaction_writer_.take();
  } catch (const std::exception& e) {  // as any journal write that fails
    if (!journal_) return;
    journal_.reset();
    return event(EventKind::error, self_, std::string(e.what()) + "; journaling stopped");
  }
  if (!written) return;
  if (!journal_ || journal_->compacting() != written)
    return discard_compaction_snapshot(options_.journal);
  journal([&](Journal& j) {
    j.finish_compaction();
    host_.update_stats([](SessionStats& s) { ++s.journal_snapshots; });
  });
}

void PeerNode::journal_own() {
  journal([&](Journal& j) {
    j.append_own({own_submit_.base_version, own_submit_.strokes, own_submit_.bytes});
  });
}

void PeerNode::journal_member(PeerId peer, const std::string& endpoint) {
  journal([&](Journal& j) { j.append_member(peer, endpoint); });
}

void PeerNode::start_resumed(const Snapshot& snap, JournalState& state) {
  base_ = snap.mesh;
  frame_ = snap.frame;
  host_.set_frame_and_attribution(snap.frame, snap.attribution);
  build_merge_state();
  replication_.reset(state.version, state.chain, snap.chains);
  joined_ = true;
  event(EventKind::joined, self_);
  host_.set_joined();
  bool replayed_all = true;
  for (VersionRecord& r : state.versions) {
    try {
      apply_version(std::move(r));
    } catch (const InvalidInput& e) {  // a record that passed its checksum but not its chain
      event(EventKind::error, self_, std::string("journal: ") + e.what());
      replayed_all = false;
      break;
    }
  }
  Invite me = invite_;
  me.endpoint = transport_.endpoint();
  journal_.emplace(
      Journal::reopen(options_.journal, state, {me, self_, options_.name}, limits_of(options_)));
  if (!replayed_all) journal_snapshot();  // what the log holds past here is not ours
  const Clock::time_point now = Clock::now();
  for (const auto& [peer, endpoint] : state.members)
    if (peer != self_ && membership_.learnt(peer, endpoint, now)) member_joined(peer, endpoint);
  // The others may hold versions this peer never journaled: merging before hearing them would
  // fork the session (they expire after `expired` if they do not come back).
  resumed_merge_hold_ = now + 2 * options_.membership.expired;
}

}  // namespace csculpt::peer
