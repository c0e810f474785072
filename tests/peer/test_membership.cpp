// Membership thresholds and the election, driven by a clock the test controls.
#include <gtest/gtest.h>

#include <vector>

#include "csculpt/peer/membership.h"

namespace {

using namespace csculpt::peer;
using namespace std::chrono_literals;

MembershipOptions thresholds() {
  return {Millis{100}, Millis{300}, Millis{600}};
}

TEST(Membership, EvasiveThenExpiredThenGone) {
  const Clock::time_point t0{};
  Membership m(5, "tcp://a", thresholds());
  EXPECT_TRUE(m.heard(7, "tcp://b", t0));
  EXPECT_FALSE(m.heard(7, "", t0 + 50ms));  // known: refreshed, endpoint kept
  EXPECT_EQ(m.members().at(7).endpoint, "tcp://b");
  EXPECT_TRUE(m.tick(t0 + 340ms).empty());
  auto c = m.tick(t0 + 360ms);
  ASSERT_EQ(c.evasive, std::vector<PeerId>{7});
  EXPECT_TRUE(m.tick(t0 + 400ms).empty());  // reported once
  c = m.tick(t0 + 650ms);
  ASSERT_EQ(c.expired, std::vector<PeerId>{7});
  EXPECT_FALSE(m.contains(7));
  EXPECT_EQ(m.ids(), std::vector<PeerId>{5});
}

TEST(Membership, GossipAboutAnExpiredPeerIsNotBelievedAtOnce) {
  const Clock::time_point t0{};
  Membership m(5, "tcp://a", thresholds());
  m.heard(7, "tcp://b", t0);
  m.tick(t0 + 700ms);
  EXPECT_FALSE(m.learnt(7, "tcp://b", t0 + 800ms));  // others have not noticed yet
  EXPECT_TRUE(m.learnt(7, "tcp://b", t0 + 700ms + 1300ms));
  EXPECT_TRUE(m.heard(9, "tcp://c", t0));  // direct contact is always believed
}

// A member that has not yet heard a peer leave still lists it in its heartbeats: that gossip
// must not bring the peer back (its cursor gone, it showed as live until it expired again).
TEST(Membership, GossipAboutAPeerThatLeftIsNotBelievedAtOnce) {
  const Clock::time_point t0{};
  Membership m(5, "tcp://a", thresholds());
  m.heard(7, "tcp://b", t0);
  EXPECT_TRUE(m.remove(7, t0 + 100ms));
  EXPECT_FALSE(m.learnt(7, "tcp://b", t0 + 200ms));
  EXPECT_FALSE(m.contains(7));
  EXPECT_TRUE(m.learnt(7, "tcp://b", t0 + 100ms + 1300ms));
}

// What a heartbeat passes on: self and the peers heard from directly, not evasive. Survivors
// of a dead peer that relayed it to one another learnt it back from each other as their
// tombstones aged, and it kept joining and expiring on a healthy network after it died.
TEST(Membership, HeartbeatsVouchOnlyForPeersHeardDirectlyAndNotSilent) {
  const Clock::time_point t0{};
  Membership m(5, "tcp://a", thresholds());
  m.heard(7, "tcp://b", t0);
  m.learnt(9, "tcp://c", t0);  // only gossiped about
  auto ids = [&] {
    std::vector<PeerId> v;
    for (const Member* x : m.vouched()) v.push_back(x->id);
    return v;
  };
  EXPECT_EQ(ids(), (std::vector<PeerId>{5, 7}));
  m.heard(9, "", t0 + 100ms);
  EXPECT_EQ(ids(), (std::vector<PeerId>{5, 7, 9}));
  m.heard(9, "", t0 + 200ms);
  m.tick(t0 + 350ms);  // 7 silent past the evasive threshold
  EXPECT_EQ(ids(), (std::vector<PeerId>{5, 9}));
  m.heard(7, "", t0 + 400ms);
  EXPECT_EQ(ids(), (std::vector<PeerId>{5, 7, 9}));
}

TEST(Election, LowestLivePeerMergesAndAnnouncesANewEpoch) {
  const Clock::time_point t0{};
  Membership m(5, "tcp://a", thresholds());
  m.heard(3, "tcp://b", t0);
  m.heard(9, "tcp://c", t0);
  Election e(5);
  auto d = e.update(m);
  EXPECT_FALSE(d.announce);  // 3 is lower: wait for its announcement
  EXPECT_FALSE(e.merger());
  EXPECT_TRUE(e.on_announcement(1, 3, m).followed);
  EXPECT_EQ(e.merger(), PeerId{3});
  EXPECT_EQ(e.epoch(), 1u);
  // 3 dies: 5 is now the lowest live id and starts epoch 2
  m.tick(t0 + 700ms);
  m.heard(9, "", t0 + 700ms);
  EXPECT_FALSE(m.contains(3));
  d = e.update(m);
  EXPECT_TRUE(d.announce);
  EXPECT_TRUE(e.is_merger());
  EXPECT_EQ(e.epoch(), 2u);
  // messages of epoch 1 are stale now; a late announcement of epoch 1 changes nothing
  EXPECT_TRUE(e.is_stale(1));
  EXPECT_FALSE(e.on_announcement(1, 3, m).followed);
  EXPECT_TRUE(e.is_merger());
}

TEST(Election, TwoClaimsOfOneEpochSettleOnTheLowerId) {
  const Clock::time_point t0{};
  Membership ma(4, "a", thresholds()), mb(6, "b", thresholds());
  Election a(4), b(6);
  // b did not know a yet and claimed epoch 1; a knows both and claims epoch 1 too.
  ASSERT_TRUE(b.update(mb).announce);
  ma.heard(6, "b", t0);
  mb.heard(4, "a", t0);
  ASSERT_TRUE(a.update(ma).announce);
  const auto oa = a.on_announcement(1, 6, ma);  // a keeps its own claim and re-asserts it
  EXPECT_FALSE(oa.followed);
  EXPECT_TRUE(oa.reassert);
  EXPECT_EQ(a.epoch(), 2u);
  EXPECT_TRUE(b.on_announcement(1, 4, mb).followed);   // b yields to the lower id
  EXPECT_FALSE(b.on_announcement(2, 4, mb).followed);  // the re-assertion: same merger
  EXPECT_EQ(a.merger(), b.merger());
  EXPECT_EQ(a.epoch(), b.epoch());
}

TEST(Election, AClaimantThatIsNotAMemberIsNotFollowed) {
  Membership m(5, "a", thresholds());
  Election e(5);
  EXPECT_FALSE(e.on_announcement(3, 99, m).followed);  // forged or long dead
  EXPECT_FALSE(e.merger());
}

TEST(Election, AForgedHigherEpochFromAHigherIdDoesNotDisplaceALiveMerger) {
  const Clock::time_point t0{};
  Membership m(5, "a", thresholds());
  m.heard(3, "b", t0);
  m.heard(8, "c", t0);
  Election e(5);
  ASSERT_TRUE(e.on_announcement(1, 3, m).followed);
  const auto o = e.on_announcement(999, 8, m);
  EXPECT_FALSE(o.followed);
  EXPECT_FALSE(o.reassert);  // not ours to re-assert: 3 merges
  EXPECT_EQ(e.merger(), PeerId{3});
  EXPECT_EQ(e.epoch(), 1u);
  // The merger itself, hearing the forged claim, re-asserts past it.
  Membership m3(3, "b", thresholds());
  m3.heard(8, "c", t0);
  Election e3(3);
  ASSERT_TRUE(e3.update(m3).announce);
  const auto r = e3.on_announcement(999, 8, m3);
  EXPECT_TRUE(r.reassert);
  EXPECT_EQ(e3.epoch(), 1000u);
  EXPECT_TRUE(e3.is_merger());
}

TEST(Election, ForgedEpochsNearTheTopAreRefusedSoElectionsNeverWrap) {
  const Clock::time_point t0{};
  Membership m(5, "a", thresholds());
  m.heard(3, "b", t0);
  Election e(5);
  ASSERT_TRUE(e.on_announcement(1, 3, m).followed);
  // A third party names our merger with the largest epoch: nothing changes.
  e.on_announcement(~std::uint64_t{0}, 3, m);
  e.on_announcement(Election::kMaxEpoch, 3, m);
  EXPECT_EQ(e.epoch(), 1u);
  // The merger dies: the next epoch follows the real one.
  m.tick(t0 + 700ms);
  ASSERT_TRUE(e.update(m).announce);
  EXPECT_EQ(e.epoch(), 2u);
}

}  // namespace
