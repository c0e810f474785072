#include "session_link.h"

#include <algorithm>
#include <cstdio>

namespace {

constexpr size_t kMaxMessages = 8;
// A cursor not heard of for this long is hidden (its sender resends every second while it
// hovers, so this is a stalled or departed peer).
constexpr uint32_t kStaleCursorMs = 2000;

std::string abi_error(const char* what, csc_status status) {
  return std::string(what) + ": " + csc_status_str(status) + ": " + csc_last_error();
}

csc_session_options app_options() {
  csc_session_options options = CSC_SESSION_OPTIONS_INIT;
  options.name = "csculpt-app";
  options.join_timeout_ms = 10000;
  return options;
}

}  // namespace

SessionLink::~SessionLink() {
  if (join_.valid()) {  // a join still under way: wait for it so its session is not leaked
    JoinResult result = join_.get();
    csc_session_destroy(result.session);
  }
  csc_session_destroy(session_);
}

bool SessionLink::host(const csc_mesh* mesh, std::string& error) {
  options_ = app_options();
  csc_session* session = nullptr;
  if (csc_status s = csc_session_create(&session, mesh, &options_); s != CSC_OK) {
    error = abi_error("cannot host a session", s);
    return false;
  }
  csc_session_destroy(session_);
  session_ = session;
  peers_.clear();
  version_pending_ = false;
  status_ = "hosting";
  note("hosting: share the invite");
  return true;
}

void SessionLink::begin_join(const std::string& invite) {
  options_ = app_options();
  status_ = "joining...";
  // csc_session_join waits for the snapshot; csc_last_error is thread-local, so the worker
  // takes the words along with the result.
  join_ = std::async(std::launch::async, [invite, options = options_] {
    JoinResult result;
    if (csc_status s = csc_session_join(&result.session, invite.c_str(), &options); s != CSC_OK)
      result.error = abi_error("cannot join", s);
    return result;
  });
}

int SessionLink::poll_join(std::string& error) {
  if (!join_.valid() || join_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return 0;
  JoinResult result = join_.get();
  if (!result.session) {
    error = result.error;
    status_ = session_ ? status_ : "not in a session";
    note(error);
    return -1;
  }
  csc_session_destroy(session_);
  session_ = result.session;
  peers_.clear();
  version_pending_ = false;
  status_ = "joined";
  note("joined the session");
  return 1;
}

void SessionLink::note(std::string message) {
  messages_.push_back(std::move(message));
  if (messages_.size() > kMaxMessages) messages_.erase(messages_.begin());
}

void SessionLink::set_peer(uint64_t id, PeerState state) {
  auto it = std::find_if(peers_.begin(), peers_.end(), [&](const Peer& p) { return p.id == id; });
  if (it == peers_.end()) peers_.push_back({id, state, "", false, 0, -1});
  else it->state = state;
}

// The library's list is the truth (names, merger, versions, round trips); the events above
// only make a change show in the same frame.
void SessionLink::refresh_peers() {
  uint32_t count = 0;
  if (csc_session_peer_count(session_, &count) != CSC_OK) return;
  peers_.clear();
  for (uint32_t i = 0; i < count; ++i) {
    csc_peer_info info = CSC_PEER_INFO_INIT;
    if (csc_session_get_peer(session_, i, &info) != CSC_OK) continue;
    const PeerState state = info.state == CSC_PEER_LEFT      ? PeerState::left
                            : info.state == CSC_PEER_EVASIVE ? PeerState::evasive
                                                             : PeerState::live;
    peers_.push_back({info.id, state, info.name ? info.name : "", info.merger != 0, info.version,
                      info.latency_ms});
  }
}

void SessionLink::refresh_cursors() {
  uint32_t count = 0;
  cursors_.clear();
  if (csc_session_presence_count(session_, &count) != CSC_OK) return;
  for (uint32_t i = 0; i < count; ++i) {
    csc_presence p = CSC_PRESENCE_INIT;
    if (csc_session_get_presence(session_, i, &p) != CSC_OK || !p.visible || p.age_ms > kStaleCursorMs)
      continue;
    presence_seen_.insert(p.peer);
    cursors_.push_back({p.peer, {p.position[0], p.position[1], p.position[2]}, p.radius, p.active != 0,
                        {p.colour[0], p.colour[1], p.colour[2]}});
  }
}

void SessionLink::set_presence(const csc_presence& presence) {
  if (!session_) return;
  if (csc_status s = csc_session_set_presence(session_, &presence); s != CSC_OK)
    note(abi_error("cannot send the cursor", s));
}

void SessionLink::poll_events() {
  if (!session_) return;
  for (;;) {
    csc_session_event event = CSC_SESSION_EVENT_INIT;
    int32_t has_event = 0;
    if (csc_session_poll(session_, &event, &has_event) != CSC_OK || !has_event) break;
    char id[32];
    std::snprintf(id, sizeof id, "%016llx", static_cast<unsigned long long>(event.peer));
    switch (event.kind) {
      case CSC_EVENT_JOINED: status_ = "live"; break;
      case CSC_EVENT_VERSION: version_pending_ = true; break;
      case CSC_EVENT_PEER_JOINED: set_peer(event.peer, PeerState::live); note(std::string("peer ") + id + " joined"); break;
      case CSC_EVENT_PEER_EVASIVE: set_peer(event.peer, PeerState::evasive); note(std::string("peer ") + id + " is silent"); break;
      case CSC_EVENT_PEER_LEFT: set_peer(event.peer, PeerState::left); note(std::string("peer ") + id + " left"); break;
      case CSC_EVENT_PEER_LIVE: set_peer(event.peer, PeerState::live); note(std::string("peer ") + id + " is back"); break;
      case CSC_EVENT_MERGER_CHANGED: note(std::string("peer ") + id + " merges now"); break;
      case CSC_EVENT_DROPPED: note(std::string("dropped a message: ") + (event.message ? event.message : "")); break;
      case CSC_EVENT_ERROR:
        status_ = "network error";
        note(std::string("network error: ") + (event.message ? event.message : ""));
        break;
      default: break;
    }
  }
  csc_session_get_stats(session_, &stats_);
  refresh_peers();
  refresh_cursors();
}

uint32_t SessionLink::update(csc_vertex_arrays& local) {
  version_pending_ = false;
  uint32_t applied = 0;
  if (csc_status s = csc_session_update(session_, &local, &applied); s != CSC_OK) {
    note(abi_error("cannot apply a merged version", s));
    return 0;
  }
  return applied;
}

bool SessionLink::submit(csc_vertex_arrays& local, uint32_t strokes) {
  int32_t sent = 0;
  last_submit_ = std::chrono::steady_clock::now();
  if (csc_status s = csc_session_submit(session_, &local, strokes, &sent); s != CSC_OK) {
    note(abi_error("cannot send the stroke", s));
    return false;
  }
  return sent != 0;
}

void SessionLink::record_stroke(csc_vertex_arrays& local, const std::vector<uint32_t>& vertices,
                                const std::vector<float>& before) {
  const uint32_t count = static_cast<uint32_t>(vertices.size());
  if (csc_status s = csc_session_record_stroke(session_, &local, vertices.data(), count, before.data());
      s != CSC_OK)
    note(abi_error("cannot keep the stroke for undo", s));
}

bool SessionLink::undo(csc_vertex_arrays& local, bool redo) {
  uint32_t changed = 0;
  const csc_status s = redo ? csc_session_redo(session_, &local, nullptr, &changed)
                            : csc_session_undo(session_, &local, nullptr, &changed);
  if (s != CSC_OK) {
    note(abi_error(redo ? "cannot redo" : "cannot undo", s));
    return false;
  }
  return changed > 0;
}

uint32_t SessionLink::undo_depth() const {
  uint32_t n = 0;
  if (session_) csc_session_undo_depth(session_, &n, nullptr);
  return n;
}

uint32_t SessionLink::redo_depth() const {
  uint32_t n = 0;
  if (session_) csc_session_undo_depth(session_, nullptr, &n);
  return n;
}

bool SessionLink::resubmit_due() const {
  return session_ && stats_.strokes_acknowledged < stats_.strokes_submitted &&
         std::chrono::steady_clock::now() - last_submit_ > std::chrono::milliseconds(options_.sync_ms);
}

void SessionLink::leave() {
  if (!session_) return;
  csc_session_leave(session_);
  csc_session_destroy(session_);
  session_ = nullptr;
  peers_.clear();
  cursors_.clear();
  status_ = "left the session";
  note("left the session; the mesh is yours to keep");
}

csc_mesh* SessionLink::copy_base(std::string& error) const {
  csc_mesh* mesh = nullptr;
  if (csc_status s = csc_session_copy_base(&mesh, session_); s != CSC_OK) {
    error = abi_error("cannot copy the session's mesh", s);
    return nullptr;
  }
  return mesh;
}

bool SessionLink::attribution_colours(std::vector<float>& rgb, uint32_t vertex_count) const {
  rgb.resize(size_t{vertex_count} * 3);
  return session_ && csc_session_attribution_colors(session_, rgb.data(), vertex_count) == CSC_OK;
}
