// A member that speaks the protocol by hand, with the session's keys, through the peers' own
// transport and message builders: it greets, beats only when told (a test can make it fall
// silent, as a stalled process would) and sends what a test wants, including what a real peer
// never would.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/peer/session.h"
#include "csculpt/wire.h"
#include "messages.h"
#include "transport.h"

namespace csculpt::peer::testing {

class FakePeer {
 public:
  /// Binds its own socket; talks to the member whose invite it was given.
  FakePeer(const std::string& invite, PeerId id)
      : invite_(parse_invite(invite)),
        id_(id),
        transport_(invite_, id, "tcp://127.0.0.1:*", std::size_t{64} << 20) {}

  EnvelopeHeader header() const { return {invite_.session, id_, epoch_}; }
  void send(const Bytes& bytes) { transport_.send(invite_.endpoint, bytes); }
  void hello() { send(hello_message(header(), transport_.endpoint(), "fake", false)); }
  /// What its heartbeats say: by default nothing (version 0, chain 0, no merger).
  void says(std::uint64_t version, std::uint64_t chain, PeerId merger) {
    version_ = version, chain_ = chain, merger_ = merger;
  }
  void heartbeat() { send(heartbeat_message(header(), version_, chain_, merger_)); }
  /// Claims the merger's role in `epoch` (the member follows a claim of a later epoch).
  void claim_merger(std::uint64_t epoch) {
    epoch_ = epoch;
    merger_ = id_;
    send(elected_message(header(), id_));
  }

  /// A version in our name: `diff` (a DiffMessage on version `v` - 1) naming the submits it
  /// `merged`, with the chains given (a real merger's: next_chain of the decoded diff); a
  /// `replay` is a fetch's answer, taken from any member.
  Bytes version(const Bytes& diff, std::uint64_t v, std::uint64_t parent_chain, std::uint64_t chain,
                std::vector<MergedSubmit> merged = {}, bool replay = false) const {
    VersionRecord r;
    r.version = v;
    r.parent_chain = parent_chain;
    r.chain = chain;
    r.diff_bytes = diff;
    r.merged = std::move(merged);
    return version_message(header(), r, replay);
  }

  /// Serves the member's connection to us (ZAP) for `span`, handing what it sends to `seen`
  /// (if given); with `beat`, heartbeats that often meanwhile.
  void pump(Millis span, std::optional<Millis> beat = std::nullopt,
            const std::function<void(const fb::Envelope&)>& seen = {}) {
    const auto end = Clock::now() + span;
    auto next_beat = Clock::now();
    while (Clock::now() < end) {
      if (beat && Clock::now() >= next_beat) {
        heartbeat();
        next_beat += *beat;
      }
      transport_.wait(Millis{5});
      for (Inbound in; transport_.receive(in);) {
        if (!seen) continue;
        // Checked and aligned as a peer reads it.
        const Opened opened =
            open_envelope({static_cast<const std::uint8_t*>(in.payload.data()), in.payload.size()},
                          {static_cast<const std::uint8_t*>(in.routing.data()), in.routing.size()},
                          invite_.session, id_, inbound_);
        if (opened.envelope) seen(*opened.envelope);
      }
    }
  }

 private:
  Invite invite_;
  PeerId id_;
  std::uint64_t epoch_ = 0, version_ = 0, chain_ = 0;
  PeerId merger_ = 0;
  Transport transport_;
  std::vector<std::uint64_t> inbound_;  // aligned copy of a misaligned message
};

/// An edit of `base` (version `base_version`) that moves `vertex`, as a DiffMessage.
inline Bytes edit_message(const Mesh& base, std::uint64_t base_version, std::uint32_t vertex) {
  Mesh edited = base;
  edited.positions.at(vertex).y += 0.05f;
  DiffHeader h;
  h.base_version = base_version;
  h.sequence = base_version + 1;
  h.author = "merge";
  return encode_diff(capture_diff(base, edited), base, h, EncodeOptions{});
}

}  // namespace csculpt::peer::testing
