#include "snapshot.h"

#include <cmath>
#include <cstring>

#include "csculpt/error.h"
#include "session_generated.h"

namespace csculpt::peer {
namespace {

namespace fb = csculpt::session;

void decode_channels(const fb::MeshSnapshot& s, Mesh& m) {
  if (!s.channels()) return;
  for (const fb::ChannelData* c : *s.channels()) {
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

void decode_attribution(const fb::MeshSnapshot& s, std::size_t n, Snapshot& out) {
  if (!s.attribution_peers()) return;
  const std::size_t peers = s.attribution_peers()->size();
  if (!s.attribution() || s.attribution()->size() != peers * n)
    throw InvalidInput("snapshot attribution has the wrong size");
  for (std::size_t k = 0; k < peers; ++k)
    out.attribution[s.attribution_peers()->Get(static_cast<flatbuffers::uoffset_t>(k))].assign(
        s.attribution()->data() + k * n, s.attribution()->data() + (k + 1) * n);
}

}  // namespace

std::vector<std::uint8_t> encode_snapshot(const Mesh& mesh, const MergeFrame& frame,
                                          const std::map<PeerId, std::vector<float>>& attrib,
                                          const ChainHistory& chains) {
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
  const auto chain_vector = b.CreateVector(chains.chains);
  b.Finish(fb::CreateMeshSnapshot(b, positions, triangles, channel_vector, frame_center,
                                  frame.scale, peer_vector, value_vector, chains.first,
                                  chain_vector));
  return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
}

std::vector<std::uint8_t> encode_snapshot(const Snapshot& snap) {
  return encode_snapshot(snap.mesh, snap.frame, snap.attribution, snap.chains);
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
  decode_channels(*s, m);
  validate(m, "snapshot");
  if (!s->frame_center() || s->frame_center()->size() != 3 || !(s->frame_scale() > 0) ||
      !std::isfinite(s->frame_scale()))
    throw InvalidInput("snapshot frame missing or invalid");
  out.frame.center = {s->frame_center()->Get(0), s->frame_center()->Get(1),
                      s->frame_center()->Get(2)};
  out.frame.scale = s->frame_scale();
  decode_attribution(*s, m.vertex_count(), out);
  out.chains.first = s->chains_first();
  if (s->chains()) out.chains.chains.assign(s->chains()->begin(), s->chains()->end());
  return out;
}

bool SnapshotAssembly::add(std::uint64_t version, std::uint64_t chain, std::uint64_t offset,
                           std::uint64_t total, std::span<const std::uint8_t> data) {
  if (version != version_ || total != total_) {
    // Another snapshot's chunk: finish the one under way first (two senders, or two answers
    // of one sender at two versions, would otherwise restart each other for ever).
    if (!chunks_.empty()) return false;
    version_ = version;
    chain_ = chain;
    total_ = total;
    // Grown as chunks come: zeroing tens of MB at the first one held the network thread past
    // a joiner's expiry under TSan.
    buffer_.clear();
    buffer_.reserve(total);
    received_ = 0;
  }
  if (offset > total || data.size() > total - offset)
    throw InvalidInput("snapshot chunk outside its buffer");
  if (!chunks_.emplace(offset, data.size()).second) return false;  // a repeat adds nothing
  if (buffer_.size() < offset + data.size()) buffer_.resize(offset + data.size());
  std::memcpy(buffer_.data() + offset, data.data(), data.size());
  received_ += data.size();
  return received_ >= total_;
}

std::vector<std::uint8_t> SnapshotAssembly::take() {
  std::vector<std::uint8_t> out = std::move(buffer_);
  buffer_ = {};
  chunks_.clear();
  received_ = 0;
  total_ = kNone;
  return out;  // version() and chain() still describe it
}

void SnapshotAssembly::reset() {
  take();
  version_ = kNone;
}

}  // namespace csculpt::peer
