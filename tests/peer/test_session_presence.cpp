// Presence, peer info and revived peers in real sessions over loopback sockets: cursors reach
// every member with their values, at most 20 a second, and go with their peer; a malformed or
// late presence is dropped; names, versions and round trips come through; a peer heard again
// after a stall is reported live.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"
#include "fake_peer.h"
#include "sessions.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;
using namespace std::chrono_literals;

std::optional<PeerPresence> presence_of(const Session& s, PeerId peer) {
  for (const PeerPresence& p : s.presence())
    if (p.peer == peer) return p;
  return std::nullopt;
}

std::optional<PeerInfo> peer_info(const Session& s, PeerId peer) {
  for (const PeerInfo& p : s.peers())
    if (p.id == peer) return p;
  return std::nullopt;
}

Presence cursor(float x, float radius, bool active, std::uint32_t rgba = 0) {
  Presence p;
  p.position = {x, 0.5f, -0.25f};
  p.radius = radius;
  p.active = active;
  p.visible = true;
  p.rgba = rgba;
  return p;
}

struct Trio {
  const Mesh sphere = make_sphere(500);
  std::unique_ptr<Session> a = Session::create(sphere, fast_options(1, "ana"));
  std::unique_ptr<Session> b = Session::join(a->invite(), fast_options(2, "ben"));
  std::unique_ptr<Session> c = Session::join(a->invite(), fast_options(3, "cy"));
  bool everyone_knows_everyone() const {
    return a->stats().members == 3 && b->stats().members == 3 && c->stats().members == 3;
  }
};

TEST(SessionPresence, ReachesEveryMemberWithItsValuesAndColour) {
  Trio t;
  ASSERT_TRUE(wait_until([&] { return t.everyone_knows_everyone(); }));
  t.a->set_presence(cursor(0.75f, 0.125f, true));
  t.b->set_presence(cursor(-1.f, 0.5f, false, 0x00ff00ffu));
  for (Session* s : {t.b.get(), t.c.get()}) {
    ASSERT_TRUE(wait_until([&] { return presence_of(*s, 1).has_value(); })) << s->id();
    const PeerPresence p = *presence_of(*s, 1);
    EXPECT_EQ(p.presence, cursor(0.75f, 0.125f, true));
    EXPECT_LT(p.age, 1000ms);
    // Nobody contributed yet: peer 1 is the first member by id, so the first hue.
    EXPECT_EQ(p.colour, peer_colour(0));
  }
  ASSERT_TRUE(wait_until([&] { return presence_of(*t.c, 2).has_value(); }));
  EXPECT_EQ(presence_of(*t.c, 2)->colour, (std::array<float, 3>{0.f, 1.f, 0.f}));  // its own
  EXPECT_FALSE(presence_of(*t.c, 3).has_value());                                  // not our own
  EXPECT_FALSE(presence_of(*t.a, 3).has_value());  // c never set one
  EXPECT_THROW(t.a->set_presence(cursor(std::nanf(""), 0.1f, false)), InvalidInput);
}

TEST(SessionPresence, IsSentAtMostTwentyTimesASecondWhateverTheHostSets) {
  Trio t;
  ASSERT_TRUE(wait_until([&] { return t.everyone_knows_everyone(); }));
  const auto start = Clock::now();
  for (int i = 0; i < 1000; ++i) {
    t.a->set_presence(cursor(float(i), 0.1f, true));
    std::this_thread::sleep_until(start + i * 1ms);
  }
  const Presence last = cursor(999.f, 0.1f, true);
  ASSERT_TRUE(wait_until([&] {
    auto p = presence_of(*t.b, 1);
    return p && p->presence == last;
  }));
  // Every message carries the next sequence number: the last one received counts them all.
  const std::uint64_t sent = presence_of(*t.b, 1)->sequence;
  EXPECT_LE(sent, 25u);
  EXPECT_GE(sent, 10u);  // it did send along the way, not only the last value
  // Unchanged, it comes again about once a second (late joiners see it), no more.
  std::this_thread::sleep_for(1300ms);
  const std::uint64_t later = presence_of(*t.b, 1)->sequence;
  EXPECT_GE(later, sent + 1);
  EXPECT_LE(later, sent + 2);
}

TEST(SessionPresence, GoesWithAPeerThatLeaves) {
  Trio t;
  ASSERT_TRUE(wait_until([&] { return t.everyone_knows_everyone(); }));
  t.c->set_presence(cursor(0.1f, 0.2f, false));
  ASSERT_TRUE(wait_until([&] { return presence_of(*t.a, 3) && presence_of(*t.b, 3); }));
  t.c->leave();
  ASSERT_TRUE(wait_until([&] { return !presence_of(*t.a, 3) && !presence_of(*t.b, 3); }));
  ASSERT_TRUE(wait_until([&] { return peer_info(*t.a, 3).has_value(); }));
  const PeerInfo gone = *peer_info(*t.a, 3);
  EXPECT_EQ(gone.state, PeerState::left);
  EXPECT_EQ(gone.name, "cy");  // still named in the list
}

TEST(SessionPeers, NamesVersionsMergerAndRoundTrips) {
  Trio t;
  ASSERT_TRUE(wait_until([&] {
    for (Session* s : {t.a.get(), t.b.get(), t.c.get()}) {
      const std::vector<PeerInfo> peers = s->peers();
      if (peers.size() != 2) return false;
      for (const PeerInfo& p : peers)
        if (p.latency_ms < 0 || p.name.empty()) return false;
    }
    return true;
  }));
  const PeerInfo ana = *peer_info(*t.b, 1), cy = *peer_info(*t.b, 3);
  EXPECT_EQ(ana.name, "ana");
  EXPECT_EQ(cy.name, "cy");
  EXPECT_EQ(peer_info(*t.a, 2)->name, "ben");
  EXPECT_TRUE(ana.merger);
  EXPECT_FALSE(cy.merger);
  EXPECT_EQ(ana.state, PeerState::live);
  for (const PeerInfo& p : {ana, cy}) {
    EXPECT_TRUE(std::isfinite(p.latency_ms));
    EXPECT_GT(p.latency_ms, 0.0);
    EXPECT_LT(p.latency_ms, 1000.0);
  }
  // Versions as heartbeats report them: a merged stroke moves everyone's.
  Mesh local = t.a->base();
  local.positions[0].x += 0.1f;
  t.a->submit(local, 1);
  ASSERT_TRUE(wait_until([&] {
    t.a->update(local);
    return t.a->version() >= 1 && peer_info(*t.c, 1)->version >= 1;
  }));
}

TEST(SessionPresence, MalformedOrLatePresenceIsDropped) {
  const Mesh sphere = make_sphere(300);
  auto a = Session::create(sphere, fast_options(1));
  FakePeer fake(a->invite(), 99);
  fake.hello();
  fake.pump(50ms, 20ms);
  ASSERT_TRUE(wait_until([&] { return a->stats().members == 2; }));
  auto send = [&](std::uint64_t sequence, Presence p) {
    fake.send(presence_message(fake.header(), sequence, p));
    fake.pump(30ms, 20ms);
  };
  send(5, cursor(2.f, 0.1f, false));
  ASSERT_TRUE(wait_until([&] { return presence_of(*a, 99).has_value(); }));
  EXPECT_EQ(presence_of(*a, 99)->presence.position.x, 2.f);
  const std::uint64_t dropped = a->stats().messages_dropped;
  send(4, cursor(3.f, 0.1f, false));  // late
  send(5, cursor(4.f, 0.1f, false));  // duplicate
  send(6, cursor(std::numeric_limits<float>::quiet_NaN(), 0.1f, false));
  send(7, cursor(5.f, -1.f, false));  // negative radius
  // A later valid one still comes through (so the ones above were seen and refused).
  send(8, cursor(6.f, 0.1f, false));
  ASSERT_TRUE(wait_until([&] { return presence_of(*a, 99)->presence.position.x == 6.f; }));
  EXPECT_EQ(a->stats().messages_dropped, dropped + 2);  // the NaN and the negative radius
  EXPECT_EQ(presence_of(*a, 99)->sequence, 8u);
  bool told = false;
  for (const Event& e : a->poll_events())
    told |= e.kind == EventKind::dropped && e.message.find("position.x") != std::string::npos;
  EXPECT_TRUE(told);
}

TEST(SessionPeers, APeerHeardAgainAfterAStallIsReportedLive) {
  const Mesh sphere = make_sphere(300);
  SessionOptions o = fast_options(1);
  o.membership = {Millis{50}, Millis{200}, Millis{1500}};  // a stall that is not an expiry
  auto a = Session::create(sphere, o);
  FakePeer fake(a->invite(), 99);
  fake.hello();
  fake.pump(200ms, 40ms);
  ASSERT_TRUE(peer_info(*a, 99).has_value());
  ASSERT_EQ(peer_info(*a, 99)->state, PeerState::live);
  fake.pump(600ms);  // stalled: it says nothing, as under SIGSTOP
  ASSERT_TRUE(wait_until([&] { return peer_info(*a, 99)->state == PeerState::evasive; }, 500ms));
  fake.pump(200ms, 40ms);  // SIGCONT
  ASSERT_TRUE(wait_until([&] { return peer_info(*a, 99)->state == PeerState::live; }, 500ms));
  std::vector<EventKind> kinds;
  for (const Event& e : a->poll_events())
    if (e.peer == 99) kinds.push_back(e.kind);
  EXPECT_EQ(kinds, (std::vector<EventKind>{EventKind::peer_joined, EventKind::peer_evasive,
                                           EventKind::peer_live}));
}

}  // namespace
