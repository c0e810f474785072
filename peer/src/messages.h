// The session protocol's messages (peer/schema/session.fbs): every message is an Envelope
// naming the session, the sender and its epoch around one body. Builders for each body, the
// version record they carry, and open_envelope, the checks every received message passes
// before anything reads it.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "csculpt/peer/membership.h"
#include "csculpt/peer/session.h"
#include "session_generated.h"

namespace csculpt::peer {

namespace fb = csculpt::session;
using Bytes = std::vector<std::uint8_t>;

/// The protocol a hello announces; a peer drops hellos of another.
constexpr std::uint32_t kProtocol = 1;
/// Longest endpoint believed from a hello or a heartbeat.
constexpr std::size_t kMaxEndpointBytes = 256;

/// Who sends: every envelope carries these.
struct EnvelopeHeader {
  std::uint64_t session = 0;
  PeerId sender = 0;
  std::uint64_t epoch = 0;  ///< the sender's election epoch
};

/// A submit a merged version includes, and how many strokes it carried.
struct MergedSubmit {
  PeerId peer = 0;
  std::uint64_t sequence = 0;
  std::uint32_t strokes = 0;
};

/// How much of a version's change came from one peer: the vertices it touched (gap-coded,
/// csculpt/varint.h) with an amount each, quantised to 0..255 of `scale`.
struct Contribution {
  PeerId peer = 0;
  Bytes index_gaps;
  Bytes amounts;
  float scale = 0;
};

/// A merged version as sent and kept (to answer fetches).
struct VersionRecord {
  std::uint64_t version = 0;
  std::uint64_t parent_chain = 0;  ///< the chain of version - 1
  std::uint64_t chain = 0;         ///< hash_mix(parent_chain, digest(decoded diff))
  Bytes diff_bytes;                ///< a DiffMessage from version - 1 (csculpt/wire.h)
  std::vector<MergedSubmit> merged;
  std::vector<Contribution> contributions;
  float merge_ms = 0;
  std::uint32_t conflicting = 0;  ///< strokes a conflict-rejecting system would refuse
};

/// A heartbeat's clock and echoes (round trips: protocol.md, Membership).
struct HeartbeatTiming {
  std::uint64_t sent_us = 0;  ///< the sender's monotonic clock
  /// Per member: its last heartbeat's sent_us and how long we held it (Echo).
  std::vector<fb::Echo> echoes;
};

/// An envelope around the body `fill(builder)` returns (a flatbuffers::Offset<void>).
template <class Fill>
Bytes envelope(const EnvelopeHeader& header, fb::Body type, Fill&& fill) {
  flatbuffers::FlatBufferBuilder b(256);
  const flatbuffers::Offset<void> body = fill(b);
  fb::EnvelopeBuilder e(b);
  e.add_session(header.session);
  e.add_sender(header.sender);
  e.add_epoch(header.epoch);
  e.add_body_type(type);
  e.add_body(body);
  fb::FinishEnvelopeBuffer(b, e.Finish());
  return {b.GetBufferPointer(), b.GetBufferPointer() + b.GetSize()};
}

Bytes hello_message(const EnvelopeHeader& h, const std::string& endpoint, const std::string& name,
                    bool wants_snapshot, std::uint32_t protocol = kProtocol);
/// `members`: id and endpoint of every member the sender knows (gossip).
Bytes heartbeat_message(const EnvelopeHeader& h, std::uint64_t version, std::uint64_t chain,
                        PeerId merger,
                        const std::vector<std::pair<PeerId, std::string>>& members = {},
                        const HeartbeatTiming& timing = {});
/// The sender's brush cursor, its `sequence`-th presence message.
Bytes presence_message(const EnvelopeHeader& h, std::uint64_t sequence, const Presence& p);
/// A received Presence body, checked (validate_presence); throws InvalidInput saying what is
/// wrong, which drops the message.
Presence presence_of(const fb::Presence& p);
Bytes leave_message(const EnvelopeHeader& h);
Bytes elected_message(const EnvelopeHeader& h, PeerId merger);
Bytes submit_message(const EnvelopeHeader& h, std::span<const std::uint8_t> diff,
                     std::uint32_t strokes);
Bytes fetch_message(const EnvelopeHeader& h, std::uint64_t after);
Bytes snapshot_request_message(const EnvelopeHeader& h);
Bytes snapshot_chunk_message(const EnvelopeHeader& h, std::uint64_t version, std::uint64_t chain,
                             std::uint64_t offset, std::uint64_t total,
                             std::span<const std::uint8_t> data);
/// `replay`: an answer to a fetch (receivers skip the epoch checks; the chain still holds).
Bytes version_message(const EnvelopeHeader& h, const VersionRecord& r, bool replay);
/// A received Version body as a record (its diff must be present).
VersionRecord record_of(const fb::Version& v);

/// A received message after open_envelope: the envelope, or why it was refused.
struct Opened {
  const fb::Envelope* envelope = nullptr;  ///< points into the payload or `storage`
  std::string error;                       ///< set when envelope is null
};
/// Checks a message before it is read: a session envelope (file identifier, FlatBuffers
/// verification) of `session` from a sender other than `self` and not 0 whose routing id
/// (`routing`, csculpt transport) is its own. FlatBuffers reads scalars in place, so a payload
/// not aligned for 8-byte fields is copied into `storage` first.
Opened open_envelope(std::span<const std::uint8_t> payload, std::span<const std::uint8_t> routing,
                     std::uint64_t session, PeerId self, std::vector<std::uint64_t>& storage);

}  // namespace csculpt::peer
