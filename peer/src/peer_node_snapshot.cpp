// Serving snapshots: a joiner's first mesh, a diverged peer's way back, a peer too far behind
// to fetch. Encoding one copies and serialises the whole mesh, which grows with it (about 20 ms
// per million faces in release, 250-400 ms at 2M under TSan: the serving test prints it in
// tests/peer/test_session.cpp), and so do its chunks: on the network thread they silenced our
// heartbeats, and the members took the server for gone. So a task copies base_ and encodes it
// beside the network thread, and everyone who asked meanwhile gets that one snapshot. It may
// be of a version before ours by then; they fetch onward from it, as after any snapshot. Its
// chunks go out a turn at a time (kTurn) between the loop's other work.
#include <algorithm>
#include <exception>
#include <memory>
#include <string>
#include <utility>

#include "peer_node.h"

namespace csculpt::peer {

void PeerNode::send_snapshot(PeerId peer) {
  if (!joined_) return;
  if (served_.bytes && served_.version == replication_.version() &&
      served_.chain == replication_.chain())
    return queue_snapshot(peer, served_);
  if (std::find(snapshot_waiters_.begin(), snapshot_waiters_.end(), peer) ==
      snapshot_waiters_.end())
    snapshot_waiters_.push_back(peer);
  if (!snapshot_encoder_.busy()) begin_snapshot_encoding();
}

void PeerNode::begin_snapshot_encoding() {
  snapshot_encoder_.start([&host = host_, &base = base_, copied = begin_base_copy(),
                           chains = replication_.recent_chains(kChainsSent),
                           version = replication_.version(), chain = replication_.chain()] {
    const Snapshot snap =
        copy_then_count_down(*copied, [&] { return host.snapshot_of(base, chains); });
    return EncodedSnapshot{version, chain, std::make_shared<const Bytes>(encode_snapshot(snap))};
  });
}

void PeerNode::finish_snapshot_encoding() {
  std::optional<EncodedSnapshot> encoded;
  try {
    encoded = snapshot_encoder_.take();
  } catch (const std::exception& e) {  // the waiters ask again (request_snapshot's retry)
    snapshot_waiters_.clear();
    return event(EventKind::error, self_, std::string("encoding a snapshot: ") + e.what());
  }
  if (!encoded) return;
  // A snapshot of a branch we left since (we took another peer's snapshot) is no longer one
  // anybody can fetch onward from here: encoded again, of what we hold now.
  if (replication_.chain_at(encoded->version) != encoded->chain) {
    if (!snapshot_waiters_.empty()) begin_snapshot_encoding();
    return;
  }
  served_ = std::move(*encoded);
  for (PeerId peer : std::exchange(snapshot_waiters_, {})) queue_snapshot(peer, served_);
}

void PeerNode::queue_snapshot(PeerId peer, const EncodedSnapshot& e) {
  // A second one would interleave its chunks with the first's, and the receiver assembles one
  // at a time; it asks again if the first does not complete.
  for (const OutgoingSnapshot& o : outgoing_snapshots_)
    if (o.peer == peer) return;
  const auto& m = membership_.members();
  if (auto it = m.find(peer); it != m.end() && !it->second.endpoint.empty())
    outgoing_snapshots_.push_back({peer, it->second.endpoint, e, 0});
}

void PeerNode::send_snapshot_chunks() {
  const Clock::time_point end = Clock::now() + kTurn;
  const std::size_t chunk = std::max<std::size_t>(1024, options_.snapshot_chunk_bytes);
  while (!outgoing_snapshots_.empty() && Clock::now() < end) {
    OutgoingSnapshot& o = outgoing_snapshots_.front();
    const Bytes& bytes = *o.snapshot.bytes;
    const std::size_t n = std::min(chunk, bytes.size() - o.offset);
    transport_.send(o.endpoint,
                    snapshot_chunk_message(header(), o.snapshot.version, o.snapshot.chain, o.offset,
                                           bytes.size(), {bytes.data() + o.offset, n}));
    o.offset += n;
    if (o.offset < bytes.size()) continue;
    outgoing_snapshots_.pop_front();
    host_.update_stats([](SessionStats& s) { ++s.snapshots_sent; });
  }
}

void PeerNode::drop_outgoing_snapshot(PeerId peer) {
  std::erase_if(outgoing_snapshots_, [&](const OutgoingSnapshot& o) { return o.peer == peer; });
}

std::shared_ptr<std::latch> PeerNode::begin_base_copy() {
  base_copies_.push_back(std::make_shared<std::latch>(1));
  return base_copies_.back();
}

void PeerNode::release_base() {
  drop_merge();
  for (const std::shared_ptr<std::latch>& copied : base_copies_) copied->wait();
  base_copies_.clear();
  served_ = {};  // of the mesh about to change: nobody asks for it again
}

}  // namespace csculpt::peer
