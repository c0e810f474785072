// Presence and the peer table without sockets: the sender's rate limit, the receivers' order
// check, the colours, round trips from heartbeat echoes, and a revived member.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "peer_table.h"
#include "presence.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace std::chrono_literals;

Presence at(float x, float radius = 0.1f) {
  Presence p;
  p.position = {x, 0, 0};
  p.radius = radius;
  p.visible = true;
  return p;
}

TEST(PresenceSender, SendsAChangeAtMostEvery50msAndTheSameAgainEverySecond) {
  PresenceSender s;
  const Clock::time_point t0 = Clock::now();
  EXPECT_FALSE(s.due(true, false, t0));  // nothing set yet
  ASSERT_TRUE(s.due(true, true, t0));
  EXPECT_EQ(s.sent(t0), 1u);
  EXPECT_FALSE(s.due(true, true, t0 + 49ms));
  EXPECT_TRUE(s.due(true, true, t0 + 50ms));
  EXPECT_FALSE(s.due(false, true, t0 + 999ms));  // unchanged: only the refresh
  EXPECT_TRUE(s.due(false, true, t0 + 1000ms));
  EXPECT_EQ(s.sent(t0 + 1000ms), 2u);
  EXPECT_EQ(s.next_send(true, true), t0 + 1050ms);
  EXPECT_EQ(s.next_send(false, false), Clock::time_point::max());
}

TEST(PresenceTable, KeepsOnlyNewerPresenceAndForgetsAPeer) {
  PresenceTable t;
  const Clock::time_point t0 = Clock::now();
  EXPECT_TRUE(t.accept(7, 5, at(1), t0));
  EXPECT_FALSE(t.accept(7, 5, at(2), t0 + 1ms));  // duplicate
  EXPECT_FALSE(t.accept(7, 3, at(3), t0 + 2ms));  // late
  EXPECT_EQ(t.latest().at(7).presence.position.x, 1.f);
  EXPECT_EQ(t.latest().at(7).at, t0);
  EXPECT_TRUE(t.accept(7, 6, at(4), t0 + 3ms));
  EXPECT_EQ(t.latest().at(7).presence.position.x, 4.f);
  t.forget(7);
  EXPECT_TRUE(t.latest().empty());
  EXPECT_TRUE(t.accept(7, 1, at(5), t0 + 4ms));  // a returning peer numbers afresh
}

TEST(PresenceValidation, NamesTheFieldThatIsWrong) {
  auto message = [](Presence p) {
    try {
      validate_presence(p);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message(at(1)), "");
  Presence nan_y = at(1);
  nan_y.position.y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(message(nan_y).find("position.y"), std::string::npos);
  EXPECT_NE(message(at(1, std::numeric_limits<float>::infinity())).find("radius is not finite"),
            std::string::npos);
  EXPECT_NE(message(at(1, -0.5f)).find("radius is negative"), std::string::npos);
}

TEST(PresenceColour, TheSendersOwnElseItsAttributionColour) {
  const std::vector<PeerId> contributors = {4, 9}, members = {2, 4, 6, 9};
  const auto own = presence_colour(6, 0xff800000u | 0xffu, contributors, members);
  EXPECT_FLOAT_EQ(own[0], 1.f);
  EXPECT_NEAR(own[1], 128.f / 255.f, 1e-6);
  EXPECT_FLOAT_EQ(own[2], 0.f);
  // Contributors rank as attribution_colours ranks them; the others come after them.
  EXPECT_EQ(presence_colour(4, 0, contributors, members), peer_colour(0));
  EXPECT_EQ(presence_colour(9, 0, contributors, members), peer_colour(1));
  EXPECT_EQ(presence_colour(2, 0, contributors, members), peer_colour(2));
  EXPECT_EQ(presence_colour(6, 0, contributors, members), peer_colour(3));
  EXPECT_EQ(presence_colour(6, 0xffffff00u, contributors, members), peer_colour(3));  // alpha 0
  // The same hue as the attribution view gives the first contributor's vertices.
  const std::vector<float> rgb = attribution_colours({{4, {1.f}}, {9, {0.f}}}, 1);
  EXPECT_EQ(rgb[0], peer_colour(0)[0]);
  EXPECT_EQ(rgb[1], peer_colour(0)[1]);
}

TEST(PeerTable, RoundTripIsTheEchoMinusTheTimeItWasHeld) {
  PeerTable t;
  Membership m(1, "tcp://me", {});
  const Clock::time_point t0 = Clock::now();
  m.heard(2, "tcp://two", t0);
  t.named(2, "ben");
  // Peer 2 held our heartbeat (sent at t0) 30 ms; the echo came back at t0 + 50 ms: 20 ms.
  t.echoed(2, fb::Echo(2, micros(t0), 30000), t0 + 50ms);
  std::vector<PeerInfo> list = t.list(m, PeerId{2}, {{2, {7, 0}}});
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].name, "ben");
  EXPECT_NEAR(list[0].latency_ms, 20.0, 1e-3);
  EXPECT_TRUE(list[0].merger);
  EXPECT_EQ(list[0].version, 7u);
  EXPECT_EQ(list[0].state, PeerState::live);
  // Smoothed: a 60 ms sample moves it a quarter of the way.
  t.echoed(2, fb::Echo(2, micros(t0), 0), t0 + 60ms);
  EXPECT_NEAR(t.list(m, {}, {})[0].latency_ms, 30.0, 1e-3);
  // An echo from another clock (in our future) is ignored.
  t.echoed(2, fb::Echo(2, micros(t0 + 1h), 0), t0 + 70ms);
  EXPECT_NEAR(t.list(m, {}, {})[0].latency_ms, 30.0, 1e-3);
  // What we echo back: their clock, and how long we held it.
  t.heartbeat_from(2, 12345, t0);
  const std::vector<fb::Echo> echoes = t.echoes(t0 + 8ms);
  ASSERT_EQ(echoes.size(), 1u);
  EXPECT_EQ(echoes[0].peer(), 2u);
  EXPECT_EQ(echoes[0].sent_us(), 12345u);
  EXPECT_EQ(echoes[0].held_us(), 8000u);
}

TEST(PeerTable, ListsTheLatestDepartedAsLeft) {
  PeerTable t;
  Membership m(1, "tcp://me", {});
  t.named(3, "cy");
  for (PeerId p = 100; p < 100 + kKeptDeparted + 3; ++p) t.departed(p);
  t.departed(3);
  const std::vector<PeerInfo> list = t.list(m, {}, {});
  ASSERT_EQ(list.size(), kKeptDeparted);
  EXPECT_EQ(list.back().id, 3u);
  EXPECT_EQ(list.back().name, "cy");
  EXPECT_EQ(list.back().state, PeerState::left);
  EXPECT_TRUE(t.echoes(Clock::now()).empty());  // nothing to echo to those who left
}

TEST(Membership, AnEvasivePeerHeardAgainIsRevivedOnce) {
  Membership m(1, "tcp://me", {Millis{50}, Millis{200}, Millis{400}});
  const Clock::time_point t0 = Clock::now();
  m.heard(2, "tcp://two", t0);
  m.heard(2, "", t0 + 10ms);
  EXPECT_TRUE(m.take_revived().empty());  // never evasive
  EXPECT_EQ(m.tick(t0 + 250ms).evasive, std::vector<PeerId>{2});
  m.heard(2, "", t0 + 300ms);
  m.heard(2, "", t0 + 310ms);
  EXPECT_EQ(m.take_revived(), std::vector<PeerId>{2});
  EXPECT_TRUE(m.take_revived().empty());
}

}  // namespace
