#include "messages.h"

#include <cstring>

#include "csculpt/error.h"
#include "transport.h"

namespace csculpt::peer {

Bytes hello_message(const EnvelopeHeader& h, const std::string& endpoint, const std::string& name,
                    bool wants_snapshot, std::uint32_t protocol) {
  return envelope(h, fb::Body::Hello, [&](auto& b) {
    return fb::CreateHello(b, protocol, b.CreateString(endpoint), b.CreateString(name),
                           wants_snapshot)
        .Union();
  });
}

Bytes heartbeat_message(const EnvelopeHeader& h, std::uint64_t version, std::uint64_t chain,
                        PeerId merger, const std::vector<std::pair<PeerId, std::string>>& members,
                        const HeartbeatTiming& timing) {
  return envelope(h, fb::Body::Heartbeat, [&](auto& b) {
    std::vector<flatbuffers::Offset<fb::Member>> list;
    for (const auto& [id, endpoint] : members)
      list.push_back(fb::CreateMember(b, id, b.CreateString(endpoint)));
    const auto vec = b.CreateVector(list);
    const auto echoes = b.CreateVectorOfStructs(timing.echoes);
    return fb::CreateHeartbeat(b, version, chain, merger, vec, timing.sent_us, echoes).Union();
  });
}

Bytes presence_message(const EnvelopeHeader& h, std::uint64_t sequence, const Presence& p) {
  return envelope(h, fb::Body::Presence, [&](auto& b) {
    const fb::Point position(p.position.x, p.position.y, p.position.z);
    return fb::CreatePresence(b, sequence, &position, p.radius, p.active, p.visible, p.rgba)
        .Union();
  });
}

Presence presence_of(const fb::Presence& p) {
  if (!p.position()) throw InvalidInput("presence without a position");
  Presence out;
  out.position = {p.position()->x(), p.position()->y(), p.position()->z()};
  out.radius = p.radius();
  out.active = p.active();
  out.visible = p.visible();
  out.rgba = p.rgba();
  validate_presence(out);
  return out;
}

Bytes leave_message(const EnvelopeHeader& h) {
  return envelope(h, fb::Body::Leave, [](auto& b) { return fb::CreateLeave(b).Union(); });
}

Bytes elected_message(const EnvelopeHeader& h, PeerId merger) {
  return envelope(h, fb::Body::Elected,
                  [&](auto& b) { return fb::CreateElected(b, merger).Union(); });
}

Bytes submit_message(const EnvelopeHeader& h, std::span<const std::uint8_t> diff,
                     std::uint32_t strokes) {
  return envelope(h, fb::Body::Submit, [&](auto& b) {
    return fb::CreateSubmit(b, b.CreateVector(diff.data(), diff.size()), strokes).Union();
  });
}

Bytes fetch_message(const EnvelopeHeader& h, std::uint64_t after) {
  return envelope(h, fb::Body::Fetch, [&](auto& b) { return fb::CreateFetch(b, after).Union(); });
}

Bytes snapshot_request_message(const EnvelopeHeader& h) {
  return envelope(h, fb::Body::SnapshotRequest,
                  [](auto& b) { return fb::CreateSnapshotRequest(b).Union(); });
}

Bytes snapshot_chunk_message(const EnvelopeHeader& h, std::uint64_t version, std::uint64_t chain,
                             std::uint64_t offset, std::uint64_t total,
                             std::span<const std::uint8_t> data) {
  return envelope(h, fb::Body::SnapshotChunk, [&](auto& b) {
    return fb::CreateSnapshotChunk(b, version, chain, offset, total,
                                   b.CreateVector(data.data(), data.size()))
        .Union();
  });
}

Bytes version_message(const EnvelopeHeader& h, const VersionRecord& r, bool replay) {
  return envelope(h, fb::Body::Version, [&](auto& b) {
    std::vector<flatbuffers::Offset<fb::Merged>> merged;
    for (const MergedSubmit& m : r.merged)
      merged.push_back(fb::CreateMerged(b, m.peer, m.sequence, m.strokes));
    std::vector<flatbuffers::Offset<fb::Contribution>> contributions;
    for (const Contribution& c : r.contributions)
      contributions.push_back(fb::CreateContribution(b, c.peer, b.CreateVector(c.index_gaps),
                                                     b.CreateVector(c.amounts), c.scale));
    const auto diff = b.CreateVector(r.diff_bytes);
    const auto merged_vector = b.CreateVector(merged);
    const auto contribution_vector = b.CreateVector(contributions);
    return fb::CreateVersion(b, r.version, r.parent_chain, r.chain, diff, merged_vector,
                             contribution_vector, r.merge_ms, r.conflicting, replay)
        .Union();
  });
}

VersionRecord record_of(const fb::Version& v) {
  auto bytes = [](const flatbuffers::Vector<std::uint8_t>* field) {
    return field ? Bytes(field->begin(), field->end()) : Bytes{};
  };
  VersionRecord r;
  r.version = v.version();
  r.parent_chain = v.parent_chain();
  r.chain = v.chain();
  r.diff_bytes = bytes(v.diff());
  if (v.merged())
    for (const fb::Merged* m : *v.merged())
      r.merged.push_back({m->peer(), m->sequence(), m->strokes()});
  r.merge_ms = v.merge_ms();
  r.conflicting = v.conflicting_strokes();
  if (v.contributions())
    for (const fb::Contribution* c : *v.contributions())
      r.contributions.push_back(
          {c->peer(), bytes(c->index_gaps()), bytes(c->amount()), c->scale()});
  return r;
}

Opened open_envelope(std::span<const std::uint8_t> payload, std::span<const std::uint8_t> routing,
                     std::uint64_t session, PeerId self, std::vector<std::uint64_t>& storage) {
  const std::uint8_t* data = payload.data();
  if (reinterpret_cast<std::uintptr_t>(data) % alignof(std::uint64_t) != 0) {
    storage.resize((payload.size() + 7) / 8);
    std::memcpy(storage.data(), data, payload.size());
    data = reinterpret_cast<const std::uint8_t*>(storage.data());
  }
  if (payload.size() < 8 || !fb::EnvelopeBufferHasIdentifier(data))
    return {nullptr, "message is not a cSculpt session envelope"};
  flatbuffers::Verifier verifier(data, payload.size(), 16, 10000);
  if (!fb::VerifyEnvelopeBuffer(verifier))
    return {nullptr, "message failed FlatBuffers verification"};
  const fb::Envelope* env = fb::GetEnvelope(data);
  if (env->session() != session) return {nullptr, "message of another session"};
  const PeerId sender = env->sender();
  if (sender == self || sender == 0 || !is_routing_id_of(sender, routing))
    return {nullptr, "message whose sender id does not match its connection"};
  return {env, ""};
}

}  // namespace csculpt::peer
