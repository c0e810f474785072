// What a peer knows of the others beyond membership: their names (from hellos), the round
// trip to each (heartbeat echoes, protocol.md "Membership"), and the few that left lately, so
// a host can list everyone (Session::peers). Pure logic: time is passed in.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "csculpt/peer/membership.h"
#include "csculpt/peer/session.h"
#include "messages.h"

namespace csculpt::peer {

/// A steady clock reading in microseconds (what heartbeats carry as sent_us).
std::uint64_t micros(Clock::time_point t);

class PeerTable {
 public:
  void named(PeerId peer, std::string name) { links_[peer].name = std::move(name); }
  /// A heartbeat from `peer`, sent at its clock's `sent_us`, arrived at `now`: our next
  /// heartbeat echoes it.
  void heartbeat_from(PeerId peer, std::uint64_t sent_us, Clock::time_point now);
  /// The echoes our next heartbeat carries (sent at `now`).
  std::vector<fb::Echo> echoes(Clock::time_point now) const;
  /// `echo` of our own heartbeat came back from `peer` at `now`: a round-trip sample (kept
  /// smoothed; one beyond a minute, or negative, is someone else's clock and ignored).
  void echoed(PeerId peer, const fb::Echo& echo, Clock::time_point now);

  /// `peer` left or expired: listed as left (the latest kKeptDeparted) until heard again.
  void departed(PeerId peer);
  /// `peer` is a member again.
  void returned(PeerId peer);

  /// Members (but `self`), then the departed ones.
  std::vector<PeerInfo> list(
      const Membership& membership, std::optional<PeerId> merger,
      const std::map<PeerId, std::pair<std::uint64_t, std::uint64_t>>& reported) const;

 private:
  struct Link {
    std::string name;
    std::uint64_t their_sent_us = 0;  // of their last heartbeat, to echo
    Clock::time_point heard_at{};     // when it came (the echo says how long we held it)
    double rtt_ms = -1;
  };
  PeerInfo info(PeerId peer, PeerState state) const;

  std::map<PeerId, Link> links_;
  std::deque<PeerId> departed_;  // oldest first
};

}  // namespace csculpt::peer
