// A member with the session's key that sends forged versions (a replay whose hash chain fails)
// to the merger while it merges. The merger merges on a worker thread; a version that would
// change its mesh drops the merge in flight, and its authors, who sent their submits when the
// merger held their base, would never send them again. So a version is checked before it may
// drop anything: a forged one costs the merger nothing but a "dropped" count.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"
#include "fake_peer.h"
#include "sessions.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;
using namespace std::chrono_literals;

/// The merger's version and chain, from its heartbeats to the forger.
struct MergerState {
  std::uint64_t version = 0, chain = 0;
  void operator()(const fb::Envelope& env) {
    if (const auto* hb = env.body_as_Heartbeat()) {
      version = hb->version();
      chain = hb->chain();
    }
  }
};

TEST(SessionForged, AForgedVersionDuringAMergeCostsTheMergerNoSubmit) {
  const Mesh sphere = make_sphere(80000);
  const auto [hierarchy, build_time, edits] = two_artists_edits(sphere, 31, 128);
  auto options = [&](PeerId id) {
    SessionOptions o = fast_options(id);
    // The first merge comes one interval after the start, after the join and both submits:
    // one merge of both edits, long enough for forged versions to arrive while it runs.
    o.sync = Millis{1000} + 8 * build_time;
    return o;
  };
  auto a = Session::create(sphere, options(1));
  auto b = Session::join(a->invite(), options(2));
  FakePeer forger{a->invite(), 9};
  forger.hello();
  MergerState seen;
  std::atomic<bool> stop{false};
  std::atomic<int> forged{0};
  std::thread flood([&] {
    // A replayed version "following" the merger's, with a wrong chain, every few ms.
    while (!stop) {
      forger.pump(2ms, 20ms, std::ref(seen));
      if (seen.chain == 0) continue;
      forger.send(forger.version(edit_message(sphere, seen.version, 7), seen.version + 1,
                                 seen.chain, seen.chain ^ 1, {}, /*replay=*/true));
      ++forged;
    }
  });
  ASSERT_TRUE(wait_until([&] { return b->stats().members == 3; }, Millis{60000}));
  Mesh la = edits[0], lb = edits[1];
  a->submit(la, 128);
  b->submit(lb, 128);
  const bool done = wait_until(
      [&] {
        a->update(la);
        b->update(lb);
        return a->stats().strokes_acknowledged == 128 && b->stats().strokes_acknowledged == 128 &&
               a->version() == b->version() && mesh_digest(la) == mesh_digest(lb);
      },
      Millis{60000});
  stop = true;
  flood.join();
  ASSERT_TRUE(done) << "the edits were not merged: a forged version dropped the merge";
  const SessionStats s = a->stats();
  EXPECT_EQ(s.merged_strokes, 256u);
  EXPECT_EQ(s.merger, 1u);
  // The premise: a merge long enough that forged versions came in while it ran.
  EXPECT_GT(s.merge_ms_max, 20.0);
  EXPECT_GT(forged.load(), 10);
  EXPECT_GT(s.messages_dropped, 0u);
}

}  // namespace
