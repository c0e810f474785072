#include "peer_node.h"

#include <algorithm>
#include <chrono>
#include <optional>
#include <utility>

#include "attribution.h"
#include "csculpt/error.h"
#include "invite.h"

namespace csculpt::peer {
namespace {

/// The hierarchy of `mesh`'s connectivity: what every peer builds for itself.
std::shared_ptr<const Hierarchy> hierarchy_of(const Mesh& mesh) {
  return std::make_shared<const Hierarchy>(
      Hierarchy::build(static_cast<std::uint32_t>(mesh.vertex_count()), mesh.triangles));
}

}  // namespace

PeerNode::PeerNode(const Invite& invite, bool creator, const SessionOptions& options)
    : options_(options),
      invite_(invite),
      self_(options.id ? options.id : random_u64() | 1),
      transport_(invite, self_, options.bind, options.max_message_bytes),
      membership_(self_, transport_.endpoint(), options.membership),
      election_(self_) {
  if (creator) invite_.endpoint = transport_.endpoint();
}

PeerNode::~PeerNode() {
  stop();
}

void PeerNode::start_as_creator(const Mesh& mesh) {
  base_ = mesh;
  frame_ = MergeFrame::fit(base_.positions);
  host_.set_frame(frame_);
  build_merge_state();
  replication_.reset(0, kGenesisChain);
  joined_ = true;
  create_journal();
  journal_snapshot();
  event(EventKind::joined, self_);
}

void PeerNode::start_as_joiner() {
  create_journal();
  transport_.connect(invite_.endpoint);
  joining_endpoint_ = invite_.endpoint;
}

void PeerNode::run() {
  thread_ = std::thread([this] { loop(); });
}

void PeerNode::stop() {
  if (!stopped_) {
    stopped_ = true;
    Command leave;
    leave.kind = Command::Kind::leave;
    command(std::move(leave));
  }
  if (thread_.joinable()) thread_.join();
}

void PeerNode::command(Command c) {
  host_.post(std::move(c));
  transport_.wake();
}

void PeerNode::presence(const Presence& p) {
  if (host_.set_presence(p)) transport_.wake();
}

std::string PeerNode::invite_text() const {
  Invite inv = invite_;
  inv.endpoint = transport_.endpoint();
  return format_invite(inv);
}

// ---- the loop ---------------------------------------------------------------------------------

void PeerNode::loop() {
  next_heartbeat_ = Clock::now();
  last_merge_ = Clock::now();  // the first merge one interval after the start, at the earliest
  while (true) {
    try {
      transport_.wait(next_deadline() - Clock::now());
      receive_all();
      finish_merge();
      finish_load();
      finish_compaction();
      finish_snapshot_encoding();
      send_snapshot_chunks();
      if (!run_commands()) break;
      run_timers(Clock::now());
      publish_stats();
    } catch (const std::exception& e) {
      // Nothing here may end the thread: the host learns of it and the loop goes on.
      event(EventKind::error, self_, e.what());
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  if (joined_) broadcast(leave_message(header()));
}

/// The earliest timer: the heartbeat, our presence, and, while we are the merger and hold
/// submits, the next merge.
Clock::time_point PeerNode::next_deadline() const {
  if (!outgoing_snapshots_.empty()) return Clock::now();  // chunks to send: no waiting
  const auto [changed, any] = host_.presence_state();
  // Before the mesh came there is nobody to show a cursor to (and the timer would be past).
  const Clock::time_point t =
      joined_ ? std::min(next_heartbeat_, presence_.next_send(changed, any)) : next_heartbeat_;
  return merge_waiting() ? std::min(t, last_merge_ + options_.sync) : t;
}

bool PeerNode::merge_waiting() const {
  return election_.is_merger() && merger_ && !merger_->empty();
}

void PeerNode::receive_all() {
  const Clock::time_point end = Clock::now() + kTurn;
  for (int i = 0; i < 1000 && Clock::now() < end; ++i) {  // then the timers get a turn
    Inbound message;
    if (!transport_.receive(message)) return;
    // Stamped when handled, not when the wait returned: a message handled after a long step (a
    // snapshot's hierarchy build, a large merge) is recent, not stale.
    handle(message, Clock::now());
  }
}

/// The host's commands, in order; false once it asked to leave.
bool PeerNode::run_commands() {
  for (Command& c : host_.take_commands()) {
    if (c.kind == Command::Kind::leave) return false;
    own_submit_ = std::move(c);
    journal_own();
    send_own_submit();
  }
  return true;
}

void PeerNode::run_timers(Clock::time_point now) {
  if (now >= next_heartbeat_) {
    next_heartbeat_ = now + options_.membership.heartbeat;
    heartbeat(now);
  }
  // Merges as soon as a submit is in, at most once per sync interval: an edit waits for no
  // tick, and a burst of submits arriving during one interval is merged together. Attempted
  // merges count (a merger catching up tries again one interval later, not in a busy loop).
  if (merge_waiting() && now >= last_merge_ + options_.sync) {
    last_merge_ = now;
    merge_pending();
  }
  send_presence(now);
}

void PeerNode::publish_stats() {
  const std::uint64_t rejected = transport_.take_auth_rejected();
  const std::uint64_t abandoned = transport_.take_handshakes_abandoned();
  host_.update_stats([&](SessionStats& s) {
    s.id = self_;
    s.version = replication_.version();
    s.epoch = election_.epoch();
    s.merger = election_.merger().value_or(0);
    s.members = static_cast<std::uint32_t>(membership_.members().size());
    s.auth_rejected += rejected;
    s.handshakes_abandoned += abandoned;
  });
  publish_peers();
}

void PeerNode::publish_peers() {
  host_.set_peers(peer_table_.list(membership_, election_.merger(), reported_));
}

// ---- inbound ----------------------------------------------------------------------------------

void PeerNode::handle(const Inbound& message, Clock::time_point now) {
  host_.update_stats([&](SessionStats& s) {
    ++s.messages_received;
    s.bytes_received += message.payload.size();
  });
  const Opened opened = open_envelope(
      {static_cast<const std::uint8_t*>(message.payload.data()), message.payload.size()},
      {static_cast<const std::uint8_t*>(message.routing.data()), message.routing.size()},
      invite_.session, self_, inbound_);
  if (!opened.envelope) return dropped(opened.error);
  try {
    dispatch(*opened.envelope, now);
  } catch (const InvalidInput& e) {
    dropped(e.what());
  } catch (const IoError& e) {  // e.g. an endpoint ZeroMQ refuses to connect to
    dropped(e.what());
  }
  report_revived();
}

void PeerNode::dispatch(const fb::Envelope& env, Clock::time_point now) {
  const PeerId sender = env.sender();
  switch (env.body_type()) {
    case fb::Body::Hello:
      return on_hello(env, *env.body_as_Hello(), now);
    case fb::Body::Heartbeat:
      return on_heartbeat(env, *env.body_as_Heartbeat(), now);
    case fb::Body::Leave:
      return on_leave(sender);
    case fb::Body::Elected:
      heard(sender, now);
      return on_elected(env, env.body_as_Elected()->merger());
    case fb::Body::Submit:
      heard(sender, now);
      return on_submit(sender, *env.body_as_Submit());
    case fb::Body::Version:
      heard(sender, now);
      return on_version(env, *env.body_as_Version());
    case fb::Body::Fetch:
      heard(sender, now);
      return on_fetch(sender, env.body_as_Fetch()->after());
    case fb::Body::SnapshotRequest:
      heard(sender, now);
      return send_snapshot(sender);
    case fb::Body::SnapshotChunk:
      return on_snapshot_chunk(*env.body_as_SnapshotChunk());
    case fb::Body::Presence:
      heard(sender, now);
      return on_presence(sender, *env.body_as_Presence(), now);
    default:
      return dropped("message of unknown kind " +
                     std::to_string(static_cast<int>(env.body_type())));
  }
}

/// Any verified message is a sign of life from a member; a sender we do not know yet is added
/// by its hello (which carries its endpoint), not here.
void PeerNode::heard(PeerId peer, Clock::time_point now) {
  if (membership_.contains(peer)) membership_.heard(peer, "", now);
}

void PeerNode::on_hello(const fb::Envelope& env, const fb::Hello& hello, Clock::time_point now) {
  if (hello.protocol() != kProtocol)
    return dropped("hello with protocol " + std::to_string(hello.protocol()));
  if (!hello.endpoint() || hello.endpoint()->size() == 0 ||
      hello.endpoint()->size() > kMaxEndpointBytes)
    return dropped("hello without a usable endpoint");
  const PeerId peer = env.sender();
  const std::string endpoint = hello.endpoint()->str();
  if (hello.name() && hello.name()->size() <= max_author_bytes)
    peer_table_.named(peer, hello.name()->str());
  if (membership_.heard(peer, endpoint, now))
    member_joined(peer, endpoint);
  else
    transport_.connect(endpoint);
  if (hello.wants_snapshot()) {
    if (!joined_) return;  // cannot serve yet; the joiner retries with another member
    send_heartbeat_to(endpoint);
    send_snapshot(peer);
  }
}

void PeerNode::on_heartbeat(const fb::Envelope& env, const fb::Heartbeat& hb,
                            Clock::time_point now) {
  const PeerId sender = env.sender();
  if (!membership_.contains(sender)) {
    // Heard before its hello arrived: its own entry in the list carries its endpoint.
    if (const auto* members = hb.members())
      for (const fb::Member* m : *members)
        if (m->peer() == sender && m->endpoint() && m->endpoint()->size() <= kMaxEndpointBytes)
          if (membership_.heard(sender, m->endpoint()->str(), now))
            member_joined(sender, m->endpoint()->str());
    if (!membership_.contains(sender)) return;
  }
  membership_.heard(sender, "", now);
  heard_timing(sender, hb, now);
  learn_members(hb, now);
  reported_[sender] = {hb.version(), hb.chain()};
  if (hb.merger() != 0) on_elected(env, hb.merger());
  if (!joined_) return;
  if (election_.merger() == sender) resend_own_submit_if_caught_up(hb.version(), hb.chain());
  // Behind someone: fetch what we missed (at most once per heartbeat interval).
  if (hb.version() > replication_.version() && now >= next_fetch_) {
    next_fetch_ = now + options_.membership.heartbeat;
    send_to_peer(sender, fetch_message(header(), replication_.version()));
    host_.update_stats([](SessionStats& s) { ++s.fetches; });
  }
  // Another history than the merger's at a version we hold: we hold a lost merger's version.
  if (election_.merger() == sender && hb.version() <= replication_.version())
    check_divergence(sender, hb.version(), hb.chain(), now);
}

/// Round trips: we echo the sender's clock in our next heartbeat, and its echo of ours (if
/// any) is a sample of the round trip to it.
void PeerNode::heard_timing(PeerId sender, const fb::Heartbeat& hb, Clock::time_point now) {
  if (hb.sent_us() != 0) peer_table_.heartbeat_from(sender, hb.sent_us(), now);
  if (const auto* echoes = hb.echoes())
    for (const fb::Echo* e : *echoes)
      if (e->peer() == self_) peer_table_.echoed(sender, *e, now);
}

/// Gossip: the members a heartbeat lists, added as if heard now (they expire if unreachable).
void PeerNode::learn_members(const fb::Heartbeat& hb, Clock::time_point now) {
  const auto* members = hb.members();
  if (!members) return;
  for (const fb::Member* m : *members) {
    if (!m->endpoint() || m->endpoint()->size() > kMaxEndpointBytes) continue;
    if (membership_.learnt(m->peer(), m->endpoint()->str(), now))
      member_joined(m->peer(), m->endpoint()->str());
  }
}

void PeerNode::on_leave(PeerId peer) {
  if (!membership_.contains(peer)) return;
  membership_.remove(peer, Clock::now());  // its socket closes later, with those of expired peers
  departed(peer, "left");
  elect();
}

void PeerNode::on_elected(const fb::Envelope& env, PeerId merger) {
  const Election::Outcome o = election_.on_announcement(env.epoch(), merger, membership_);
  if (o.followed) merger_changed();
  if (o.reassert) broadcast(elected_message(header(), self_));
}

void PeerNode::on_submit(PeerId sender, const fb::Submit& submit) {
  auto stale = [&] { host_.update_stats([](SessionStats& s) { ++s.stale_ignored; }); };
  if (!election_.is_merger() || !joined_ || !merger_) return stale();
  if (!submit.diff()) return dropped("submit without a diff");
  // Based on an older version: the author rebases and sends again when it sees ours.
  if (!merger_->accept(sender, {submit.diff()->data(), submit.diff()->size()}, submit.strokes(),
                       base_, replication_.version(), frame_))
    stale();
}

void PeerNode::on_version(const fb::Envelope& env, const fb::Version& v) {
  if (!v.diff()) return dropped("version without a diff");
  if (!joined_) return replication_.buffer(record_of(v));
  if (!v.replay() && !is_current_merger_version(env)) {
    host_.update_stats([](SessionStats& s) { ++s.stale_ignored; });
    return;
  }
  switch (replication_.classify(v.version(), v.parent_chain())) {
    case Replication::Arrival::held:  // already have it, unless our history differs
      if (election_.merger() == env.sender())
        check_divergence(env.sender(), v.version(), v.chain(), Clock::now());
      return;
    case Replication::Arrival::gap:
      replication_.buffer(record_of(v));
      send_to_peer(env.sender(), fetch_message(header(), replication_.version()));
      return;
    case Replication::Arrival::other_branch:
      // Built on a version we do not hold: we are on a lost merger's branch.
      return request_snapshot(env.sender());
    case Replication::Arrival::next:
      apply_version(record_of(v));
      return drain_buffered();
  }
}

/// A version that is not a replay counts only from the merger of the current epoch (a newer
/// epoch's sender is followed first, if the election agrees).
bool PeerNode::is_current_merger_version(const fb::Envelope& env) {
  if (election_.is_stale(env.epoch())) return false;
  if (env.epoch() > election_.epoch()) on_elected(env, env.sender());
  return election_.merger() == env.sender();
}

void PeerNode::on_fetch(PeerId peer, std::uint64_t after) {
  if (!joined_) return;
  const auto kept = replication_.since(after);
  if (!kept) {
    if (after < replication_.version()) send_snapshot(peer);
    return;
  }
  for (const VersionRecord* r : *kept) send_to_peer(peer, version_message(header(), *r, true));
}

void PeerNode::on_presence(PeerId sender, const fb::Presence& p, Clock::time_point now) {
  if (!membership_.contains(sender)) return;  // a stranger's cursor is nobody's to draw
  const Presence presence = presence_of(p);   // InvalidInput (NaN, no position): dropped
  host_.update_presence([&](PresenceTable& t) { t.accept(sender, p.sequence(), presence, now); });
}

void PeerNode::on_snapshot_chunk(const fb::SnapshotChunk& c) {
  if (!c.data()) return dropped("snapshot chunk without data");
  if (snapshot_loader_.busy()) return;  // ours came: another is one asked for twice
  if (c.total() > options_.max_snapshot_bytes)
    return dropped("snapshot of " + std::to_string(c.total()) + " bytes exceeds the limit");
  // A snapshot older than our version is only wanted when we asked for it (divergence).
  if (joined_ && c.version() < replication_.version() && !snapshot_requested_) return;
  const bool complete = snapshot_.add(c.version(), c.chain(), c.offset(), c.total(),
                                      {c.data()->data(), c.data()->size()});
  // Only chunks of the snapshot under way say it is still coming: chunks of another one, which
  // it ignores, must not keep a stalled one from being given up (request_snapshot, heartbeat).
  if (snapshot_.version() == c.version()) last_snapshot_chunk_ = Clock::now();
  if (!complete) return;
  if (!hierarchy_) {
    // The joiner's first mesh: decoded, its hierarchy built and its journal snapshot written,
    // off the network thread (a mesh of millions of faces takes seconds), while our heartbeats
    // go on.
    snapshot_loader_.start([bytes = snapshot_.take(), version = snapshot_.version(),
                            chain = snapshot_.chain(),
                            dir = journal_ ? journal_->dir() : std::string()] {
      LoadedSnapshot loaded{
          std::make_shared<const Snapshot>(decode_snapshot(bytes)), {}, false, {}};
      loaded.hierarchy = hierarchy_of(loaded.snap->mesh);
      if (dir.empty()) return loaded;
      try {
        write_compaction_snapshot(dir, bytes, version, chain);
        loaded.journaled = true;
      } catch (const std::exception& e) {
        loaded.journal_error = e.what();
      }
      return loaded;
    });
    return;
  }
  auto snap = std::make_shared<const Snapshot>(decode_snapshot(snapshot_.take()));
  if (joined_ && snap->mesh.triangles != base_.triangles)
    return dropped("snapshot of another mesh connectivity");
  install_snapshot(std::move(snap));
}

/// The assembled snapshot becomes our version: the joiner's first, or a diverged peer's way
/// back to the merger's history.
void PeerNode::install_snapshot(std::shared_ptr<const Snapshot> snap,
                                std::shared_ptr<const Hierarchy> hierarchy, bool journaled) {
  const std::optional<std::uint64_t> fork =
      joined_ ? replication_.fork_point(snap->chains) : std::nullopt;
  release_base();
  base_ = snap->mesh;
  replication_.reset(snapshot_.version(), snapshot_.chain(), snap->chains);
  snapshot_requested_ = false;
  if (merger_) merger_->clear();
  frame_ = snap->frame;
  host_.set_frame_and_attribution(snap->frame, snap->attribution);
  if (!hierarchy_) build_merge_state(std::move(hierarchy));
  own_submit_.bytes.clear();
  if (journaled)
    adopt_journal_snapshot();
  else
    journal_snapshot();
  HostItem item;
  item.snapshot = true;
  item.version = replication_.version();
  item.snap = std::move(snap);
  item.fork = fork;
  host_.push_item(std::move(item), [](SessionStats&) {});
  if (!joined_) {
    joined_ = true;
    event(EventKind::joined, self_);
    host_.set_joined();
  }
  drain_buffered();
}

// ---- membership and election glue -------------------------------------------------------------

void PeerNode::member_joined(PeerId peer, const std::string& endpoint) {
  peer_table_.returned(peer);
  transport_.connect(endpoint);
  // Introduce ourselves: the newcomer learns our endpoint and that we are alive.
  transport_.send(endpoint, hello(false));
  journal_member(peer, endpoint);
  event(EventKind::peer_joined, peer, endpoint);
}

void PeerNode::merger_changed() {
  if (merger_) merger_->clear();
  event(EventKind::merger_changed, *election_.merger());
  send_own_submit();  // a peer keeps its diff until merged: the new merger gets it
}

void PeerNode::elect() {
  if (!joined_) return;
  const Election::Decision d = election_.update(membership_);
  if (d.announce) broadcast(elected_message(header(), self_));
  if (d.changed && election_.merger()) merger_changed();
}

/// Applies the membership thresholds: evasive peers reported, expired ones forgotten (their
/// endpoints greeted for a while: they may be across a partition that heals).
void PeerNode::expire(Clock::time_point now) {
  const std::map<PeerId, Member> before = membership_.members();
  const Membership::Changes changes = membership_.tick(now);
  for (PeerId p : changes.evasive) event(EventKind::peer_evasive, p);
  for (PeerId p : changes.expired) {
    if (const auto it = before.find(p); it != before.end() && !it->second.endpoint.empty()) {
      lost_[it->second.endpoint] = now;
      transport_.disconnect(it->second.endpoint);  // greeted over a new connection
      drop_outgoing_snapshot(p);  // what was queued went with the connection: it asks again
    }
    departed(p, "expired");
  }
}

/// A hello to every lost endpoint, every four heartbeats: whoever answers is a member again
/// (on_hello), and both sides of a healed partition meet whichever spoke first.
void PeerNode::greet_lost(Clock::time_point now) {
  if (now < next_greeting_) return;
  next_greeting_ = now + 4 * options_.membership.heartbeat;
  for (auto it = lost_.begin(); it != lost_.end();) {
    const bool member = std::any_of(membership_.members().begin(), membership_.members().end(),
                                    [&](const auto& m) { return m.second.endpoint == it->first; });
    if (member || now - it->second > kGreetLostFor) {
      it = lost_.erase(it);
      continue;
    }
    transport_.send(it->first, hello(false));
    ++it;
  }
}

/// `peer` is no longer a member: what it sent for merging, its version and its cursor go.
void PeerNode::departed(PeerId peer, const char* how) {
  if (merger_) merger_->forget(peer);
  reported_.erase(peer);
  peer_table_.departed(peer);
  publish_peers();  // before its cursor goes: a host that sees it gone sees the peer left
  host_.update_presence([&](PresenceTable& t) { t.forget(peer); });
  event(EventKind::peer_left, peer, how);
}

/// Peers reported evasive and heard again since: the host learns they are live.
void PeerNode::report_revived() {
  for (PeerId p : membership_.take_revived())
    if (membership_.contains(p)) event(EventKind::peer_live, p);
}

// ---- replication glue -------------------------------------------------------------------------

/// Applies a version that follows ours, hands it to the host and keeps it for fetches.
void PeerNode::apply_version(VersionRecord r, Diff* merged_here) {
  // Checked before the merge in flight is dropped (the check only reads base_, as the worker
  // does): a version that fails, forged or corrupt, must not cost the submits being merged.
  Diff merged = merged_here ? std::move(*merged_here) : replication_.check(r, base_);
  release_base();
  replication_.append(std::move(r), merged, base_);
  const VersionRecord& kept = replication_.latest();
  const std::uint64_t version = replication_.version();
  // Submits held for the old version (a merger catching up by fetch) no longer apply: their
  // authors rebase and send again when they see this version.
  if (merger_) merger_->clear();
  add_contributions(kept);
  journal_version(kept);  // on disk before the host sees it
  if (own_submit_.kind == Command::Kind::submit && own_submit_.base_version < version)
    own_submit_.bytes.clear();  // stale: the host rebases and submits again
  HostItem item;
  item.version = version;
  item.merged = std::move(merged);
  item.merged_by = kept.merged;
  host_.push_item(std::move(item), [&](SessionStats& s) { s.version = version; });
  event(EventKind::version, election_.merger().value_or(0));
}

void PeerNode::drain_buffered() {
  while (std::optional<VersionRecord> r = replication_.take_next_buffered())
    apply_version(std::move(*r));
}

void PeerNode::add_contributions(const VersionRecord& r) {
  const std::size_t n = base_.vertex_count();
  host_.update_attribution([&](std::map<PeerId, std::vector<float>>& attribution) {
    for (const Contribution& c : r.contributions) {
      std::vector<float>& a = attribution[c.peer];
      a.resize(n, 0.f);
      add_contribution(c, a);
    }
  });
}

/// The merger's history says `chain` at `version`, which we also hold: if ours differs, we
/// applied a lost merger's versions (two mergers for a moment, after a false expiry or a
/// partition) and take the merger's state instead. Rate-limited.
void PeerNode::check_divergence(PeerId merger, std::uint64_t version, std::uint64_t chain,
                                Clock::time_point now) {
  if (!replication_.diverges(version, chain) || now < next_divergence_check_) return;
  next_divergence_check_ = now + 4 * options_.membership.heartbeat;
  request_snapshot(merger);
}

/// One snapshot at a time: each request is answered with a whole snapshot of the sender's
/// version of the moment, and a peer behind a merger that publishes every 10 ms asked once per
/// version it received, so the answers' chunks interleaved and none ever completed. Asked
/// again (from whoever is asked now) only when the last one has not come in kSnapshotRetry.
void PeerNode::request_snapshot(PeerId from) {
  const Clock::time_point now = Clock::now();
  if (snapshot_requested_ && (now < next_snapshot_request_ || snapshot_flowing(now))) return;
  next_snapshot_request_ = now + std::max(kSnapshotRetry, 4 * options_.membership.expired);
  snapshot_.reset();
  snapshot_requested_ = true;
  send_to_peer(from, snapshot_request_message(header()));
}

/// Chunks of a snapshot have come lately: it is on its way.
bool PeerNode::snapshot_flowing(Clock::time_point now) const {
  return now - last_snapshot_chunk_ < kSnapshotRetry;
}

// ---- outbound ---------------------------------------------------------------------------------

EnvelopeHeader PeerNode::header() const {
  return {invite_.session, self_, election_.epoch()};
}

void PeerNode::send_to_peer(PeerId peer, const Bytes& bytes) {
  const auto& m = membership_.members();
  if (auto it = m.find(peer); it != m.end() && !it->second.endpoint.empty())
    transport_.send(it->second.endpoint, bytes);
}

void PeerNode::broadcast(const Bytes& bytes) {
  for (const Member* m : membership_.others())
    if (!m->endpoint.empty()) transport_.send(m->endpoint, bytes);
}

void PeerNode::heartbeat(Clock::time_point now) {
  if (!joined_) return joining_heartbeat(now);
  expire(now);
  // A new socket would reuse our routing id while the old connection is still open on the
  // stalled peer's side, which its ROUTER refuses, and both sides would stay deaf to each other:
  // sockets of peers no longer members close only some time after they went.
  transport_.close_departed(
      [&](const std::string& endpoint) {
        if (endpoint == joining_endpoint_ || lost_.count(endpoint)) return true;
        for (const auto& [id, m] : membership_.members())
          if (m.endpoint == endpoint) return true;
        return false;
      },
      now, 2 * options_.membership.expired);
  elect();
  for (const Member* m : membership_.others()) send_heartbeat_to(m->endpoint);
  greet_lost(now);
}

/// Still joining: the members we know hear that we are alive (a large snapshot's transfer and
/// load take longer than their expiry; taken for dead, we lost the socket the snapshot came
/// on), and the inviter is greeted again until the snapshot arrives (not so often that a large
/// one is sent twice while the first is on its way or loading).
void PeerNode::joining_heartbeat(Clock::time_point now) {
  for (const Member* m : membership_.others()) send_heartbeat_to(m->endpoint);
  if (now < next_join_hello_ || snapshot_loader_.busy()) return;
  next_join_hello_ = now + std::max(kSnapshotRetry, 4 * options_.membership.expired);
  if (snapshot_flowing(now)) return;
  snapshot_.reset();  // one that stopped coming is not finished
  transport_.send(joining_endpoint_, hello(true));
}

void PeerNode::send_heartbeat_to(const std::string& endpoint) {
  std::vector<std::pair<PeerId, std::string>> members;
  for (const Member* m : membership_.vouched())
    if (!m->endpoint.empty()) members.emplace_back(m->id, m->endpoint);
  const Clock::time_point now = Clock::now();
  transport_.send(endpoint, heartbeat_message(header(), replication_.version(),
                                              replication_.chain(), election_.merger().value_or(0),
                                              members, {micros(now), peer_table_.echoes(now)}));
}

Bytes PeerNode::hello(bool wants_snapshot) const {
  return hello_message(header(), transport_.endpoint(), options_.name, wants_snapshot);
}

void PeerNode::send_own_submit() {
  if (own_submit_.kind != Command::Kind::submit || own_submit_.bytes.empty()) return;
  if (own_submit_.base_version != replication_.version()) return;  // stale: host will rebase
  const Bytes bytes = submit_message(header(), own_submit_.bytes, own_submit_.strokes);
  host_.update_stats([&](SessionStats& s) {
    ++s.submits;
    s.submit_bytes += bytes.size();
  });
  if (election_.is_merger()) {
    // Our own submit goes through the same checks as anyone's.
    const fb::Envelope* env = fb::GetEnvelope(bytes.data());
    try {
      on_submit(self_, *env->body_as_Submit());
    } catch (const InvalidInput& e) {
      event(EventKind::error, self_, e.what());
    }
  } else if (election_.merger()) {
    const auto merger = reported_.find(*election_.merger());
    own_submit_merger_version_ = merger == reported_.end() ? kUnknownVersion : merger->second.first;
    send_to_peer(*election_.merger(), bytes);
  }
}

void PeerNode::resend_own_submit_if_caught_up(std::uint64_t version, std::uint64_t chain) {
  if (own_submit_.kind != Command::Kind::submit || own_submit_.bytes.empty()) return;
  if (version != own_submit_.base_version || version != replication_.version() ||
      chain != replication_.chain() || own_submit_merger_version_ == version)
    return;  // not caught up with our base, or it held our base when the submit went
  host_.update_stats([](SessionStats& s) { ++s.submits_resent; });
  send_own_submit();
}

/// Our cursor to every member: a change at most every 50 ms, the same again every second.
void PeerNode::send_presence(Clock::time_point now) {
  const auto [changed, any] = host_.presence_state();
  if (!joined_ || !presence_.due(changed, any, now)) return;
  const Presence p = host_.take_presence();
  broadcast(presence_message(header(), presence_.sent(now), p));
}

void PeerNode::merge_pending() {
  if (!joined_ || !merger_ || merger_->empty() || merge_worker_.busy() || hold_merges(Clock::now()))
    return;
  // A new merger first catches up with the most advanced live peer (fetching as heartbeats
  // show the gap), so it never publishes a version number someone already holds.
  for (const auto& [peer, vc] : reported_)
    if (membership_.contains(peer) && vc.first > replication_.version()) return;
  // The worker reads base_ in place: nothing changes it while the merge runs (drop_merge).
  merge_worker_.start([&role = *merger_, submits = merger_->take_pending(), &base = base_,
                       version = replication_.version(), chain = replication_.chain(),
                       frame = frame_, wire = options_.wire]() mutable {
    return role.merge(std::move(submits), base, version, chain, frame, wire);
  });
}

void PeerNode::drop_merge() {
  // Another merger's version or a snapshot replaces the mesh the merge began on, so its outcome
  // could not be published anyway; waiting keeps base_ unchanged while the worker reads it. A
  // peer applies such a version while it merges only when catching up (a fetch's replay) or
  // recovering from divergence: rarely, and never on the path of an edit.
  if (!merge_worker_.busy()) return;
  merge_worker_.drop();
  if (merger_) merger_->forget_last();
}

void PeerNode::finish_merge() {
  std::optional<MergeOutcome> outcome = merge_worker_.take();
  if (!outcome) return;
  MergeOutcome& o = *outcome;
  // The version and chain it merged on still hold (whatever changes them drops the merge
  // first, drop_merge). If this peer no longer merges, the merged submits' authors send them
  // to the new merger.
  if (!election_.is_merger()) {
    merger_->forget_last();
    return;
  }
  const Bytes message = version_message(header(), o.record, false);
  broadcast(message);
  const std::uint32_t folds = merger_->count_last_folds(base_);  // base_: the merged-on mesh
  const std::uint32_t conflicting = o.record.conflicting;
  const float merge_ms = o.record.merge_ms;
  apply_version(std::move(o.record), &o.decoded);
  // After applying, so a reader never sees a merge counted before its version.
  const std::size_t others = membership_.others().size();
  host_.update_stats([&](SessionStats& s) {
    ++s.merges;
    s.merged_strokes += o.merged_strokes;
    s.conflicting_strokes += conflicting;
    s.folds_introduced += folds;
    s.merge_ms_sum += merge_ms;
    s.merge_ms_max = std::max(s.merge_ms_max, double(merge_ms));
    s.version_bytes_sent += message.size() * others;
  });
}

void PeerNode::finish_load() {
  std::optional<LoadedSnapshot> loaded;
  try {
    loaded = snapshot_loader_.take();
  } catch (const InvalidInput& e) {
    // A snapshot that fails its checks: asked for again at the next greeting.
    return dropped(e.what());
  }
  if (!loaded) return;
  if (!loaded->journal_error.empty() && journal_) {
    journal_.reset();
    event(EventKind::error, self_, loaded->journal_error + "; journaling stopped");
  }
  install_snapshot(std::move(loaded->snap), std::move(loaded->hierarchy), loaded->journaled);
}

void PeerNode::build_merge_state(std::shared_ptr<const Hierarchy> hierarchy) {
  drop_merge();  // its merge uses the role replaced here
  hierarchy_ = hierarchy ? std::move(hierarchy) : hierarchy_of(base_);
  merger_.emplace(hierarchy_);
  host_.set_hierarchy(hierarchy_);
}

// ---- events -----------------------------------------------------------------------------------

void PeerNode::event(EventKind kind, PeerId peer, std::string message) {
  host_.push_event({kind, peer, replication_.version(), election_.epoch(), std::move(message)});
}

void PeerNode::dropped(const std::string& why) {
  host_.update_stats([](SessionStats& s) { ++s.messages_dropped; });
  host_.push_event({EventKind::dropped, 0, replication_.version(), election_.epoch(), why});
}

}  // namespace csculpt::peer
