// The network thread's side of the journal (journal.h): what PeerNode writes on each event, and
// how it starts again from a journal. Each write is synced before the node goes on, so a
// version reaches the host (and counts as acknowledged) only once it is on disk.
#include <string>

#include "csculpt/error.h"
#include "peer_node.h"

namespace csculpt::peer {
namespace {

JournalLimits limits_of(const SessionOptions& o) {
  return {o.journal_max_log_bytes, o.journal_max_log_versions};
}

/// Runs `write` on the journal, if there is one; a failure ends journaling (`failed(why)`).
template <class Write, class Failed>
void with_journal(std::optional<Journal>& journal, Write&& write, Failed&& failed) {
  if (!journal) return;
  try {
    write(*journal);
  } catch (const std::exception& e) {
    journal.reset();
    failed(std::string(e.what()) + "; journaling stopped");
  }
}

}  // namespace

void PeerNode::create_journal() {
  if (options_.journal.empty()) return;
  Invite me = invite_;
  me.endpoint = transport_.endpoint();
  journal_.emplace(
      Journal::create(options_.journal, {me, self_, options_.name}, limits_of(options_)));
}

void PeerNode::journal_snapshot() {
  with_journal(
      journal_,
      [&](Journal& j) {
        j.reset(host_.encode_snapshot_of(base_), replication_.version(), replication_.chain());
      },
      [&](const std::string& why) { event(EventKind::error, self_, why); });
}

void PeerNode::journal_version(const VersionRecord& r) {
  with_journal(
      journal_,
      [&](Journal& j) {
        j.append_version(r);
        if (j.wants_compaction())
          j.reset(host_.encode_snapshot_of(base_), replication_.version(), replication_.chain());
      },
      [&](const std::string& why) { event(EventKind::error, self_, why); });
}

void PeerNode::journal_own() {
  with_journal(
      journal_,
      [&](Journal& j) {
        j.append_own({own_submit_.base_version, own_submit_.strokes, own_submit_.bytes});
      },
      [&](const std::string& why) { event(EventKind::error, self_, why); });
}

void PeerNode::journal_member(PeerId peer, const std::string& endpoint) {
  with_journal(
      journal_, [&](Journal& j) { j.append_member(peer, endpoint); },
      [&](const std::string& why) { event(EventKind::error, self_, why); });
}

void PeerNode::start_resumed(const Snapshot& snap, JournalState& state) {
  base_ = snap.mesh;
  frame_ = snap.frame;
  host_.set_frame_and_attribution(snap.frame, snap.attribution);
  build_merge_state();
  replication_.reset(state.version, state.chain);
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
