#include "session_link.h"

namespace {

constexpr size_t kMaxNotes = 4;

}  // namespace

void SessionLink::host(MeshContent content, TriangleBvh bvh, PeerSettings settings) {
  worker_ =
      std::make_unique<SessionWorker>(std::move(content), std::move(bvh), std::move(settings));
  joined_ = true;
  starting_host_ = true;
  view_ = worker_->view();
  status_ = view_.status;
}

int SessionLink::poll_host(std::string& error) {
  if (!starting_host()) return 0;
  const int state = worker_->state(error);
  if (state != 0) starting_host_ = false;
  if (state < 0) {
    worker_.reset();
    joined_ = false;
    status_ = "not in a session";
    note(error);
  }
  if (state > 0) poll_events();  // the invite
  return state;
}

void SessionLink::begin_join(const std::string& invite, PeerSettings settings) {
  worker_ = std::make_unique<SessionWorker>(invite, std::move(settings));
  joined_ = false;
  adopting_ = false;
  status_ = "joining...";
}

int SessionLink::poll_join(std::string& error) {
  if (!worker_ || joined_ || adopting_) return 0;
  const int state = worker_->state(error);
  if (state < 0) {
    worker_.reset();
    status_ = "not in a session";
    note(error);
  }
  if (state > 0) {
    adopting_ = true;
    status_ = "preparing the session's mesh...";
  }
  return state;
}

void SessionLink::adopted() {
  if (!worker_ || !adopting_) return;
  adopting_ = false;
  joined_ = true;
  status_ = "joined";
}

void SessionLink::poll_events() {
  if (!active()) return;
  view_ = worker_->view();
  status_ = view_.status;
  messages_ = notes_;
  messages_.insert(messages_.end(), view_.messages.begin(), view_.messages.end());
}

namespace {

// FNV-1a over the bytes of each value added: enough to notice a change between two frames.
class LookDigest {
 public:
  template <typename T>
  void add(const T& value) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(&value);
    for (size_t i = 0; i < sizeof value; ++i) h_ = (h_ ^ bytes[i]) * 0x100000001b3ull;
  }
  void add(const std::string& text) {
    for (const char c : text) add(c);
    add(text.size());
  }
  template <typename T, typename... More>
  void add(const T& first, const More&... more) {
    add(first);
    add(more...);
  }
  uint64_t value() const { return h_; }

 private:
  uint64_t h_ = 0xcbf29ce484222325ull;
};

}  // namespace

uint64_t SessionLink::look() const {
  LookDigest d;
  d.add(joined_, view_.id, view_.version, status_, messages_.size());
  if (!messages_.empty()) d.add(messages_.back());
  const csc_session_stats& s = view_.stats;
  for (const uint64_t counter : {s.merger, s.epoch, uint64_t{s.members}, s.strokes_submitted,
                                 s.strokes_acknowledged, s.merges})
    d.add(counter);
  for (const Peer& p : view_.peers) d.add(p.id, p.state, p.name, p.merger, p.version);
  for (const Cursor& c : view_.cursors) d.add(c.peer, c.position, c.radius, c.active, c.colour);
  d.add(view_.undo_depth, view_.redo_depth);
  return d.value();
}

void SessionLink::set_presence(const csc_presence& presence) {
  if (active()) worker_->set_presence(presence);
}

void SessionLink::hand_bvh(TriangleBvh bvh, std::vector<float> positions) {
  if (worker_) worker_->hand_bvh(std::move(bvh), std::move(positions));
}

void SessionLink::hand_stroke(const std::vector<uint32_t>& vertices,
                              const std::vector<float>& before, const std::vector<float>& after) {
  if (active()) worker_->hand_stroke(vertices, before, after);
}

void SessionLink::request_step(bool redo) {
  if (active()) worker_->request_step(redo);
}

std::shared_ptr<const MeshChanges> SessionLink::take_changes() {
  return active() ? worker_->take_changes() : nullptr;
}

void SessionLink::settle(int timeout_ms) {
  if (active()) worker_->settle(timeout_ms);
}

void SessionLink::leave() {
  if (!worker_) return;
  const bool was_active = joined_;
  worker_.reset();  // the worker sends what it has, tells the others and stops
  joined_ = false;
  adopting_ = false;
  view_ = {};
  if (was_active) {
    status_ = "left the session";
    note("left the session; the mesh is yours to keep");
  }
}

std::shared_ptr<const std::vector<float>> SessionLink::attribution_colours() {
  return active() ? worker_->attribution_colours() : nullptr;
}

void SessionLink::note(std::string message) {
  notes_.push_back(std::move(message));
  if (notes_.size() > kMaxNotes) notes_.erase(notes_.begin());
  messages_ = notes_;
}
