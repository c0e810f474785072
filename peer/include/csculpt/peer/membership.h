// Who is in a session and who merges: heartbeat-based membership with two thresholds (zyre's
// evasive / expired) and an epoch-numbered election whose rule is deterministic (the live
// peer with the lowest id). Pure logic: time is passed in, so tests drive it with their own
// clock and no sockets.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace csculpt::peer {

using PeerId = std::uint64_t;
using Clock = std::chrono::steady_clock;
using Millis = std::chrono::milliseconds;

struct MembershipOptions {
  Millis heartbeat{200};  ///< how often a peer says it is alive
  Millis evasive{600};    ///< silent this long: evasive (reported, still a member)
  Millis expired{1200};   ///< silent this long: gone (removed; a merger re-elected)
};

struct Member {
  PeerId id = 0;
  std::string endpoint;
  Clock::time_point last_heard{};
  bool evasive = false;
  bool heard_directly = false;  ///< heard from it, not only of it (gossip)
};

/// The members one peer knows of, itself included.
class Membership {
 public:
  Membership(PeerId self, std::string self_endpoint, MembershipOptions options = {});

  struct Changes {
    std::vector<PeerId> joined;   ///< heard of for the first time
    std::vector<PeerId> evasive;  ///< crossed the evasive threshold
    std::vector<PeerId> expired;  ///< crossed the expired threshold, removed
    bool empty() const { return joined.empty() && evasive.empty() && expired.empty(); }
  };

  /// We heard from `peer` (any verified message) at `now`. Returns true if it is new. A peer
  /// that was evasive is live again: take_revived() lists it.
  bool heard(PeerId peer, const std::string& endpoint, Clock::time_point now);
  /// The peers reported evasive that were heard again since the last call.
  std::vector<PeerId> take_revived();
  /// We learnt of `peer` from someone else (gossip): added as if heard at `now`, so an
  /// unreachable one expires after the threshold. Returns true if it is new.
  bool learnt(PeerId peer, const std::string& endpoint, Clock::time_point now);
  /// `peer` said it leaves at `now` (or is known dead): removed at once, and gossip about it
  /// is not believed for a while (as after an expiry).
  bool remove(PeerId peer, Clock::time_point now);
  /// Applies the thresholds at `now`: marks evasive peers, removes expired ones.
  Changes tick(Clock::time_point now);

  PeerId self() const { return self_; }
  bool contains(PeerId peer) const { return members_.count(peer) != 0; }
  /// Every member, self included, in increasing id order.
  std::vector<PeerId> ids() const;
  const std::map<PeerId, Member>& members() const { return members_; }
  /// The others (not self), in increasing id order.
  std::vector<const Member*> others() const;
  /// The members a heartbeat vouches for, in increasing id order: self and those heard from
  /// directly and not evasive. A peer only gossiped about, or gone silent, is not passed on:
  /// survivors that relayed a dead peer to one another learnt it back from each other, each
  /// once its tombstone aged, and kept it joining and expiring after it died.
  std::vector<const Member*> vouched() const;
  const MembershipOptions& options() const { return options_; }

 private:
  PeerId self_;
  MembershipOptions options_;
  std::map<PeerId, Member> members_;
  /// Peers seen to expire: gossip about them is not believed for a while.
  std::map<PeerId, Clock::time_point> tombstones_;
  std::vector<PeerId> revived_;  // evasive, then heard again: not yet taken
};

/// One merger per epoch (Raft's one leader per term), chosen by a deterministic rule among
/// live peers: the lowest id. A peer that finds the merger gone and itself the lowest live id
/// starts epoch + 1 and announces it. Announcements (and versions) of a stale epoch are
/// ignored, so two mergers never both publish a version a peer accepts. A claim is followed only
/// if it agrees with the rule as this peer sees it: a higher id never displaces a live merger
/// with a lower id, whatever epoch it claims (a forged epoch gains nothing); when the rightful
/// merger hears such a claim it re-asserts itself with a higher epoch, which also reunites
/// peers whose views of who is alive differed for a while.
class Election {
 public:
  explicit Election(PeerId self) : self_(self) {}

  /// What this peer should announce, if anything, given the live members.
  struct Decision {
    bool announce = false;  ///< we became the merger of epoch(): tell everyone
    bool changed = false;   ///< the merger changed (to us or to someone else)
  };
  Decision update(const Membership& membership);

  struct Outcome {
    bool followed = false;  ///< the claimant is our merger now (it changed)
    bool reassert = false;  ///< we are the rightful merger: announce epoch() again
  };
  /// A claim by `claimant` to merge `epoch`.
  Outcome on_announcement(std::uint64_t epoch, PeerId claimant, const Membership& membership);

  /// Claims of this epoch or beyond are refused as forged (no session holds 2^62 elections).
  static constexpr std::uint64_t kMaxEpoch = std::uint64_t{1} << 62;

  /// Whether a message of `epoch` about merging (versions, elections) is stale.
  bool is_stale(std::uint64_t epoch) const { return epoch < epoch_; }

  std::uint64_t epoch() const { return epoch_; }
  std::optional<PeerId> merger() const { return merger_; }
  bool is_merger() const { return merger_ == self_; }

 private:
  PeerId self_;
  std::uint64_t epoch_ = 0;
  std::optional<PeerId> merger_;
};

}  // namespace csculpt::peer
