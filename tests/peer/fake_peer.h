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

#include "csculpt/peer/session.h"
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

}  // namespace csculpt::peer::testing
