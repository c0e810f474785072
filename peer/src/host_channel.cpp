#include "host_channel.h"

namespace csculpt::peer {

void HostChannel::post(Command c) {
  std::lock_guard lock(mutex_);
  commands_.push_back(std::move(c));
}

std::deque<Command> HostChannel::take_commands() {
  std::deque<Command> out;
  std::lock_guard lock(mutex_);
  out.swap(commands_);
  return out;
}

bool HostChannel::set_presence(const Presence& p) {
  std::lock_guard lock(mutex_);
  if (presence_set_ && own_presence_ == p) return false;  // hosts may set it every frame
  own_presence_ = p;
  presence_set_ = true;
  const bool wake = !presence_changed_;
  presence_changed_ = true;
  return wake;
}

std::pair<bool, bool> HostChannel::presence_state() const {
  std::lock_guard lock(mutex_);
  return {presence_changed_, presence_set_};
}

Presence HostChannel::take_presence() {
  std::lock_guard lock(mutex_);
  presence_changed_ = false;
  return own_presence_;
}

std::map<PeerId, ReceivedPresence> HostChannel::presence() const {
  std::lock_guard lock(mutex_);
  return presence_.latest();
}

void HostChannel::set_peers(std::vector<PeerInfo> peers) {
  std::lock_guard lock(mutex_);
  peers_ = std::move(peers);
}

std::vector<PeerInfo> HostChannel::peers() const {
  std::lock_guard lock(mutex_);
  return peers_;
}

std::vector<PeerId> HostChannel::attribution_peers() const {
  std::lock_guard lock(mutex_);
  std::vector<PeerId> out;
  for (const auto& [peer, values] : attribution_) out.push_back(peer);
  return out;
}

std::vector<HostItem> HostChannel::take_items() {
  std::lock_guard lock(mutex_);
  std::vector<HostItem> out(std::make_move_iterator(items_.begin()),
                            std::make_move_iterator(items_.end()));
  items_.clear();
  return out;
}

void HostChannel::push_event(Event e) {
  std::lock_guard lock(mutex_);
  if (events_.size() >= kMaxEvents) events_.pop_front();
  events_.push_back(std::move(e));
}

std::vector<Event> HostChannel::take_events() {
  std::lock_guard lock(mutex_);
  std::vector<Event> out(events_.begin(), events_.end());
  events_.clear();
  return out;
}

SessionStats HostChannel::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

std::vector<std::pair<PeerId, std::vector<float>>> HostChannel::attribution() const {
  std::lock_guard lock(mutex_);
  return {attribution_.begin(), attribution_.end()};
}

void HostChannel::set_frame_and_attribution(const MergeFrame& frame,
                                            std::map<PeerId, std::vector<float>> attribution) {
  std::lock_guard lock(mutex_);
  frame_ = frame;
  attribution_ = std::move(attribution);
}

Snapshot HostChannel::frame_and_attribution() const {
  Snapshot snap;
  std::lock_guard lock(mutex_);
  snap.frame = frame_;
  snap.attribution = attribution_;
  return snap;
}

Bytes HostChannel::encode_snapshot_of(const Mesh& mesh, const ChainHistory& chains) const {
  const Snapshot s = frame_and_attribution();
  return encode_snapshot(mesh, s.frame, s.attribution, chains);
}

Snapshot HostChannel::snapshot_of(const Mesh& mesh, const ChainHistory& chains) const {
  Snapshot s = frame_and_attribution();
  s.mesh = mesh;
  s.chains = chains;
  return s;
}

void HostChannel::set_hierarchy(std::shared_ptr<const Hierarchy> hierarchy) {
  std::lock_guard lock(mutex_);
  hierarchy_ = std::move(hierarchy);
}

std::shared_ptr<const Hierarchy> HostChannel::hierarchy() const {
  std::lock_guard lock(mutex_);
  return hierarchy_;
}

void HostChannel::set_frame(const MergeFrame& frame) {
  std::lock_guard lock(mutex_);
  frame_ = frame;
}

MergeFrame HostChannel::frame() const {
  std::lock_guard lock(mutex_);
  return frame_;
}

void HostChannel::set_joined() {
  std::lock_guard lock(mutex_);
  joined_ = true;
  joined_cv_.notify_all();
}

bool HostChannel::wait_joined(Millis timeout) {
  std::unique_lock lock(mutex_);
  return joined_cv_.wait_for(lock, timeout, [&] { return joined_; });
}

}  // namespace csculpt::peer
