#include "session_worker.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <utility>

#include "abi_error.h"

namespace {

constexpr size_t kMaxMessages = 8;
// How often the worker looks at the session when nothing is handed to it: well under a frame.
constexpr auto kTick = std::chrono::milliseconds(4);
// Peers, cursors and statistics are read this often (the panel shows them, nothing waits).
constexpr auto kViewEvery = std::chrono::milliseconds(50);
// A cursor not heard of for this long is hidden (its sender resends every second while it
// hovers, so this is a stalled or departed peer).
constexpr uint32_t kStaleCursorMs = 2000;

// Points into `settings`, which outlives the call it is made for.
csc_session_options session_options(const PeerSettings& settings) {
  csc_session_options options = CSC_SESSION_OPTIONS_INIT;
  options.join_timeout_ms = 10000;
  options.name = settings.name.c_str();
  if (!settings.bind.empty()) options.bind = settings.bind.c_str();
  return options;
}

}  // namespace

// ---- MeshArrays -----------------------------------------------------------------------------

uint32_t MeshArrays::stride() const {
  uint32_t n = 3;
  for (uint32_t w : widths) n += w;
  return n;
}

csc_vertex_arrays MeshArrays::view() {
  pointers_.clear();
  for (std::vector<float>& c : channels) pointers_.push_back(c.data());
  csc_vertex_arrays a = CSC_VERTEX_ARRAYS_INIT;
  a.vertex_count = vertex_count();
  a.positions = positions.data();
  a.channel_count = static_cast<uint32_t>(channels.size());
  a.channels = pointers_.data();
  return a;
}

void MeshArrays::read(uint32_t v, float* out) const {
  out = std::copy_n(&positions[3 * size_t{v}], 3, out);
  for (size_t c = 0; c < channels.size(); ++c)
    out = std::copy_n(&channels[c][size_t{v} * widths[c]], widths[c], out);
}

void MeshArrays::write(uint32_t v, const float* in) {
  std::copy_n(in, 3, &positions[3 * size_t{v}]);
  in += 3;
  for (size_t c = 0; c < channels.size(); ++c) {
    std::copy_n(in, widths[c], &channels[c][size_t{v} * widths[c]]);
    in += widths[c];
  }
}

namespace {

/** Whether `count` vertices from `first` of two arrays of `width` floats per vertex differ. */
bool block_differs(const std::vector<float>& a, const std::vector<float>& b, uint32_t width,
                   uint32_t first, uint32_t count) {
  const size_t at = size_t{first} * width;
  return std::memcmp(&a[at], &b[at], size_t{count} * width * sizeof(float)) != 0;
}

}  // namespace

bool MeshArrays::range_differs(const MeshArrays& other, uint32_t first, uint32_t count) const {
  if (block_differs(positions, other.positions, 3, first, count)) return true;
  for (size_t c = 0; c < channels.size(); ++c)
    if (block_differs(channels[c], other.channels[c], widths[c], first, count)) return true;
  return false;
}

// A version usually changes a few strokes' worth of vertices: whole blocks compared at memory
// speed, vertex by vertex only inside the blocks that differ (a call per vertex over every
// array cost the session worker a core's worth of time at 160K vertices).
void MeshArrays::differing_vertices(const MeshArrays& other, std::vector<uint32_t>& out) const {
  constexpr uint32_t kBlock = 64;
  const uint32_t n = vertex_count();
  for (uint32_t first = 0; first < n; first += kBlock) {
    const uint32_t count = std::min(kBlock, n - first);
    if (!range_differs(other, first, count)) continue;
    for (uint32_t v = first; v < first + count; ++v)
      if (range_differs(other, v, 1)) out.push_back(v);
  }
}

MeshArrays MeshArrays::of(const csc_mesh* mesh) {
  MeshArrays a;
  const uint32_t n = csc_mesh_vertex_count(mesh);
  const float* p = csc_mesh_positions(mesh);
  a.positions.assign(p, p + 3 * size_t{n});
  for (uint32_t c = 0; c < csc_mesh_channel_count(mesh); ++c) {
    csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
    if (csc_mesh_channel(mesh, c, &view) != CSC_OK) continue;
    a.channels.emplace_back(view.values, view.values + size_t{n} * view.desc.width);
    a.widths.push_back(view.desc.width);
    a.min_value.push_back(view.desc.min_value);
    a.max_value.push_back(view.desc.max_value);
  }
  return a;
}

// ---- SessionWorker: the UI thread's side ----------------------------------------------------

SessionWorker::SessionWorker(MeshContent content, TriangleBvh bvh, PeerSettings settings)
    : host_content_(std::move(content)), settings_(std::move(settings)) {
  handed_bvh_ = std::make_unique<TriangleBvh>(std::move(bvh));  // its positions: create()
  local_view_.status = "starting a session...";
  view_ = local_view_;
  thread_ = std::thread([this] { run({}); });
}

SessionWorker::SessionWorker(std::string invite, PeerSettings settings)
    : settings_(std::move(settings)) {
  local_view_.status = "joining...";
  view_ = local_view_;
  thread_ = std::thread([this, invite = std::move(invite)] { run(invite); });
}

SessionWorker::~SessionWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
  csc_mesh_destroy(joined_mesh_);
}

int SessionWorker::state(std::string& error) const {
  std::lock_guard lock(mutex_);
  error = error_;
  return state_;
}

csc_mesh* SessionWorker::take_joined_mesh() {
  std::lock_guard lock(mutex_);
  return std::exchange(joined_mesh_, nullptr);
}

void SessionWorker::hand_stroke(std::vector<uint32_t> vertices, std::vector<float> before,
                                std::vector<float> after) {
  {
    std::lock_guard lock(mutex_);
    inbox_.commands.push_back(
        {Command::Kind::stroke, std::move(vertices), std::move(before), std::move(after), {}});
    ++inbox_.handed;
  }
  wake_.notify_one();
}

void SessionWorker::request_step(bool redo) {
  {
    std::lock_guard lock(mutex_);
    inbox_.commands.push_back({redo ? Command::Kind::redo : Command::Kind::undo, {}, {}, {}, {}});
    ++inbox_.handed;
  }
  wake_.notify_one();
}

void SessionWorker::set_presence(const csc_presence& presence) {
  std::lock_guard lock(mutex_);
  inbox_.has_presence = true;
  inbox_.presence = presence;
}

void SessionWorker::hand_bvh(TriangleBvh bvh, std::vector<float> positions) {
  std::lock_guard lock(mutex_);
  handed_bvh_ = std::make_unique<TriangleBvh>(std::move(bvh));
  handed_bvh_positions_ = std::move(positions);
}

std::shared_ptr<const MeshChanges> SessionWorker::take_changes() {
  std::lock_guard lock(mutex_);
  if (!outbox_ || outbox_->includes < inbox_.handed || outbox_taken_) return {};
  outbox_taken_ = true;
  ++takes_;
  // In line with the strokes: the worker learns what the document holds in the order it
  // changed (a stroke's after-values over an older take, never the other way round).
  inbox_.commands.push_back({Command::Kind::taken, {}, {}, {}, outbox_});
  return outbox_;
}

void SessionWorker::settle(int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    {
      std::lock_guard lock(mutex_);
      // An outbox is published after the submit of the same loop: including every command
      // handed means they are all sent too.
      if (state_ != 1 || (outbox_ && outbox_->includes >= inbox_.handed)) return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

SessionView SessionWorker::view() const {
  std::lock_guard lock(mutex_);
  return view_;
}

std::shared_ptr<const std::vector<float>> SessionWorker::attribution_colours() {
  std::lock_guard lock(mutex_);
  want_attribution_ = true;
  return attribution_;
}

// ---- SessionWorker: the worker thread -------------------------------------------------------

void SessionWorker::run(std::string invite) {
  if (!invite.empty() && !join(invite)) return;
  if (invite.empty() && !create()) return;
  loop();
  finish();
}

// Hosting: the session's mesh is made of the document's arrays as they were when Host was
// clicked; the mirror, what the UI shows and the normals' topology are that mesh's.
bool SessionWorker::create() {
  std::string error;
  csc_mesh* mesh = host_content_.to_csc_mesh(error);
  {
    std::lock_guard lock(mutex_);
    handed_bvh_positions_ = std::move(host_content_.positions);  // what the BVH is tight over
  }
  host_content_ = {};  // the mesh holds the arrays now
  csc_session* session = nullptr;
  if (mesh) {
    mirror_ = MeshArrays::of(mesh);
    shown_ = mirror_;
    const uint32_t* corners = csc_mesh_triangles(mesh);
    normals_.set_topology({corners, corners + 3 * size_t{csc_mesh_triangle_count(mesh)}},
                          mirror_.vertex_count());
    const csc_session_options options = session_options(settings_);
    if (csc_status s = csc_session_create(&session, mesh, &options); s != CSC_OK)
      error = abi_error("cannot host a session", s);
    csc_mesh_destroy(mesh);
  }
  std::lock_guard lock(mutex_);
  if (!session) {
    error_ = error;
    state_ = -1;
    return false;
  }
  session_ = session;
  local_view_.status = "hosting";
  local_view_.invite = csc_session_invite(session);
  view_ = local_view_;
  state_ = 1;
  return true;
}

bool SessionWorker::join(const std::string& invite) {
  const csc_session_options options = session_options(settings_);
  csc_session* session = nullptr;
  csc_mesh* base = nullptr;
  csc_status s = csc_session_join(&session, invite.c_str(), &options);
  if (s == CSC_OK) s = csc_session_copy_base(&base, session);
  std::lock_guard lock(mutex_);
  if (s != CSC_OK) {
    error_ = abi_error("cannot join", s);
    csc_session_destroy(session);
    state_ = -1;
    return false;
  }
  session_ = session;
  mirror_ = MeshArrays::of(base);
  const uint32_t* corners = csc_mesh_triangles(base);
  normals_.set_topology({corners, corners + 3 * size_t{csc_mesh_triangle_count(base)}},
                        mirror_.vertex_count());
  shown_ = mirror_;
  joined_mesh_ = base;
  local_view_.status = "joined";
  state_ = 1;
  return true;
}

void SessionWorker::loop() {
  note(local_view_.status == "hosting" ? "hosting: share the invite" : "joined the session");
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, kTick, [&] { return stop_ || !inbox_.commands.empty(); });
      if (stop_) return;
    }
    drain_inbox();
    sync();
    if (std::chrono::steady_clock::now() - last_view_ > kViewEvery) refresh_view();
    publish();
  }
}

void SessionWorker::drain_inbox() {
  Inbox in;
  {
    std::lock_guard lock(mutex_);
    in.commands.swap(inbox_.commands);
    in.has_presence = std::exchange(inbox_.has_presence, false);
    in.presence = inbox_.presence;
    if (handed_bvh_) {
      bvh_ = std::move(*handed_bvh_);
      bvh_positions_ = std::move(handed_bvh_positions_);
      handed_bvh_.reset();
    }
  }
  const uint32_t stride = shown_.stride();
  for (const Command& c : in.commands) {
    if (c.kind == Command::Kind::taken) {
      ++takes_drained_;
      for (size_t i = 0; i < c.changes->vertices.size(); ++i)
        shown_.write(c.changes->vertices[i], &c.changes->values[i * stride]);
      continue;
    }
    if (c.kind == Command::Kind::stroke)
      apply_stroke(c);
    else
      apply_step(c.kind == Command::Kind::redo);
    ++done_;
    dirty_ = true;
  }
  if (in.has_presence)
    if (csc_status s = csc_session_set_presence(session_, &in.presence); s != CSC_OK)
      note(abi_error("cannot send the cursor", s));
}

// The stroke's change onto the mirror: exact where the mirror still holds the values the stroke
// started from, added where a remote version moved the vertex since; then kept for undo.
void SessionWorker::apply_stroke(const Command& c) {
  const uint32_t stride = mirror_.stride();
  std::vector<float> now(stride), recorded(c.vertices.size() * stride);
  for (size_t i = 0; i < c.vertices.size(); ++i) {
    const float* before = &c.before[i * stride];
    const float* after = &c.after[i * stride];
    mirror_.read(c.vertices[i], now.data());
    std::copy(now.begin(), now.end(), &recorded[i * stride]);
    for (uint32_t k = 0; k < stride; ++k)
      now[k] = now[k] == before[k] ? after[k] : now[k] + (after[k] - before[k]);
    for (uint32_t k = 3, ch = 0; ch < mirror_.widths.size(); k += mirror_.widths[ch++])
      for (uint32_t j = k; j < k + mirror_.widths[ch]; ++j)
        now[j] = std::clamp(now[j], mirror_.min_value[ch], mirror_.max_value[ch]);
    mirror_.write(c.vertices[i], now.data());
    shown_.write(c.vertices[i], after);  // what the UI shows there now: the diff starts from it
  }
  const csc_vertex_arrays a = mirror_.view();
  const uint32_t count = static_cast<uint32_t>(c.vertices.size());
  if (csc_status s =
          csc_session_record_stroke(session_, &a, c.vertices.data(), count, recorded.data());
      s != CSC_OK)
    note(abi_error("cannot keep the stroke for undo", s));
  unsent_vertices_.insert(unsent_vertices_.end(), c.vertices.begin(), c.vertices.end());
  ++strokes_unsent_;
}

void SessionWorker::apply_step(bool redo) {
  const csc_vertex_arrays a = mirror_.view();
  uint32_t changed = 0;
  const csc_status s = redo ? csc_session_redo(session_, &a, nullptr, &changed)
                            : csc_session_undo(session_, &a, nullptr, &changed);
  if (s != CSC_OK) note(abi_error(redo ? "cannot redo" : "cannot undo", s));
  if (changed > 0) ++strokes_unsent_;  // sent like a stroke
}

void SessionWorker::sync() {
  const csc_vertex_arrays a = mirror_.view();
  if (poll_events()) {
    uint32_t applied = 0;
    // The strokes since the last submit are all the worker changed: the session compares and
    // writes back those and what it changed, not the whole mesh.
    const auto count = static_cast<uint32_t>(unsent_vertices_.size());
    if (csc_status s =
            csc_session_update_changed(session_, &a, unsent_vertices_.data(), count, &applied);
        s != CSC_OK)
      note(abi_error("cannot apply a merged version", s));
    if (applied > 0) dirty_ = attribution_stale_ = true;
  }
  const csc_session_stats& stats = local_view_.stats;
  const bool resubmit = stats.strokes_acknowledged < stats.strokes_submitted &&
                        std::chrono::steady_clock::now() - last_submit_ >
                            std::chrono::milliseconds(session_options(settings_).sync_ms);
  if (strokes_unsent_ > 0 || resubmit) {
    int32_t sent = 0;
    last_submit_ = std::chrono::steady_clock::now();
    // The strokes' vertices only: the session keeps what else differs from its version (what
    // undo and redo wrote, what a rebase left), so a submit costs the stroke, not the mesh.
    const auto count = static_cast<uint32_t>(unsent_vertices_.size());
    if (csc_status s = csc_session_submit_changed(session_, &a, unsent_vertices_.data(), count,
                                                  strokes_unsent_, &sent);
        s != CSC_OK)
      note(abi_error("cannot send the stroke", s));
    strokes_unsent_ = 0;
    unsent_vertices_.clear();
    dirty_ = true;   // submit sets the values to what the peers receive
    refresh_view();  // the counters the resubmission above reads
  }
}

bool SessionWorker::poll_events() {
  bool version_pending = false;
  for (;;) {
    csc_session_event event = CSC_SESSION_EVENT_INIT;
    int32_t has_event = 0;
    if (csc_session_poll(session_, &event, &has_event) != CSC_OK || !has_event) break;
    char id[32];
    std::snprintf(id, sizeof id, "%016llx", static_cast<unsigned long long>(event.peer));
    const std::string peer = std::string("peer ") + id;
    const std::string message = event.message ? event.message : "";
    switch (event.kind) {
      case CSC_EVENT_JOINED:
        local_view_.status = "live";
        break;
      case CSC_EVENT_VERSION:
        version_pending = true;
        break;
      case CSC_EVENT_PEER_JOINED:
        note(peer + " joined");
        break;
      case CSC_EVENT_PEER_EVASIVE:
        note(peer + " is silent");
        break;
      case CSC_EVENT_PEER_LEFT:
        note(peer + " left");
        break;
      case CSC_EVENT_PEER_LIVE:
        note(peer + " is back");
        break;
      case CSC_EVENT_MERGER_CHANGED:
        note(peer + " merges now");
        break;
      case CSC_EVENT_DROPPED:
        note("dropped a message: " + message);
        break;
      case CSC_EVENT_ERROR:
        local_view_.status = "network error";
        note("network error: " + message);
        break;
      default:
        break;
    }
    if (event.kind >= CSC_EVENT_PEER_JOINED && event.kind <= CSC_EVENT_MERGER_CHANGED)
      last_view_ = {};  // show a change of the peers at once
  }
  return version_pending;
}

// The library's lists are the truth (names, merger, versions, round trips, cursors).
void SessionWorker::refresh_view() {
  last_view_ = std::chrono::steady_clock::now();
  SessionView& v = local_view_;
  csc_session_get_stats(session_, &v.stats);
  v.id = csc_session_id(session_);
  v.version = csc_session_version(session_);
  v.invite = csc_session_invite(session_);
  csc_session_undo_depth(session_, &v.undo_depth, &v.redo_depth);
  uint32_t count = 0;
  v.peers.clear();
  if (csc_session_peer_count(session_, &count) == CSC_OK)
    for (uint32_t i = 0; i < count; ++i) {
      csc_peer_info info = CSC_PEER_INFO_INIT;
      if (csc_session_get_peer(session_, i, &info) != CSC_OK) continue;
      const auto state = info.state == CSC_PEER_LEFT      ? SessionView::PeerState::left
                         : info.state == CSC_PEER_EVASIVE ? SessionView::PeerState::evasive
                                                          : SessionView::PeerState::live;
      v.peers.push_back({info.id, state, info.name ? info.name : "", info.merger != 0, info.version,
                         info.latency_ms});
    }
  v.cursors.clear();
  if (csc_session_presence_count(session_, &count) == CSC_OK)
    for (uint32_t i = 0; i < count; ++i) {
      csc_presence p = CSC_PRESENCE_INIT;
      if (csc_session_get_presence(session_, i, &p) != CSC_OK || !p.visible ||
          p.age_ms > kStaleCursorMs)
        continue;
      presence_seen_.insert(p.peer);
      v.cursors.push_back({p.peer,
                           {p.position[0], p.position[1], p.position[2]},
                           p.radius,
                           p.active != 0,
                           {p.colour[0], p.colour[1], p.colour[2]}});
    }
  v.presence_seen = presence_seen_.size();
}

void SessionWorker::publish() {
  std::shared_ptr<MeshChanges> box;
  if (dirty_) {  // what the mirror has and the UI does not
    box = std::make_shared<MeshChanges>();
    const uint32_t stride = mirror_.stride();
    mirror_.differing_vertices(shown_, box->vertices);
    box->values.resize(box->vertices.size() * stride);
    for (size_t i = 0; i < box->vertices.size(); ++i)
      mirror_.read(box->vertices[i], &box->values[i * stride]);
    box->includes = done_;
    for (uint32_t v : box->vertices)
      if (block_differs(mirror_.positions, shown_.positions, 3, v, 1))
        box->normals.moved.push_back(v);
    normals_.compute(mirror_.positions.data(), box->normals);
    add_bvh_boxes(*box);
    dirty_ = false;
  }
  std::shared_ptr<std::vector<float>> colours;
  bool want = false;
  {
    std::lock_guard lock(mutex_);
    want = want_attribution_;
  }
  if (want && attribution_stale_) {
    colours = std::make_shared<std::vector<float>>(size_t{mirror_.vertex_count()} * 3);
    if (csc_session_attribution_colors(session_, colours->data(), mirror_.vertex_count()) != CSC_OK)
      colours.reset();
    attribution_stale_ = false;
  }
  std::lock_guard lock(mutex_);
  // The UI took an outbox since the inbox was drained: `shown_` lacks it, so this box, made
  // against `shown_`, could miss a vertex that box changed; it is made again after the drain.
  if (box && takes_ != takes_drained_) {
    box.reset();
    dirty_ = true;
  }
  if (box) {
    outbox_ = std::move(box);
    outbox_taken_ = false;
  }
  if (colours) attribution_ = std::move(colours);
  view_ = local_view_;
}

void SessionWorker::add_bvh_boxes(MeshChanges& box) {
  if (bvh_positions_.size() != mirror_.positions.size() || box.normals.moved.empty()) return;
  // Tight over the mirror first: every vertex it moved since the last refit (strokes, undo,
  // versions), block by block at memory speed as differing_vertices does.
  constexpr uint32_t kBlock = 64;
  const uint32_t n = mirror_.vertex_count();
  stale_.clear();
  for (uint32_t first = 0; first < n; first += kBlock) {
    const uint32_t count = std::min(kBlock, n - first);
    if (!block_differs(mirror_.positions, bvh_positions_, 3, first, count)) continue;
    for (uint32_t v = first; v < first + count; ++v)
      if (block_differs(mirror_.positions, bvh_positions_, 3, v, 1)) {
        stale_.push_back(v);
        std::copy_n(&mirror_.positions[3 * size_t{v}], 3, &bvh_positions_[3 * size_t{v}]);
      }
  }
  bvh_.refit_exactly(mirror_.positions, normals_.corners(), stale_);
  bvh_.boxes_around(box.normals.moved, box.bvh_nodes, box.bvh_boxes);
}

void SessionWorker::note(std::string message) {
  std::vector<std::string>& m = local_view_.messages;
  m.push_back(std::move(message));
  if (m.size() > kMaxMessages) m.erase(m.begin());
}

// Leaving: what the artist handed last is sent first, then the others are told.
void SessionWorker::finish() {
  drain_inbox();
  sync();
  csc_session_leave(session_);
  csc_session_destroy(session_);
  session_ = nullptr;
}
