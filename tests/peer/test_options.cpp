// SessionOptions checked by the peer layer itself: a C++ caller gets a clear InvalidInput.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;

std::string refusal(const std::function<void(SessionOptions&)>& change) {
  SessionOptions o;
  change(o);
  try {
    validate_options(o);
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "accepted";
}

bool mentions(const std::string& message, const std::string& what) {
  return message.find(what) != std::string::npos;
}

TEST(SessionOptions, DefaultsAndTheTestsFastOptionsAreValid) {
  EXPECT_EQ(refusal([](SessionOptions&) {}), "accepted");
  EXPECT_EQ(refusal([](SessionOptions& o) {
              o.sync = Millis{30};
              o.membership = {Millis{50}, Millis{200}, Millis{400}};
              o.wire.position_tolerance = 0;
              o.wire.channel_tolerance = 0;
            }),
            "accepted");
}

TEST(SessionOptions, RefusesIntervalsOutOfRange) {
  const std::string zero = refusal([](SessionOptions& o) { o.sync = Millis{0}; });
  EXPECT_TRUE(mentions(zero, "sync is 0 ms")) << zero;
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.sync = Millis{-5}; }), "sync"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.sync = std::chrono::hours{2}; }), "sync"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.membership.heartbeat = Millis{0}; }),
                       "heartbeat"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.membership.evasive = Millis{100}; }),
                       "heartbeat < evasive < expired"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.membership.expired = Millis{600}; }),
                       "heartbeat < evasive < expired"));
}

TEST(SessionOptions, RefusesNegativeNonFiniteOrAbsurdTolerances) {
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.position_tolerance = -1e-5; }),
                       "wire.position_tolerance"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.position_tolerance = NAN; }),
                       "wire.position_tolerance"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.position_tolerance = 5; }),
                       "wire.position_tolerance"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.channel_tolerance = INFINITY; }),
                       "wire.channel_tolerance"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.channel_tolerance = -1; }),
                       "wire.channel_tolerance"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.position_scale = -2; }),
                       "wire.position_scale"));
  // Issue 12, finding 8: steps so coarse that strokes round to nothing on the wire (and are
  // still counted acknowledged) are refused, with the range in words.
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.position_tolerance = 1e30; }),
                       "must be 0 (lossless) to 0.01 (a fraction of the session's bounding-box"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.position_tolerance = 0.5; }),
                       "wire.position_tolerance is 0.5"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.wire.channel_tolerance = 1e30; }),
                       "in the channel's stored units"));
}

TEST(SessionOptions, RefusesSizesThatCannotCarryASnapshotAndLongNames) {
  EXPECT_TRUE(
      mentions(refusal([](SessionOptions& o) { o.max_message_bytes = 100; }), "max_message_bytes"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.snapshot_chunk_bytes = 0; }),
                       "snapshot_chunk_bytes"));
  EXPECT_TRUE(
      mentions(refusal([](SessionOptions& o) { o.snapshot_chunk_bytes = o.max_message_bytes; }),
               "snapshot_chunk_bytes"));
  EXPECT_TRUE(
      mentions(refusal([](SessionOptions& o) { o.max_snapshot_bytes = 0; }), "max_snapshot_bytes"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.name = std::string(300, 'a'); }), "name"));
  EXPECT_TRUE(mentions(refusal([](SessionOptions& o) { o.bind.clear(); }), "bind"));
}

TEST(SessionOptions, CreateAndJoinRefuseBadOptionsBeforeOpeningAnything) {
  SessionOptions o;
  o.sync = Millis{0};
  try {
    Session::create(make_sphere(80), o);
    ADD_FAILURE() << "created a session with a 0 ms sync";
  } catch (const InvalidInput& e) {
    EXPECT_TRUE(mentions(e.what(), "session options: sync is 0 ms")) << e.what();
  }
  EXPECT_THROW(Session::join("csculpt1:garbage", o), InvalidInput);
}

TEST(SessionOptions, AnEndpointThatCannotBeBoundIsAnIoErrorNotAZeroMQError) {
  SessionOptions o;
  o.bind = "tcp://no-such-interface-xyz:*";
  try {
    Session::create(make_sphere(80), o);
    ADD_FAILURE() << "bound to an impossible endpoint";
  } catch (const IoError& e) {
    EXPECT_TRUE(mentions(e.what(), "tcp://no-such-interface-xyz:*")) << e.what();
  }
  o.bind = "bogus://x";
  EXPECT_THROW(Session::create(make_sphere(80), o), IoError);
}

}  // namespace
