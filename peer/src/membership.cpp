#include "csculpt/peer/membership.h"

#include <algorithm>

namespace csculpt::peer {

Membership::Membership(PeerId self, std::string self_endpoint, MembershipOptions options)
    : self_(self), options_(options) {
  members_[self] = Member{self, std::move(self_endpoint), {}, false, true};
}

bool Membership::heard(PeerId peer, const std::string& endpoint, Clock::time_point now) {
  if (peer == self_) return false;
  tombstones_.erase(peer);  // a peer we hear from directly is alive, whatever we thought
  auto [it, inserted] = members_.try_emplace(peer, Member{peer, endpoint, now, false, true});
  if (!inserted) {
    it->second.last_heard = now;
    it->second.heard_directly = true;
    if (it->second.evasive) revived_.push_back(peer);
    it->second.evasive = false;
    if (!endpoint.empty()) it->second.endpoint = endpoint;
  }
  return inserted;
}

std::vector<PeerId> Membership::take_revived() {
  std::vector<PeerId> out;
  out.swap(revived_);
  return out;
}

bool Membership::learnt(PeerId peer, const std::string& endpoint, Clock::time_point now) {
  if (peer == self_ || members_.count(peer) || endpoint.empty()) return false;
  // Gossip about a peer we saw expire is not believed until the tombstone ages out: the
  // others may simply not have noticed yet.
  if (auto t = tombstones_.find(peer); t != tombstones_.end()) {
    if (now - t->second < 2 * options_.expired) return false;
    tombstones_.erase(t);
  }
  members_.emplace(peer, Member{peer, endpoint, now, false, false});
  return true;
}

bool Membership::remove(PeerId peer, Clock::time_point now) {
  if (peer == self_) return false;
  // As after an expiry: members that have not yet heard it leave still gossip it.
  tombstones_[peer] = now;
  return members_.erase(peer) != 0;
}

Membership::Changes Membership::tick(Clock::time_point now) {
  Changes c;
  for (auto it = members_.begin(); it != members_.end();) {
    Member& m = it->second;
    if (m.id == self_) {
      ++it;
      continue;
    }
    const auto silent = now - m.last_heard;
    if (silent >= options_.expired) {
      c.expired.push_back(m.id);
      tombstones_[m.id] = now;
      it = members_.erase(it);
      continue;
    }
    if (silent >= options_.evasive && !m.evasive) {
      m.evasive = true;
      c.evasive.push_back(m.id);
    }
    ++it;
  }
  return c;
}

std::vector<PeerId> Membership::ids() const {
  std::vector<PeerId> v;
  v.reserve(members_.size());
  for (const auto& [id, m] : members_) v.push_back(id);
  return v;
}

std::vector<const Member*> Membership::others() const {
  std::vector<const Member*> v;
  for (const auto& [id, m] : members_)
    if (id != self_) v.push_back(&m);
  return v;
}

std::vector<const Member*> Membership::vouched() const {
  std::vector<const Member*> v;
  for (const auto& [id, m] : members_)
    if (m.heard_directly && !m.evasive) v.push_back(&m);
  return v;
}

Election::Decision Election::update(const Membership& membership) {
  Decision d;
  const PeerId lowest = membership.ids().front();  // self is always a member
  const bool merger_alive = merger_ && membership.contains(*merger_);
  if (merger_alive) return d;
  // No live merger: the lowest live id takes the next epoch. Others wait for its announcement
  // (if it never comes, it expires too and the next lowest takes over).
  if (lowest == self_) {
    ++epoch_;
    merger_ = self_;
    d.announce = true;
    d.changed = true;
  } else if (merger_) {
    merger_.reset();
    d.changed = true;
  }
  return d;
}

Election::Outcome Election::on_announcement(std::uint64_t epoch, PeerId claimant,
                                            const Membership& membership) {
  Outcome o;
  // A claimant we do not know, or know to be dead, is not followed (forged or stale). Epochs
  // grow by one per election (or one past a claim when re-asserting): one at 2^62 or beyond is
  // forged, and refusing it keeps every increment far from wrapping around.
  if (!membership.contains(claimant) || epoch >= kMaxEpoch) return o;
  if (merger_ == claimant) {
    epoch_ = std::max(epoch_, epoch);
    return o;
  }
  const bool merger_alive = merger_ && membership.contains(*merger_);
  if (merger_alive && *merger_ < claimant) {
    // The rule says our merger, not the claimant. If that is us, tell everyone again with an
    // epoch past the claim, so the claimant and its followers come back.
    if (is_merger() && epoch >= epoch_) {
      epoch_ = epoch + 1;
      o.reassert = true;
    }
    return o;
  }
  if (epoch < epoch_) return o;
  epoch_ = epoch;
  merger_ = claimant;
  o.followed = true;
  return o;
}

}  // namespace csculpt::peer
