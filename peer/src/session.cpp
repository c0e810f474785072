// Serverless session: the network thread (Node) and the host side (Session::Impl).
#include "csculpt/peer/session.h"

#include <zmq.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <thread>
#include <zmq.hpp>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/folds.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "session_generated.h"

namespace csculpt::peer {
namespace {

namespace fb = csculpt::session;
constexpr std::uint32_t kProtocol = 1;
constexpr std::size_t kHistory = 256;      // versions kept to answer fetches
constexpr std::size_t kMaxEvents = 10000;  // host event queue bound
constexpr const char* kZapEndpoint = "inproc://zeromq.zap.01";

// ---- small helpers -----------------------------------------------------------------------

/// The session's wire options: the position tolerance is relative to the session's fixed
/// frame (the first mesh's bounding-box diagonal), not recomputed from each version's mesh.
EncodeOptions wire_options_for(const EncodeOptions& wire, const MergeFrame& frame) {
  EncodeOptions o = wire;
  if (o.position_scale == 0) o.position_scale = frame.scale;
  return o;
}

std::uint64_t mix64(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  h *= 0xff51afd7ed558ccdull;
  return h ^ (h >> 32);
}

std::uint64_t hash_bytes(std::uint64_t h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t w;
    std::memcpy(&w, p + i, 8);
    h = mix64(h, w);
  }
  std::uint64_t tail = n;
  for (std::size_t k = 0; i < n; ++i, ++k) tail ^= std::uint64_t{p[i]} << (8 * (k % 7 + 1));
  return mix64(h, tail);
}

std::string hex(const std::uint8_t* p, std::size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    s += digits[p[i] >> 4];
    s += digits[p[i] & 15];
  }
  return s;
}

bool unhex(std::string_view s, std::uint8_t* out, std::size_t n) {
  if (s.size() != 2 * n) return false;
  auto val = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const int hi = val(s[2 * i]), lo = val(s[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return true;
}

std::string z85(const std::array<std::uint8_t, 32>& key) {
  char out[41];
  zmq_z85_encode(out, key.data(), key.size());
  return out;
}

std::array<std::uint8_t, 32> public_key(const std::array<std::uint8_t, 32>& secret) {
  char pub[41];
  if (zmq_curve_public(pub, z85(secret).c_str()) != 0)
    throw IoError("CURVE is not available in this libzmq");
  std::array<std::uint8_t, 32> out{};
  zmq_z85_decode(out.data(), pub);
  return out;
}

std::uint64_t random_u64() {
  std::random_device rd;
  return (std::uint64_t{rd()} << 32) ^ rd();
}

void put_varint(std::vector<std::uint8_t>& out, std::uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

/// Every vertex a diff touches (positions or any channel), increasing.
std::vector<std::uint32_t> touched(const Diff& d) {
  std::vector<std::uint32_t> all(d.positions.indices);
  for (const ChannelDiff& c : d.channels) {
    std::vector<std::uint32_t> merged;
    merged.reserve(all.size() + c.change.indices.size());
    std::set_union(all.begin(), all.end(), c.change.indices.begin(), c.change.indices.end(),
                   std::back_inserter(merged));
    all.swap(merged);
  }
  return all;
}

/// How much a diff changes each vertex it touches (position displacement in the frame's
/// units plus channel changes), for attribution.
std::vector<float> change_amounts(const Diff& d, const Mesh& base,
                                  std::span<const std::uint32_t> vertices, float scale) {
  std::vector<float> amount(vertices.size(), 0.f);
  auto slot = [&](std::uint32_t v) {
    return static_cast<std::size_t>(std::lower_bound(vertices.begin(), vertices.end(), v) -
                                    vertices.begin());
  };
  for (std::size_t i = 0; i < d.positions.indices.size(); ++i) {
    const std::uint32_t v = d.positions.indices[i];
    const Vec3f& b = base.positions[v];
    const float* e = d.positions.values.data() + 3 * i;
    const float dx = e[0] - b.x, dy = e[1] - b.y, dz = e[2] - b.z;
    amount[slot(v)] += std::sqrt(dx * dx + dy * dy + dz * dz) / scale;
  }
  for (const ChannelDiff& c : d.channels) {
    const int k = base.find_channel(c.desc.name);
    if (k < 0) continue;
    const auto& values = base.channels[static_cast<std::size_t>(k)].values;
    const std::uint32_t w = c.desc.width;
    for (std::size_t i = 0; i < c.change.indices.size(); ++i) {
      const std::uint32_t v = c.change.indices[i];
      float sum = 0;
      for (std::uint32_t j = 0; j < w; ++j)
        sum += std::abs(c.change.values[i * w + j] - values[std::size_t{v} * w + j]);
      amount[slot(v)] += sum;
    }
  }
  return amount;
}

// ---- mesh snapshots --------------------------------------------------------------------

struct Snapshot {
  Mesh mesh;
  MergeFrame frame;
  std::map<PeerId, std::vector<float>> attribution;
};

std::vector<std::uint8_t> encode_snapshot(const Mesh& mesh, const MergeFrame& frame,
                                          const std::map<PeerId, std::vector<float>>& attrib) {
  flatbuffers::FlatBufferBuilder b(mesh.vertex_count() * 16 + mesh.face_count() * 12 + 1024);
  const auto positions = b.CreateVector(reinterpret_cast<const float*>(mesh.positions.data()),
                                        mesh.positions.size() * 3);
  const auto triangles = b.CreateVector(
      reinterpret_cast<const std::uint32_t*>(mesh.triangles.data()), mesh.triangles.size() * 3);
  std::vector<flatbuffers::Offset<fb::ChannelData>> channels;
  for (const Channel& c : mesh.channels)
    channels.push_back(fb::CreateChannelData(b, b.CreateString(c.desc.name), c.desc.width,
                                             static_cast<std::uint32_t>(c.desc.linearisation),
                                             c.desc.min_value, c.desc.max_value,
                                             b.CreateVector(c.values)));
  const auto channel_vector = b.CreateVector(channels);
  const float center[3] = {frame.center.x, frame.center.y, frame.center.z};
  const auto frame_center = b.CreateVector(center, 3);
  std::vector<std::uint64_t> peers;
  std::vector<float> values;
  for (const auto& [peer, v] : attrib) {
    peers.push_back(peer);
    values.insert(values.end(), v.begin(), v.end());
  }
  const auto peer_vector = b.CreateVector(peers);
  const auto value_vector = b.CreateVector(values);
  b.Finish(fb::CreateMeshSnapshot(b, positions, triangles, channel_vector, frame_center,
                                  frame.scale, peer_vector, value_vector));
  return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
}

Snapshot decode_snapshot(std::span<const std::uint8_t> bytes) {
  flatbuffers::Verifier verifier(bytes.data(), bytes.size(), 8, 1000000, bytes.size());
  if (!verifier.VerifyBuffer<fb::MeshSnapshot>(nullptr))
    throw InvalidInput("snapshot failed FlatBuffers verification");
  const auto* s = flatbuffers::GetRoot<fb::MeshSnapshot>(bytes.data());
  Snapshot out;
  Mesh& m = out.mesh;
  if (!s->positions() || s->positions()->size() % 3 || !s->triangles() ||
      s->triangles()->size() % 3)
    throw InvalidInput("snapshot positions or triangles missing or not in threes");
  m.positions.resize(s->positions()->size() / 3);
  std::memcpy(static_cast<void*>(m.positions.data()), s->positions()->data(),
              s->positions()->size() * sizeof(float));
  m.triangles.resize(s->triangles()->size() / 3);
  std::memcpy(static_cast<void*>(m.triangles.data()), s->triangles()->data(),
              s->triangles()->size() * sizeof(std::uint32_t));
  if (s->channels()) {
    for (const fb::ChannelData* c : *s->channels()) {
      if (c->width() < 1 || c->width() > 4 || c->linearisation() > 2)
        throw InvalidInput("snapshot channel with width outside 1..4 or unknown linearisation");
      Channel ch;
      ch.desc =
          ChannelDesc{c->name()->str(), c->width(), static_cast<Linearisation>(c->linearisation()),
                      c->min_value(), c->max_value()};
      if (c->values()) ch.values.assign(c->values()->begin(), c->values()->end());
      m.channels.push_back(std::move(ch));
    }
  }
  validate(m, "snapshot");
  if (!s->frame_center() || s->frame_center()->size() != 3 || !(s->frame_scale() > 0) ||
      !std::isfinite(s->frame_scale()))
    throw InvalidInput("snapshot frame missing or invalid");
  out.frame.center = {s->frame_center()->Get(0), s->frame_center()->Get(1),
                      s->frame_center()->Get(2)};
  out.frame.scale = s->frame_scale();
  const std::size_t n = m.vertex_count();
  if (s->attribution_peers()) {
    const std::size_t peers = s->attribution_peers()->size();
    if (!s->attribution() || s->attribution()->size() != peers * n)
      throw InvalidInput("snapshot attribution has the wrong size");
    for (std::size_t k = 0; k < peers; ++k)
      out.attribution[s->attribution_peers()->Get(static_cast<flatbuffers::uoffset_t>(k))].assign(
          s->attribution()->data() + k * n, s->attribution()->data() + (k + 1) * n);
  }
  return out;
}

}  // namespace

// ---- invite and digest -------------------------------------------------------------------

std::string format_invite(const Invite& invite) {
  std::uint8_t session[8];
  for (int i = 0; i < 8; ++i)
    session[i] = static_cast<std::uint8_t>(invite.session >> (56 - 8 * i));
  return "csculpt1:" + hex(session, 8) + hex(invite.server_secret.data(), 32) +
         hex(invite.client_secret.data(), 32) + "@" + invite.endpoint;
}

Invite parse_invite(const std::string& text) {
  const std::string prefix = "csculpt1:";
  if (text.rfind(prefix, 0) != 0) throw InvalidInput("invite does not start with '" + prefix + "'");
  const std::size_t at = text.find('@');
  if (at == std::string::npos) throw InvalidInput("invite has no '@<endpoint>'");
  const std::string_view keys(text.data() + prefix.size(), at - prefix.size());
  if (keys.size() != 144)
    throw InvalidInput("invite key part has " + std::to_string(keys.size()) +
                       " hex digits, 144 expected");
  Invite inv;
  std::uint8_t session[8];
  if (!unhex(keys.substr(0, 16), session, 8) ||
      !unhex(keys.substr(16, 64), inv.server_secret.data(), 32) ||
      !unhex(keys.substr(80, 64), inv.client_secret.data(), 32))
    throw InvalidInput("invite key part is not hexadecimal");
  for (int i = 0; i < 8; ++i) inv.session = (inv.session << 8) | session[i];
  inv.endpoint = text.substr(at + 1);
  if (inv.endpoint.rfind("tcp://", 0) != 0 && inv.endpoint.rfind("ipc://", 0) != 0 &&
      inv.endpoint.rfind("inproc://", 0) != 0)
    throw InvalidInput("invite endpoint '" + inv.endpoint + "' is not tcp://, ipc:// or inproc://");
  return inv;
}

std::uint64_t mesh_digest(const Mesh& mesh) {
  std::uint64_t h = 0x6a09e667f3bcc908ull;
  h = hash_bytes(h, mesh.positions.data(), mesh.positions.size() * sizeof(Vec3f));
  for (const Channel& c : mesh.channels) {
    h = hash_bytes(h, c.desc.name.data(), c.desc.name.size());
    h = hash_bytes(h, c.values.data(), c.values.size() * sizeof(float));
  }
  return h;
}

std::vector<float> attribution_colours(
    const std::vector<std::pair<PeerId, std::vector<float>>>& attribution,
    std::size_t vertex_count) {
  // green, blue, red, magenta, orange, teal, yellow, violet: green + blue mix to cyan (Fig. 1)
  static const float hues[8][3] = {{0.1f, 0.85f, 0.2f}, {0.15f, 0.35f, 0.95f}, {0.9f, 0.15f, 0.1f},
                                   {0.85f, 0.2f, 0.8f}, {0.95f, 0.55f, 0.1f},  {0.1f, 0.6f, 0.6f},
                                   {0.9f, 0.85f, 0.1f}, {0.5f, 0.3f, 0.85f}};
  std::vector<float> rgb(vertex_count * 3, 0.82f);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    float total = 0, peak = 0;
    for (const auto& [peer, amounts] : attribution) {
      total += amounts[v];
      peak = std::max(peak, amounts[v]);
    }
    if (!(total > 0)) continue;
    float mix[3] = {0, 0, 0};
    for (std::size_t k = 0; k < attribution.size(); ++k) {
      const float share = attribution[k].second[v] / peak;  // both at full: additive mix
      for (int j = 0; j < 3; ++j) mix[j] += share * hues[k % 8][j];
    }
    for (int j = 0; j < 3; ++j) rgb[3 * v + j] = std::min(1.f, mix[j]);
  }
  return rgb;
}

// ---- the network thread --------------------------------------------------------------------

namespace {

/// What the network thread hands to the host: a merged version, or a whole snapshot.
struct HostItem {
  bool snapshot = false;
  std::uint64_t version = 0;
  Diff merged;                                              // version: from version - 1
  std::vector<std::pair<PeerId, std::uint64_t>> merged_by;  // peer, sequence
  std::shared_ptr<const Snapshot> snap;                     // snapshot
};

struct Command {
  enum class Kind { none, submit, leave } kind = Kind::none;
  std::uint64_t base_version = 0;
  std::vector<std::uint8_t> bytes;
  std::uint32_t strokes = 0;
};

struct PendingSubmit {
  std::uint64_t sequence = 0;
  std::uint32_t strokes = 0;
  Diff diff;
};

struct VersionRecord {
  std::uint64_t version = 0;
  std::uint64_t parent_chain = 0;
  std::uint64_t chain = 0;
  std::vector<std::uint8_t> diff_bytes;
  std::vector<std::pair<PeerId, std::uint64_t>> merged_by;
  std::vector<std::uint32_t> merged_strokes;
  float merge_ms = 0;
  std::uint32_t conflicting = 0;
  // contributions, as sent
  std::vector<PeerId> contributors;
  std::vector<std::vector<std::uint8_t>> contribution_gaps;
  std::vector<std::vector<std::uint8_t>> contribution_amounts;
  std::vector<float> contribution_scales;
};

}  // namespace

class Node {
 public:
  Node(const Invite& invite, bool creator, const SessionOptions& options)
      : options_(options),
        invite_(invite),
        self_(options.id ? options.id : random_u64() | 1),
        membership_(self_, "", options.membership),
        election_(self_) {
    server_public_ = public_key(invite.server_secret);
    client_public_ = public_key(invite.client_secret);
    // ZAP handler first: CURVE sockets ask it about every connecting client.
    zap_ = zmq::socket_t(ctx_, zmq::socket_type::rep);
    zap_.bind(kZapEndpoint);
    router_ = zmq::socket_t(ctx_, zmq::socket_type::router);
    router_.set(zmq::sockopt::curve_server, 1);
    router_.set(zmq::sockopt::curve_secretkey, zmq::const_buffer(invite.server_secret.data(), 32));
    router_.set(zmq::sockopt::zap_domain, "csculpt");
    router_.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(options.max_message_bytes));
    router_.set(zmq::sockopt::linger, 0);
    router_.set(zmq::sockopt::rcvhwm, 100000);
    router_.bind(options.bind);
    endpoint_ = router_.get(zmq::sockopt::last_endpoint);
    membership_ = Membership(self_, endpoint_, options.membership);
    if (creator) invite_.endpoint = endpoint_;
  }

  // ---- set-up before the thread starts -----------------------------------------------
  void start_as_creator(const Mesh& mesh) {
    base_ = mesh;
    frame_ = MergeFrame::fit(base_.positions);
    build_merge_state();
    chain_ = 0x243f6a8885a308d3ull;
    joined_ = true;
    push_event({EventKind::joined, self_, 0, 0, ""});
  }

  void start_as_joiner() {
    connect(invite_.endpoint);
    joining_endpoint_ = invite_.endpoint;
  }

  void run() {
    thread_ = std::thread([this] { loop(); });
  }

  void stop() {
    {
      std::lock_guard lock(mutex_);
      Command leave;
      leave.kind = Command::Kind::leave;
      commands_.push_back(std::move(leave));
    }
    if (thread_.joinable()) thread_.join();
  }

  ~Node() { stop(); }

  // ---- host-facing (any thread) ----------------------------------------------------------
  void command(Command c) {
    std::lock_guard lock(mutex_);
    commands_.push_back(std::move(c));
  }
  std::vector<HostItem> take_items() {
    std::lock_guard lock(mutex_);
    std::vector<HostItem> out(std::make_move_iterator(items_.begin()),
                              std::make_move_iterator(items_.end()));
    items_.clear();
    return out;
  }
  std::vector<Event> take_events() {
    std::lock_guard lock(mutex_);
    std::vector<Event> out(events_.begin(), events_.end());
    events_.clear();
    return out;
  }
  SessionStats stats() const {
    std::lock_guard lock(mutex_);
    return stats_;
  }
  std::vector<std::pair<PeerId, std::vector<float>>> attribution() const {
    std::lock_guard lock(mutex_);
    return {attribution_.begin(), attribution_.end()};
  }
  bool wait_joined(Millis timeout) {
    std::unique_lock lock(mutex_);
    return joined_cv_.wait_for(lock, timeout, [&] { return joined_flag_; });
  }
  PeerId id() const { return self_; }
  const std::string& endpoint() const { return endpoint_; }
  std::string invite_text() const {
    Invite inv = invite_;
    inv.endpoint = endpoint_;
    return format_invite(inv);
  }
  /// The merge state a joiner needs on the host side (valid once joined).
  std::shared_ptr<const Hierarchy> hierarchy() const {
    std::lock_guard lock(mutex_);
    return hierarchy_;
  }
  MergeFrame frame() const {
    std::lock_guard lock(mutex_);
    return frame_;
  }

 private:
  // ---- sockets ------------------------------------------------------------------------------
  zmq::socket_t& connect(const std::string& endpoint) {
    auto it = dealers_.find(endpoint);
    if (it != dealers_.end()) return it->second;
    zmq::socket_t s(ctx_, zmq::socket_type::dealer);
    s.set(zmq::sockopt::curve_serverkey, zmq::const_buffer(server_public_.data(), 32));
    s.set(zmq::sockopt::curve_publickey, zmq::const_buffer(client_public_.data(), 32));
    s.set(zmq::sockopt::curve_secretkey, zmq::const_buffer(invite_.client_secret.data(), 32));
    s.set(zmq::sockopt::linger, 0);
    s.set(zmq::sockopt::sndhwm, 10000);
    // The receiver checks every envelope's sender against this: a member cannot speak for
    // another (ROUTER refuses a second connection with a routing id already in use).
    const std::array<std::uint8_t, 9> rid = routing_id(self_);
    s.set(zmq::sockopt::routing_id, zmq::const_buffer(rid.data(), rid.size()));
    s.set(zmq::sockopt::maxmsgsize, static_cast<std::int64_t>(options_.max_message_bytes));
    s.connect(endpoint);
    return dealers_.emplace(endpoint, std::move(s)).first->second;
  }

  /// 'P' and the id's 8 bytes (a routing id may not start with a zero byte).
  static std::array<std::uint8_t, 9> routing_id(PeerId id) {
    std::array<std::uint8_t, 9> r{'P'};
    for (int i = 0; i < 8; ++i) r[1 + i] = static_cast<std::uint8_t>(id >> (8 * i));
    return r;
  }

  template <class Fill>
  std::vector<std::uint8_t> envelope(fb::Body type, Fill&& fill) {
    flatbuffers::FlatBufferBuilder b(256);
    const flatbuffers::Offset<void> body = fill(b);
    fb::EnvelopeBuilder e(b);
    e.add_session(invite_.session);
    e.add_sender(self_);
    e.add_epoch(election_.epoch());
    e.add_body_type(type);
    e.add_body(body);
    fb::FinishEnvelopeBuffer(b, e.Finish());
    return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
  }

  void send_to(const std::string& endpoint, const std::vector<std::uint8_t>& bytes) {
    zmq::socket_t& s = connect(endpoint);
    // Never block the loop on a slow or dead peer: past the high-water mark the message is
    // dropped (the protocol recovers: fetches, resends, snapshots).
    (void)s.send(zmq::buffer(bytes), zmq::send_flags::dontwait);
  }

  void send_to_peer(PeerId peer, const std::vector<std::uint8_t>& bytes) {
    const auto& m = membership_.members();
    if (auto it = m.find(peer); it != m.end() && !it->second.endpoint.empty())
      send_to(it->second.endpoint, bytes);
  }

  void broadcast(const std::vector<std::uint8_t>& bytes) {
    for (const Member* m : membership_.others())
      if (!m->endpoint.empty()) send_to(m->endpoint, bytes);
  }

  // ---- events and stats ---------------------------------------------------------------------
  void push_event(Event e) {
    std::lock_guard lock(mutex_);
    if (events_.size() >= kMaxEvents) events_.pop_front();
    events_.push_back(std::move(e));
  }

  void dropped(const std::string& why) {
    {
      std::lock_guard lock(mutex_);
      ++stats_.messages_dropped;
    }
    push_event({EventKind::dropped, 0, version_, election_.epoch(), why});
  }

  void publish_stats() {
    std::lock_guard lock(mutex_);
    stats_.id = self_;
    stats_.version = version_;
    stats_.epoch = election_.epoch();
    stats_.merger = election_.merger().value_or(0);
    stats_.members = static_cast<std::uint32_t>(membership_.members().size());
  }

  // ---- the loop -------------------------------------------------------------------------------
  void loop() {
    auto next_heartbeat = Clock::now();
    auto next_merge = Clock::now() + options_.sync;
    bool leaving = false;
    while (!leaving) {
      zmq::pollitem_t items[] = {{router_.handle(), 0, ZMQ_POLLIN, 0},
                                 {zap_.handle(), 0, ZMQ_POLLIN, 0}};
      zmq::poll(items, 2, std::chrono::milliseconds(2));
      if (items[1].revents & ZMQ_POLLIN) serve_zap();
      for (int i = 0; i < 1000 && (items[0].revents & ZMQ_POLLIN); ++i) {
        zmq::message_t routing, payload;
        if (!router_.recv(routing, zmq::recv_flags::dontwait)) break;
        if (!routing.more()) continue;
        if (!router_.recv(payload, zmq::recv_flags::dontwait)) break;
        while (payload.more()) {  // a well-behaved peer sends one frame
          zmq::message_t extra;
          if (!router_.recv(extra, zmq::recv_flags::dontwait)) break;
        }
        // Stamped when handled, not when the poll returned: a message handled after a long
        // step (a snapshot's hierarchy build, a large merge) is recent, not stale.
        handle(routing, payload, Clock::now());
      }
      std::deque<Command> commands;
      {
        std::lock_guard lock(mutex_);
        commands.swap(commands_);
      }
      for (Command& c : commands) {
        if (c.kind == Command::Kind::leave) {
          leaving = true;
          break;
        }
        own_submit_ = std::move(c);
        send_own_submit();
      }
      if (leaving) break;
      const auto now = Clock::now();
      if (now >= next_heartbeat) {
        next_heartbeat = now + options_.membership.heartbeat;
        heartbeat(now);
      }
      if (election_.is_merger() && now >= next_merge) {
        next_merge = now + options_.sync;
        merge_pending();
      }
      publish_stats();
    }
    if (joined_)
      broadcast(envelope(fb::Body::Leave, [](auto& b) { return fb::CreateLeave(b).Union(); }));
  }

  void serve_zap() {
    std::vector<zmq::message_t> frames;
    while (true) {
      zmq::message_t f;
      if (!zap_.recv(f, zmq::recv_flags::dontwait)) break;
      const bool more = f.more();
      frames.push_back(std::move(f));
      if (!more) break;
    }
    if (frames.size() < 6) return;
    const std::string mechanism = frames[5].to_string();
    const bool ok = mechanism == "CURVE" && frames.size() >= 7 && frames[6].size() == 32 &&
                    std::memcmp(frames[6].data(), client_public_.data(), 32) == 0;
    if (!ok) {
      std::lock_guard lock(mutex_);
      ++stats_.auth_rejected;
    }
    const std::string reply[6] = {"1.0",
                                  frames[1].to_string(),
                                  ok ? "200" : "400",
                                  ok ? "OK" : "not a member of this session",
                                  "",
                                  ""};
    for (int i = 0; i < 6; ++i)
      zap_.send(zmq::buffer(reply[i]), i < 5 ? zmq::send_flags::sndmore : zmq::send_flags::none);
  }

  // ---- inbound -------------------------------------------------------------------------------
  void handle(const zmq::message_t& routing, const zmq::message_t& payload, Clock::time_point now) {
    {
      std::lock_guard lock(mutex_);
      ++stats_.messages_received;
      stats_.bytes_received += payload.size();
    }
    // FlatBuffers reads scalars in place: a message ZeroMQ hands over at an address not aligned
    // for 8-byte fields is copied into aligned storage first.
    const auto* data = static_cast<const std::uint8_t*>(payload.data());
    if (reinterpret_cast<std::uintptr_t>(data) % alignof(std::uint64_t) != 0) {
      inbound_.resize((payload.size() + 7) / 8);
      std::memcpy(inbound_.data(), data, payload.size());
      data = reinterpret_cast<const std::uint8_t*>(inbound_.data());
    }
    if (payload.size() < 8 || !fb::EnvelopeBufferHasIdentifier(data))
      return dropped("message is not a cSculpt session envelope");
    flatbuffers::Verifier verifier(data, payload.size(), 16, 10000);
    if (!fb::VerifyEnvelopeBuffer(verifier))
      return dropped("message failed FlatBuffers verification");
    const fb::Envelope* env = fb::GetEnvelope(data);
    if (env->session() != invite_.session) return dropped("message of another session");
    const PeerId sender = env->sender();
    const std::array<std::uint8_t, 9> rid = routing_id(sender);
    if (sender == self_ || sender == 0 || routing.size() != rid.size() ||
        std::memcmp(routing.data(), rid.data(), rid.size()) != 0)
      return dropped("message whose sender id does not match its connection");
    try {
      switch (env->body_type()) {
        case fb::Body::Hello:
          return on_hello(*env, *env->body_as_Hello(), now);
        case fb::Body::Heartbeat:
          return on_heartbeat(*env, *env->body_as_Heartbeat(), now);
        case fb::Body::Leave:
          return on_leave(sender);
        case fb::Body::Elected:
          heard(sender, now);
          return on_elected(*env, env->body_as_Elected()->merger());
        case fb::Body::Submit:
          heard(sender, now);
          return on_submit(*env, *env->body_as_Submit());
        case fb::Body::Version:
          heard(sender, now);
          return on_version(*env, *env->body_as_Version());
        case fb::Body::Fetch:
          heard(sender, now);
          return on_fetch(sender, env->body_as_Fetch()->after());
        case fb::Body::SnapshotRequest:
          heard(sender, now);
          return send_snapshot(sender);
        case fb::Body::SnapshotChunk:
          return on_snapshot_chunk(*env->body_as_SnapshotChunk());
        default:
          return dropped("message of unknown kind " +
                         std::to_string(static_cast<int>(env->body_type())));
      }
    } catch (const InvalidInput& e) {
      dropped(e.what());
    }
  }

  /// Any verified message is a sign of life from a member; a sender we do not know yet is
  /// added by its hello (which carries its endpoint), not here.
  void heard(PeerId peer, Clock::time_point now) {
    if (membership_.contains(peer)) membership_.heard(peer, "", now);
  }

  void on_hello(const fb::Envelope& env, const fb::Hello& hello, Clock::time_point now) {
    if (hello.protocol() != kProtocol)
      return dropped("hello with protocol " + std::to_string(hello.protocol()));
    if (!hello.endpoint() || hello.endpoint()->size() == 0 || hello.endpoint()->size() > 256)
      return dropped("hello without a usable endpoint");
    const PeerId peer = env.sender();
    const std::string endpoint = hello.endpoint()->str();
    if (membership_.heard(peer, endpoint, now))
      member_joined(peer, endpoint);
    else
      connect(endpoint);
    if (hello.wants_snapshot()) {
      if (!joined_) return;  // cannot serve yet; the joiner retries with another member
      send_heartbeat_to(endpoint);
      send_snapshot(peer);
    }
  }

  void member_joined(PeerId peer, const std::string& endpoint) {
    connect(endpoint);
    // Introduce ourselves: the newcomer learns our endpoint and that we are alive.
    send_to(endpoint, hello(false));
    push_event({EventKind::peer_joined, peer, version_, election_.epoch(), endpoint});
  }

  std::vector<std::uint8_t> hello(bool wants_snapshot) {
    return envelope(fb::Body::Hello, [&](auto& b) {
      return fb::CreateHello(b, kProtocol, b.CreateString(endpoint_), b.CreateString(options_.name),
                             wants_snapshot)
          .Union();
    });
  }

  void on_heartbeat(const fb::Envelope& env, const fb::Heartbeat& hb, Clock::time_point now) {
    const PeerId sender = env.sender();
    if (!membership_.contains(sender)) {
      // Heard before its hello arrived: wait for the hello, which carries the endpoint.
      const auto* members = hb.members();
      if (members)
        for (const fb::Member* m : *members)
          if (m->peer() == sender && m->endpoint() && m->endpoint()->size() <= 256)
            if (membership_.heard(sender, m->endpoint()->str(), now))
              member_joined(sender, m->endpoint()->str());
      if (!membership_.contains(sender)) return;
    }
    membership_.heard(sender, "", now);
    if (const auto* members = hb.members()) {
      for (const fb::Member* m : *members) {
        if (!m->endpoint() || m->endpoint()->size() > 256) continue;
        if (membership_.learnt(m->peer(), m->endpoint()->str(), now))
          member_joined(m->peer(), m->endpoint()->str());
      }
    }
    reported_[sender] = {hb.version(), hb.chain()};
    if (hb.merger() != 0) on_elected(env, hb.merger());
    if (!joined_) return;
    // Behind someone: fetch what we missed (at most once per heartbeat interval).
    if (hb.version() > version_ && now >= next_fetch_) {
      next_fetch_ = now + options_.membership.heartbeat;
      send_to_peer(sender, envelope(fb::Body::Fetch,
                                    [&](auto& b) { return fb::CreateFetch(b, version_).Union(); }));
      std::lock_guard lock(mutex_);
      ++stats_.fetches;
    }
    // Another history than the merger's at a version we hold: we hold a lost merger's version.
    if (election_.merger() == sender && hb.version() <= version_)
      check_divergence(sender, hb.version(), hb.chain(), now);
  }

  void on_leave(PeerId peer) {
    const auto& m = membership_.members();
    if (auto it = m.find(peer); it != m.end()) {
      membership_.remove(peer);  // its socket closes later, with those of expired peers
      pending_.erase(peer);
      reported_.erase(peer);
      push_event({EventKind::peer_left, peer, version_, election_.epoch(), "left"});
      elect();
    }
  }

  void on_elected(const fb::Envelope& env, PeerId merger) {
    const Election::Outcome o = election_.on_announcement(env.epoch(), merger, membership_);
    if (o.followed) merger_changed();
    if (o.reassert) announce();
  }

  void announce() {
    broadcast(
        envelope(fb::Body::Elected, [&](auto& b) { return fb::CreateElected(b, self_).Union(); }));
  }

  void merger_changed() {
    pending_.clear();
    push_event({EventKind::merger_changed, *election_.merger(), version_, election_.epoch(), ""});
    send_own_submit();  // a peer keeps its diff until merged: the new merger gets it
  }

  void elect() {
    if (!joined_) return;
    const Election::Decision d = election_.update(membership_);
    if (d.announce) {
      broadcast(envelope(fb::Body::Elected,
                         [&](auto& b) { return fb::CreateElected(b, self_).Union(); }));
    }
    if (d.changed && election_.merger()) merger_changed();
  }

  void on_submit(const fb::Envelope& env, const fb::Submit& submit) {
    if (!election_.is_merger() || !joined_) {
      std::lock_guard lock(mutex_);
      ++stats_.stale_ignored;
      return;
    }
    if (!submit.diff()) return dropped("submit without a diff");
    const std::span<const std::uint8_t> bytes(submit.diff()->data(), submit.diff()->size());
    const DiffHeader header = peek_diff_header(bytes);
    if (header.base_version != version_) {
      // Based on an older version: the author rebases and sends again when it sees ours.
      std::lock_guard lock(mutex_);
      ++stats_.stale_ignored;
      return;
    }
    PendingSubmit p;
    p.diff = decode_diff(bytes, base_);
    p.sequence = header.sequence;
    p.strokes = submit.strokes();
    auto [it, inserted] = pending_.try_emplace(env.sender());
    if (inserted || it->second.sequence < p.sequence) it->second = std::move(p);
  }

  void on_version(const fb::Envelope& env, const fb::Version& v) {
    if (!v.diff()) return dropped("version without a diff");
    if (!joined_) {
      if (buffered_.size() < kHistory) buffered_[v.version()] = record_of(v);
      return;
    }
    if (!v.replay()) {
      if (election_.is_stale(env.epoch())) {
        std::lock_guard lock(mutex_);
        ++stats_.stale_ignored;
        return;
      }
      if (env.epoch() > election_.epoch()) on_elected(env, env.sender());
      if (election_.merger() != env.sender()) {
        std::lock_guard lock(mutex_);
        ++stats_.stale_ignored;
        return;
      }
    }
    if (v.version() <= version_) {  // already have it, unless our history differs
      if (election_.merger() == env.sender())
        check_divergence(env.sender(), v.version(), v.chain(), Clock::now());
      return;
    }
    if (v.version() > version_ + 1) {
      if (buffered_.size() < kHistory) buffered_[v.version()] = record_of(v);
      send_to_peer(env.sender(), envelope(fb::Body::Fetch, [&](auto& b) {
                     return fb::CreateFetch(b, version_).Union();
                   }));
      return;
    }
    if (v.parent_chain() != chain_) {
      // Built on a version we do not hold: we are on a lost merger's branch.
      request_snapshot(env.sender());
      return;
    }
    apply_version(record_of(v));
    drain_buffered();
  }

  static VersionRecord record_of(const fb::Version& v) {
    VersionRecord r;
    r.version = v.version();
    r.parent_chain = v.parent_chain();
    r.chain = v.chain();
    r.diff_bytes.assign(v.diff()->begin(), v.diff()->end());
    if (v.merged())
      for (const fb::Merged* m : *v.merged()) {
        r.merged_by.emplace_back(m->peer(), m->sequence());
        r.merged_strokes.push_back(m->strokes());
      }
    r.merge_ms = v.merge_ms();
    r.conflicting = v.conflicting_strokes();
    if (v.contributions())
      for (const fb::Contribution* c : *v.contributions()) {
        r.contributors.push_back(c->peer());
        auto bytes = [](const flatbuffers::Vector<std::uint8_t>* field) {
          return field ? std::vector<std::uint8_t>(field->begin(), field->end())
                       : std::vector<std::uint8_t>{};
        };
        r.contribution_gaps.push_back(bytes(c->index_gaps()));
        r.contribution_amounts.push_back(bytes(c->amount()));
        r.contribution_scales.push_back(c->scale());
      }
    return r;
  }

  void drain_buffered() {
    while (!buffered_.empty()) {
      auto it = buffered_.begin();
      if (it->first <= version_) {
        buffered_.erase(it);
        continue;
      }
      if (it->first != version_ + 1 || it->second.parent_chain != chain_) break;
      VersionRecord r = std::move(it->second);
      buffered_.erase(it);
      apply_version(std::move(r));
    }
  }

  /// Applies a version that follows ours: decode against our base, check the chain, hand it
  /// to the host, keep it for fetches.
  void apply_version(VersionRecord r) {
    DiffHeader header;
    Diff merged = decode_diff(r.diff_bytes, base_, &header);
    if (header.base_version != version_)
      throw InvalidInput("version " + std::to_string(r.version) + " carries a diff based on " +
                         std::to_string(header.base_version));
    if (mix64(chain_, digest(merged)) != r.chain)
      throw InvalidInput("version " + std::to_string(r.version) + " fails its hash chain");
    apply_diff(merged, base_);
    version_ = r.version;
    chain_ = r.chain;
    // Submits held for the old version (a merger catching up by fetch) no longer apply: their
    // authors rebase and send again when they see this version.
    pending_.clear();
    apply_contributions(r);
    if (own_submit_.kind == Command::Kind::submit && own_submit_.base_version < version_)
      own_submit_.bytes.clear();  // stale: the host rebases and submits again
    HostItem item;
    item.version = version_;
    item.merged = std::move(merged);
    item.merged_by = r.merged_by;
    {
      std::lock_guard lock(mutex_);
      stats_.version = version_;
      items_.push_back(std::move(item));
      for (std::size_t i = 0; i < r.merged_by.size(); ++i)
        if (r.merged_by[i].first == self_) stats_.strokes_acknowledged += r.merged_strokes[i];
    }
    push_event(
        {EventKind::version, election_.merger().value_or(0), version_, election_.epoch(), ""});
    history_.push_back(std::move(r));
    if (history_.size() > kHistory) history_.pop_front();
  }

  void apply_contributions(const VersionRecord& r) {
    std::lock_guard lock(mutex_);
    const std::size_t n = base_.vertex_count();
    for (std::size_t k = 0; k < r.contributors.size(); ++k) {
      std::vector<float>& a = attribution_[r.contributors[k]];
      a.resize(n, 0.f);
      const auto& gaps = r.contribution_gaps[k];
      const auto& amounts = r.contribution_amounts[k];
      std::size_t pos = 0, i = 0;
      std::uint64_t next = 0;
      while (pos < gaps.size() && i < amounts.size()) {
        std::uint64_t g = 0;
        int shift = 0;
        while (pos < gaps.size() && shift < 64) {
          const std::uint8_t byte = gaps[pos++];
          g |= std::uint64_t{byte & 0x7fu} << shift;
          shift += 7;
          if (!(byte & 0x80)) break;
        }
        const std::uint64_t v = next + g;
        if (v >= n) break;  // attribution is advisory: a bad list is cut, never trusted
        a[v] += float(amounts[i++]) / 255.f * r.contribution_scales[k];
        next = v + 1;
      }
    }
  }

  void on_fetch(PeerId peer, std::uint64_t after) {
    if (!joined_) return;
    if (history_.empty() || history_.front().version > after + 1) {
      if (after < version_) send_snapshot(peer);
      return;
    }
    for (const VersionRecord& r : history_)
      if (r.version > after) send_to_peer(peer, version_message(r, true));
  }

  std::vector<std::uint8_t> version_message(const VersionRecord& r, bool replay) {
    return envelope(fb::Body::Version, [&](auto& b) {
      std::vector<flatbuffers::Offset<fb::Merged>> merged;
      for (std::size_t i = 0; i < r.merged_by.size(); ++i)
        merged.push_back(
            fb::CreateMerged(b, r.merged_by[i].first, r.merged_by[i].second, r.merged_strokes[i]));
      std::vector<flatbuffers::Offset<fb::Contribution>> contributions;
      for (std::size_t k = 0; k < r.contributors.size(); ++k)
        contributions.push_back(fb::CreateContribution(
            b, r.contributors[k], b.CreateVector(r.contribution_gaps[k]),
            b.CreateVector(r.contribution_amounts[k]), r.contribution_scales[k]));
      const auto diff = b.CreateVector(r.diff_bytes);
      const auto merged_vector = b.CreateVector(merged);
      const auto contribution_vector = b.CreateVector(contributions);
      return fb::CreateVersion(b, r.version, r.parent_chain, r.chain, diff, merged_vector,
                               contribution_vector, r.merge_ms, r.conflicting, replay)
          .Union();
    });
  }

  // ---- snapshots (Clone pattern) ------------------------------------------------------------
  void request_snapshot(PeerId from) {
    snapshot_requested_ = true;
    send_to_peer(from, envelope(fb::Body::SnapshotRequest,
                                [](auto& b) { return fb::CreateSnapshotRequest(b).Union(); }));
  }

  /// Our chain at `version`, if we still hold it.
  std::optional<std::uint64_t> chain_at(std::uint64_t version) const {
    if (version == version_) return chain_;
    for (const VersionRecord& r : history_)
      if (r.version == version) return r.chain;
    return std::nullopt;
  }

  /// The merger's history says `chain` at `version`, which we also hold: if ours differs, we
  /// applied a lost merger's versions (two mergers for a moment, after a false expiry or a
  /// partition) and take the merger's state instead. Rate-limited.
  void check_divergence(PeerId merger, std::uint64_t version, std::uint64_t chain,
                        Clock::time_point now) {
    const std::optional<std::uint64_t> ours = chain_at(version);
    if (!ours || *ours == chain || now < next_divergence_check_) return;
    next_divergence_check_ = now + 4 * options_.membership.heartbeat;
    request_snapshot(merger);
  }

  void send_snapshot(PeerId peer) {
    if (!joined_) return;
    std::vector<std::uint8_t> bytes;
    {
      std::lock_guard lock(mutex_);
      bytes = encode_snapshot(base_, frame_, attribution_);
      ++stats_.snapshots_sent;
    }
    const std::size_t chunk = std::max<std::size_t>(1024, options_.snapshot_chunk_bytes);
    for (std::size_t offset = 0; offset < bytes.size(); offset += chunk) {
      const std::size_t n = std::min(chunk, bytes.size() - offset);
      send_to_peer(peer, envelope(fb::Body::SnapshotChunk, [&](auto& b) {
                     return fb::CreateSnapshotChunk(b, version_, chain_, offset, bytes.size(),
                                                    b.CreateVector(bytes.data() + offset, n))
                         .Union();
                   }));
    }
  }

  void on_snapshot_chunk(const fb::SnapshotChunk& c) {
    // Only wanted while joining or after asking (divergence); otherwise stray.
    if (!c.data()) return dropped("snapshot chunk without data");
    if (c.total() > options_.max_snapshot_bytes)
      return dropped("snapshot of " + std::to_string(c.total()) + " bytes exceeds the limit");
    // A snapshot older than our version is only wanted when we asked for it (divergence).
    if (joined_ && c.version() < version_ && !snapshot_requested_) return;
    if (c.version() != snap_version_ || c.total() != snap_buffer_.size()) {
      snap_version_ = c.version();
      snap_chain_ = c.chain();
      snap_buffer_.assign(c.total(), 0);
      snap_received_ = 0;
    }
    if (c.offset() > c.total() || c.data()->size() > c.total() - c.offset())
      return dropped("snapshot chunk outside its buffer");
    std::memcpy(snap_buffer_.data() + c.offset(), c.data()->data(), c.data()->size());
    snap_received_ += c.data()->size();
    if (snap_received_ < snap_buffer_.size()) return;
    auto snap = std::make_shared<Snapshot>(decode_snapshot(snap_buffer_));
    snap_buffer_.clear();
    snap_buffer_.shrink_to_fit();
    if (joined_ && snap->mesh.triangles != base_.triangles)
      return dropped("snapshot of another mesh connectivity");
    base_ = snap->mesh;
    version_ = snap_version_;
    chain_ = snap_chain_;
    snapshot_requested_ = false;
    history_.clear();  // another branch's versions: not ours to serve any more
    pending_.clear();
    {
      std::lock_guard lock(mutex_);
      frame_ = snap->frame;
      attribution_ = snap->attribution;
    }
    if (!hierarchy_) build_merge_state();
    own_submit_.bytes.clear();
    HostItem item;
    item.snapshot = true;
    item.version = version_;
    item.snap = snap;
    {
      std::lock_guard lock(mutex_);
      items_.push_back(std::move(item));
    }
    if (!joined_) {
      joined_ = true;
      push_event({EventKind::joined, self_, version_, election_.epoch(), ""});
      std::lock_guard lock(mutex_);
      joined_flag_ = true;
      joined_cv_.notify_all();
    }
    drain_buffered();
  }

  void build_merge_state() {
    auto h = std::make_shared<const Hierarchy>(
        Hierarchy::build(static_cast<std::uint32_t>(base_.vertex_count()), base_.triangles));
    std::lock_guard lock(mutex_);
    hierarchy_ = std::move(h);
    merger_ = std::make_unique<Merger>(*hierarchy_);
    fold_counter_ = std::make_unique<FoldCounter>(hierarchy_->topology());
  }

  // ---- outbound ------------------------------------------------------------------------------
  void heartbeat(Clock::time_point now) {
    if (!joined_) {
      // Still joining: greet the inviter again until the snapshot arrives (not so often that a
      // large snapshot is sent twice while the first is on its way).
      if (now >= next_join_hello_) {
        next_join_hello_ = now + std::max(Millis{2000}, 4 * options_.membership.expired);
        send_to(joining_endpoint_, hello(true));
      }
      return;
    }
    const Membership::Changes changes = membership_.tick(now);
    for (PeerId p : changes.evasive)
      push_event({EventKind::peer_evasive, p, version_, election_.epoch(), ""});
    for (PeerId p : changes.expired) {
      pending_.erase(p);
      reported_.erase(p);
      push_event({EventKind::peer_left, p, version_, election_.epoch(), "expired"});
    }
    // Close sockets of peers no longer members, but only some time after they went: a peer
    // taken for dead that was only stalled comes back over the connection it still has. A new
    // socket would reuse our routing id while the old connection is still open on its side,
    // which its ROUTER refuses, and both sides would stay deaf to each other.
    const auto linger = 2 * options_.membership.expired;
    for (auto it = dealers_.begin(); it != dealers_.end();) {
      bool keep = it->first == joining_endpoint_;
      for (const auto& [id, m] : membership_.members()) keep |= m.endpoint == it->first;
      if (keep) {
        departed_.erase(it->first);
        ++it;
        continue;
      }
      const auto [since, inserted] = departed_.try_emplace(it->first, now);
      if (now - since->second < linger) {
        ++it;
        continue;
      }
      departed_.erase(since);
      it = dealers_.erase(it);
    }
    elect();
    for (const Member* m : membership_.others()) send_heartbeat_to(m->endpoint);
  }

  void send_heartbeat_to(const std::string& endpoint) {
    send_to(endpoint, envelope(fb::Body::Heartbeat, [&](auto& b) {
              std::vector<flatbuffers::Offset<fb::Member>> members;
              for (const auto& [id, m] : membership_.members())
                if (!m.endpoint.empty())
                  members.push_back(fb::CreateMember(b, id, b.CreateString(m.endpoint)));
              const auto vec = b.CreateVector(members);
              return fb::CreateHeartbeat(b, version_, chain_, election_.merger().value_or(0), vec)
                  .Union();
            }));
  }

  void send_own_submit() {
    if (own_submit_.kind != Command::Kind::submit || own_submit_.bytes.empty()) return;
    if (own_submit_.base_version != version_) return;  // stale: host will rebase
    auto bytes = envelope(fb::Body::Submit, [&](auto& b) {
      return fb::CreateSubmit(b, b.CreateVector(own_submit_.bytes), own_submit_.strokes).Union();
    });
    {
      std::lock_guard lock(mutex_);
      ++stats_.submits;
      stats_.submit_bytes += bytes.size();
    }
    if (election_.is_merger()) {
      // Our own submit goes through the same checks as anyone's.
      const fb::Envelope* env = fb::GetEnvelope(bytes.data());
      try {
        on_submit(*env, *env->body_as_Submit());
      } catch (const InvalidInput& e) {
        push_event({EventKind::error, self_, version_, election_.epoch(), e.what()});
      }
    } else if (election_.merger()) {
      send_to_peer(*election_.merger(), bytes);
    }
  }

  // ---- the merger ------------------------------------------------------------------------------
  void merge_pending() {
    if (pending_.empty() || !joined_) return;
    // A new merger first catches up with the most advanced live peer (fetching as heartbeats
    // show the gap), so it never publishes a version number someone already holds.
    for (const auto& [peer, vc] : reported_)
      if (membership_.contains(peer) && vc.first > version_) return;
    const auto t0 = Clock::now();
    std::vector<const Diff*> diffs;
    std::vector<PeerId> authors;
    for (const auto& [peer, p] : pending_) {
      diffs.push_back(&p.diff);
      authors.push_back(peer);
    }
    Diff merged = merger_->merge(base_, diffs, MergeMethod::full, frame_);
    // What everyone applies is the decoded message, the merger included.
    DiffHeader header;
    header.base_version = version_;
    header.sequence = version_ + 1;
    header.author = "merge";
    std::vector<std::uint8_t> diff_bytes =
        encode_diff(merged, base_, header, wire_options_for(options_.wire, frame_));
    const float merge_ms = std::chrono::duration<float, std::milli>(Clock::now() - t0).count();
    // Outside merge_ms: a quality measure of the merge, not part of making it (sparse, cheap).
    const std::uint32_t folds = fold_counter_->count_new_folds(base_, diffs, merged);

    VersionRecord r;
    r.version = version_ + 1;
    r.parent_chain = chain_;
    r.chain = mix64(chain_, digest(decode_diff(diff_bytes, base_)));
    r.diff_bytes = std::move(diff_bytes);
    r.merge_ms = merge_ms;
    // Conflicts as a conflict-rejecting system (MeshHisto) sees them: an edit conflicts when
    // another peer touched one of its vertices in the same window.
    std::vector<std::vector<std::uint32_t>> sets;
    for (const Diff* d : diffs) sets.push_back(touched(*d));
    std::vector<std::uint8_t> hits(base_.vertex_count(), 0);
    for (const auto& s : sets)
      for (std::uint32_t v : s) hits[v] = static_cast<std::uint8_t>(std::min(2, hits[v] + 1));
    std::uint32_t merged_strokes = 0;
    for (std::size_t k = 0; k < diffs.size(); ++k) {
      const PendingSubmit& p = pending_.at(authors[k]);
      r.merged_by.emplace_back(authors[k], p.sequence);
      r.merged_strokes.push_back(p.strokes);
      merged_strokes += p.strokes;
      const bool conflict =
          std::any_of(sets[k].begin(), sets[k].end(), [&](std::uint32_t v) { return hits[v] > 1; });
      if (conflict) r.conflicting += p.strokes;
      // contribution
      std::vector<float> amount = change_amounts(*diffs[k], base_, sets[k], frame_.scale);
      const float peak = amount.empty() ? 0.f : *std::max_element(amount.begin(), amount.end());
      std::vector<std::uint8_t> gaps, q;
      std::uint64_t next = 0;
      for (std::size_t i = 0; i < sets[k].size(); ++i) {
        put_varint(gaps, sets[k][i] - next);
        next = std::uint64_t{sets[k][i]} + 1;
        q.push_back(peak > 0 ? static_cast<std::uint8_t>(std::lround(amount[i] / peak * 255.f))
                             : 0);
      }
      r.contributors.push_back(authors[k]);
      r.contribution_gaps.push_back(std::move(gaps));
      r.contribution_amounts.push_back(std::move(q));
      r.contribution_scales.push_back(peak);
    }
    pending_.clear();
    const std::vector<std::uint8_t> message = version_message(r, false);
    broadcast(message);
    const std::uint32_t conflicting = r.conflicting;
    apply_version(std::move(r));
    // After applying, so a reader never sees a merge counted before its version.
    std::lock_guard lock(mutex_);
    stats_.version = version_;
    ++stats_.merges;
    stats_.merged_strokes += merged_strokes;
    stats_.conflicting_strokes += conflicting;
    stats_.folds_introduced += folds;
    stats_.merge_ms_sum += merge_ms;
    stats_.merge_ms_max = std::max(stats_.merge_ms_max, double(merge_ms));
    stats_.version_bytes_sent += message.size() * membership_.others().size();
  }

  // ---- state ---------------------------------------------------------------------------------
  SessionOptions options_;
  Invite invite_;
  PeerId self_;
  zmq::context_t ctx_{1};
  zmq::socket_t zap_, router_;
  std::map<std::string, zmq::socket_t> dealers_;
  std::map<std::string, Clock::time_point> departed_;  // endpoint -> when its peer went
  std::array<std::uint8_t, 32> server_public_{}, client_public_{};
  std::string endpoint_, joining_endpoint_;
  Membership membership_;
  Election election_;

  bool joined_ = false;
  Mesh base_;
  std::uint64_t version_ = 0;
  std::uint64_t chain_ = 0;
  std::deque<VersionRecord> history_;
  std::map<std::uint64_t, VersionRecord> buffered_;
  std::map<PeerId, std::pair<std::uint64_t, std::uint64_t>> reported_;  // version, chain
  Clock::time_point next_fetch_{};
  Clock::time_point next_join_hello_{};
  Clock::time_point next_divergence_check_{};
  bool snapshot_requested_ = false;
  std::map<PeerId, PendingSubmit> pending_;
  Command own_submit_;  // the last submit, until a merged version covers it
  std::uint64_t snap_version_ = ~std::uint64_t{0}, snap_chain_ = 0;
  std::vector<std::uint8_t> snap_buffer_;
  std::size_t snap_received_ = 0;
  std::unique_ptr<Merger> merger_;
  std::unique_ptr<FoldCounter> fold_counter_;  // the merger's quality count, on hierarchy_
  std::vector<std::uint64_t> inbound_;         // aligned copy of a misaligned message

  // shared with the host (mutex_)
  mutable std::mutex mutex_;
  std::condition_variable joined_cv_;
  bool joined_flag_ = false;
  std::deque<Command> commands_;
  std::deque<HostItem> items_;
  std::deque<Event> events_;
  SessionStats stats_;
  std::map<PeerId, std::vector<float>> attribution_;
  std::shared_ptr<const Hierarchy> hierarchy_;
  MergeFrame frame_;

  std::thread thread_;
};

// ---- host side --------------------------------------------------------------------------------

namespace {

/// Whether `width`-wide `local` equals `base` with `change` applied (bitwise), without making
/// that state: memcmp of the runs between changed vertices.
bool equals_with(const float* base, const float* local, std::size_t vertices, std::uint32_t width,
                 const AttributeDiff* change) {
  std::size_t v = 0;
  const std::size_t row = std::size_t{width} * sizeof(float);
  if (change) {
    for (std::size_t i = 0; i < change->indices.size(); ++i) {
      const std::size_t at = change->indices[i];
      if (std::memcmp(base + v * width, local + v * width, (at - v) * row) != 0) return false;
      if (std::memcmp(change->values.data() + i * width, local + at * width, row) != 0)
        return false;
      v = at + 1;
    }
  }
  return std::memcmp(base + v * width, local + v * width, (vertices - v) * row) == 0;
}

bool same_layout(const Mesh& base, const Mesh& local) {
  if (local.vertex_count() != base.vertex_count() || local.channels.size() != base.channels.size())
    return false;
  for (std::size_t c = 0; c < base.channels.size(); ++c)
    if (local.channels[c].values.size() != base.channels[c].values.size()) return false;
  return true;
}

bool equals_base_plus(const Mesh& base, const Diff* d, const Mesh& local) {
  const std::size_t n = base.vertex_count();
  if (!equals_with(reinterpret_cast<const float*>(base.positions.data()),
                   reinterpret_cast<const float*>(local.positions.data()), n, 3,
                   d ? &d->positions : nullptr))
    return false;
  for (std::size_t c = 0; c < base.channels.size(); ++c)
    if (!equals_with(base.channels[c].values.data(), local.channels[c].values.data(), n,
                     base.channels[c].desc.width, d ? &d->channels[c].change : nullptr))
      return false;
  return true;
}

/// Puts the vertices `d` changes back to their values in `base`.
void restore(const Mesh& base, const Diff& d, Mesh& local) {
  for (std::uint32_t v : d.positions.indices) local.positions[v] = base.positions[v];
  for (std::size_t c = 0; c < d.channels.size(); ++c) {
    const std::uint32_t w = d.channels[c].desc.width;
    for (std::uint32_t v : d.channels[c].change.indices)
      std::copy_n(base.channels[c].values.data() + std::size_t{w} * v, w,
                  local.channels[c].values.data() + std::size_t{w} * v);
  }
}

}  // namespace

struct Session::Impl {
  std::unique_ptr<Node> node;
  SessionOptions options;
  bool left = false;
  // host's view
  bool has_base = false;
  Mesh base;
  std::uint64_t version = 0;
  std::shared_ptr<const Hierarchy> hierarchy;
  std::unique_ptr<Merger> merger;
  MergeFrame frame;
  std::map<std::uint64_t, Diff> submitted;  // sequence -> what was sent (decoded), this base
  std::uint64_t next_sequence = 1;
  std::uint64_t last_submit_digest = 0;
  std::uint32_t unacknowledged_strokes = 0;
  std::map<std::uint64_t, std::uint32_t> strokes_at;  // sequence -> strokes it carried
  std::uint64_t versions_applied = 0, rebases = 0, strokes_submitted = 0;

  void ensure_merge_state() {
    if (!merger) {
      hierarchy = node->hierarchy();
      frame = node->frame();
      merger = std::make_unique<Merger>(*hierarchy);
    }
  }
};

Session::Session(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Session::~Session() {
  leave();
}

std::unique_ptr<Session> Session::create(const Mesh& mesh, const SessionOptions& options) {
  validate(mesh, "session mesh");
  Invite invite;
  invite.session = random_u64();
  for (auto& b : invite.server_secret) b = static_cast<std::uint8_t>(random_u64());
  for (auto& b : invite.client_secret) b = static_cast<std::uint8_t>(random_u64());
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->node = std::make_unique<Node>(invite, true, options);
  impl->node->start_as_creator(mesh);
  impl->base = mesh;
  impl->has_base = true;
  impl->ensure_merge_state();
  impl->node->run();
  return std::unique_ptr<Session>(new Session(std::move(impl)));
}

std::unique_ptr<Session> Session::join(const std::string& invite_text,
                                       const SessionOptions& options, Millis timeout) {
  const Invite invite = parse_invite(invite_text);
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->node = std::make_unique<Node>(invite, false, options);
  impl->node->start_as_joiner();
  impl->node->run();
  if (!impl->node->wait_joined(timeout))
    throw IoError("no snapshot from " + invite.endpoint + " within " +
                  std::to_string(timeout.count()) + " ms (wrong invite, or no member reachable)");
  auto session = std::unique_ptr<Session>(new Session(std::move(impl)));
  Mesh scratch;
  session->update(scratch);  // takes the snapshot as the base
  return session;
}

std::string Session::invite() const {
  return impl_->node->invite_text();
}
PeerId Session::id() const {
  return impl_->node->id();
}
std::string Session::endpoint() const {
  return impl_->node->endpoint();
}
std::uint64_t Session::version() const {
  return impl_->version;
}
const Mesh& Session::base() const {
  return impl_->base;
}

bool Session::submit(Mesh& local, std::uint32_t strokes) {
  Impl& s = *impl_;
  if (s.left) throw InvalidInput("submit: the session was left");
  const Diff d = capture_diff(s.base, local);
  if (d.positions.empty() && std::all_of(d.channels.begin(), d.channels.end(),
                                         [](const auto& c) { return c.change.empty(); }))
    return false;
  if (digest(d) == s.last_submit_digest) return false;  // nothing new since the last submit
  s.unacknowledged_strokes += strokes;
  s.strokes_submitted += strokes;
  DiffHeader header;
  header.base_version = s.version;
  header.sequence = s.next_sequence++;
  header.author = s.options.name;
  s.ensure_merge_state();
  std::vector<std::uint8_t> bytes =
      encode_diff(d, s.base, header, wire_options_for(s.options.wire, s.frame));
  Diff sent = decode_diff(bytes, s.base);
  // The host's values become what the peers receive: changed vertices the quantisation left
  // out go back to the base, the others to their decoded values.
  restore(s.base, d, local);
  apply_diff(sent, local);
  s.last_submit_digest = digest(capture_diff(s.base, local));
  s.strokes_at[header.sequence] = s.unacknowledged_strokes;
  s.submitted[header.sequence] = std::move(sent);
  Command c;
  c.kind = Command::Kind::submit;
  c.base_version = s.version;
  c.bytes = std::move(bytes);
  c.strokes = s.unacknowledged_strokes;
  s.node->command(std::move(c));
  return true;
}

std::size_t Session::update(Mesh& local) {
  Impl& s = *impl_;
  std::vector<HostItem> items = s.node->take_items();
  std::size_t applied = 0;
  // A submit that a version did not include (it reached the merger after the merge, based on
  // the older version) is sent again, rebased, once the versions are applied: the host does
  // not have to notice.
  bool resend = false;
  for (HostItem& item : items) {
    if (item.snapshot) {
      const Mesh& snap = item.snap->mesh;
      if (s.has_base && !local.positions.empty()) {
        // Carry the local edits (relative to the old base) over to the snapshot.
        s.ensure_merge_state();
        const Diff mine = capture_diff(s.base, local);
        const Diff theirs = capture_diff(s.base, snap);
        Mesh rebased = s.base;
        const Diff* both[2] = {&theirs, &mine};
        apply_diff(s.merger->merge(s.base, both, MergeMethod::full, s.frame), rebased);
        local = std::move(rebased);
        ++s.rebases;
      } else {
        local = snap;
      }
      s.base = snap;
      s.has_base = true;
      s.version = item.version;
      resend |= !s.submitted.empty();
      s.submitted.clear();
      s.last_submit_digest = 0;
      s.ensure_merge_state();
      ++applied;
      continue;
    }
    if (item.version != s.version + 1) continue;  // cannot happen: the node hands them in order
    s.ensure_merge_state();
    // S: the state this peer's merged submit described (the base if none of ours is in).
    const Diff* ours = nullptr;
    std::uint64_t merged_sequence = 0;
    for (const auto& [peer, seq] : item.merged_by)
      if (peer == s.node->id())
        if (auto it = s.submitted.find(seq); it != s.submitted.end()) {
          ours = &it->second;
          merged_sequence = seq;
          if (auto st = s.strokes_at.find(seq); st != s.strokes_at.end())
            s.unacknowledged_strokes -= std::min(s.unacknowledged_strokes, st->second);
        }
    if (!local.positions.empty() && !same_layout(s.base, local))
      throw InvalidInput("update: the local mesh's vertices or channels differ from the session's");
    if (local.positions.empty() || equals_base_plus(s.base, ours, local)) {
      // No edits since the submit (the common case): local = base + ours becomes the new
      // version sparsely: our submitted vertices back to the base, then the merged diff.
      if (!local.positions.empty()) {
        if (ours) restore(s.base, *ours, local);
        apply_diff(item.merged, local);
      }
      apply_diff(item.merged, s.base);
      if (local.positions.empty()) local = s.base;
    } else {
      // Edits made since the submit: merged with what the version changed relative to S, the
      // state the submit described.
      Mesh sent_state = s.base;
      if (ours) apply_diff(*ours, sent_state);
      apply_diff(item.merged, s.base);
      const Diff theirs = capture_diff(sent_state, s.base);
      const Diff mine = capture_diff(sent_state, local);
      const Diff* both[2] = {&theirs, &mine};
      local = sent_state;
      apply_diff(s.merger->merge(sent_state, both, MergeMethod::full, s.frame), local);
      ++s.rebases;
    }
    s.version = item.version;
    resend |= !s.submitted.empty() && s.submitted.rbegin()->first != merged_sequence;
    s.submitted.clear();
    s.strokes_at.clear();
    s.last_submit_digest = 0;
    ++applied;
  }
  s.versions_applied += applied;
  if (resend && !local.positions.empty()) submit(local, 0);
  return applied;
}

std::vector<Event> Session::poll_events() {
  return impl_->node->take_events();
}

SessionStats Session::stats() const {
  SessionStats st = impl_->node->stats();
  st.versions_applied = impl_->versions_applied;
  st.rebases = impl_->rebases;
  st.strokes_submitted = impl_->strokes_submitted;
  return st;
}

std::vector<std::pair<PeerId, std::vector<float>>> Session::attribution() const {
  return impl_->node->attribution();
}

void Session::leave() {
  if (impl_->left) return;
  impl_->left = true;
  impl_->node->stop();
}

}  // namespace csculpt::peer
