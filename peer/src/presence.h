// Presence (brush cursors, protocol.md "Presence"): the sender's rate limit, the receivers'
// table of the latest cursor of each peer, and the colour a receiver draws a cursor in. Pure
// logic: time is passed in, no sockets, no threads.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <span>

#include "csculpt/peer/membership.h"
#include "csculpt/peer/session.h"

namespace csculpt::peer {

/// When this peer sends its presence: a change at most every `min_interval` (20 Hz by
/// default), the unchanged value again every `refresh` (a late joiner sees it, and receivers
/// know the sender still hovers). Every message gets the next sequence number.
class PresenceSender {
 public:
  explicit PresenceSender(Millis min_interval = Millis{50}, Millis refresh = Millis{1000})
      : min_interval_(min_interval), refresh_(refresh) {}

  /// The next time to send, given whether the host changed its presence since the last send
  /// and whether it ever set one (max() when there is nothing to send).
  Clock::time_point next_send(bool changed, bool any) const;
  bool due(bool changed, bool any, Clock::time_point now) const {
    return any && now >= next_send(changed, any);
  }
  /// A message leaves at `now`: its sequence number.
  std::uint64_t sent(Clock::time_point now);

 private:
  Millis min_interval_, refresh_;
  Clock::time_point last_{};
  std::uint64_t sequence_ = 0;
};

/// A peer's presence as received.
struct ReceivedPresence {
  Presence presence;
  std::uint64_t sequence = 0;
  Clock::time_point at{};
};

/// The latest presence of each peer: a message older than (or the same as) the one held is
/// dropped, so late and duplicate messages never move a cursor back.
class PresenceTable {
 public:
  /// False (nothing changes) when `sequence` is not newer than the one held for `peer`.
  bool accept(PeerId peer, std::uint64_t sequence, const Presence& p, Clock::time_point now);
  /// `peer` left or expired: its cursor goes (a later return starts its numbering afresh).
  void forget(PeerId peer) { latest_.erase(peer); }
  const std::map<PeerId, ReceivedPresence>& latest() const { return latest_; }

 private:
  std::map<PeerId, ReceivedPresence> latest_;
};

/// What a receiver draws `peer`'s cursor in: the sender's `rgba` if it gave one (alpha not 0),
/// else the colour the attribution view gives it: peer_colour of its rank among the
/// `contributors` (increasing id, as attribution_colours ranks them), peers that have not
/// contributed yet ranked after them among `members` (both sorted, increasing).
std::array<float, 3> presence_colour(PeerId peer, std::uint32_t rgba,
                                     std::span<const PeerId> contributors,
                                     std::span<const PeerId> members);

}  // namespace csculpt::peer
