// A member that speaks the protocol by hand, with the session's keys, through the peers' own
// transport and message builders: it greets, beats only when told (a test can make it fall
// silent, as a stalled process would) and sends what a test wants, including what a real peer
// never would.
#pragma once

#include <optional>
#include <string>

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

  EnvelopeHeader header() const { return {invite_.session, id_, 0}; }
  void send(const Bytes& bytes) { transport_.send(invite_.endpoint, bytes); }
  void hello() { send(hello_message(header(), transport_.endpoint(), "fake", false)); }
  void heartbeat() { send(heartbeat_message(header(), 0, 0, 0)); }

  /// Serves the member's connection to us (ZAP) and throws away what it sends, for `span`;
  /// with `beat`, heartbeats that often meanwhile.
  void pump(Millis span, std::optional<Millis> beat = std::nullopt) {
    const auto end = Clock::now() + span;
    auto next_beat = Clock::now();
    while (Clock::now() < end) {
      if (beat && Clock::now() >= next_beat) {
        heartbeat();
        next_beat += *beat;
      }
      transport_.wait(Millis{5});
      for (Inbound in; transport_.receive(in);) {
      }
    }
  }

 private:
  Invite invite_;
  PeerId id_;
  Transport transport_;
};

}  // namespace csculpt::peer::testing
