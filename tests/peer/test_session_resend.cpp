// A submit that reached a merger behind the author's version (after a heal, the new merger can
// be the peer that was behind) is ignored there as stale. The author sends it again once the
// merger's heartbeat says it caught up, exactly once: an artist who stopped editing would
// otherwise wait for ever for a version with their last strokes. The merger here is a hand-
// driven member (FakePeer) so that "behind" and "caught up" happen when the test says.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/peer/session.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/wire.h"
#include "fake_peer.h"
#include "replication.h"
#include "sessions.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;
using namespace std::chrono_literals;

/// What the fake merger saw of the real peer: its submits (their diff bytes and the strokes
/// they said they carry) and the chain its heartbeats gave for each version.
struct Seen {
  std::vector<std::vector<std::uint8_t>> submits;
  std::vector<std::uint32_t> strokes;
  std::uint64_t version = 0, chain = 0;
  void operator()(const fb::Envelope& env) {
    if (const auto* s = env.body_as_Submit()) {
      submits.emplace_back(s->diff()->begin(), s->diff()->end());
      strokes.push_back(s->strokes());
    } else if (const auto* hb = env.body_as_Heartbeat()) {
      version = hb->version();
      chain = hb->chain();
    }
  }
};

void nudge(Mesh& local, std::uint32_t vertex, float by) {
  local.positions.at(vertex).y += by;
}

/// A real author (id 5) and a hand-driven member (id 1) that claims the merger's role.
struct AuthorAndFakeMerger {
  const Mesh sphere = make_sphere(400);
  std::unique_ptr<Session> author = Session::create(sphere, fast_options(5, "author"));
  Mesh local = author->base();
  FakePeer merger{author->invite(), 1};
  Seen seen;
  std::uint64_t chain = 0;  ///< of the latest version the fake published

  /// Joins the fake, which then claims the merger's role; true once the author follows it and
  /// has said (heartbeat) that it holds `author_version`.
  bool fake_merges(std::uint64_t author_version) {
    merger.hello();
    pump(100ms);
    merger.claim_merger(100);
    return wait_until([&] {
      pump(20ms);
      return author->stats().merger == 1 && seen.version == author_version && seen.chain != 0;
    });
  }
  void pump(Millis span) { merger.pump(span, 20ms, std::ref(seen)); }
  /// The author submits an edit; true once the fake merger received it.
  bool submit_edit(std::uint32_t vertex) {
    nudge(local, vertex, 0.05f);
    const std::size_t before = seen.submits.size();
    return author->submit(local, 1) && submits_reach(before + 1);
  }
  /// The fake holds version 0 as the author does and takes its submits.
  bool fake_merges_version_0() {
    merger.says(0, 0, 1);
    if (!fake_merges(0)) return false;
    chain = seen.chain;
    merger.says(0, chain, 1);
    pump(100ms);
    return true;
  }
  /// The fake publishes `version`: `diff` on the author's current base, naming `merged`;
  /// true once the author's host applied it.
  bool publish(std::uint64_t version, const Bytes& diff, std::vector<MergedSubmit> merged) {
    const std::uint64_t parent = chain;
    chain = next_chain(parent, decode_diff(diff, author->base()));
    merger.send(merger.version(diff, version, parent, chain, std::move(merged)));
    merger.says(version, chain, 1);
    return wait_until([&] {
      pump(20ms);
      author->update(local);
      return author->version() == version;
    });
  }
  std::uint64_t sequence_of(std::size_t submit) const {
    return peek_diff_header(seen.submits.at(submit)).sequence;
  }
  bool submits_reach(std::size_t n) {
    return wait_until([&] {
      pump(20ms);
      return seen.submits.size() == n;
    });
  }
};

TEST(SessionResend, ASubmitIgnoredByAMergerThatWasBehindGoesAgainOnceItCatchesUp) {
  AuthorAndFakeMerger t;
  // Version 1, merged by the author while it is the only member.
  nudge(t.local, 3, 0.05f);
  t.author->submit(t.local, 1);
  ASSERT_TRUE(wait_until([&] {
    t.author->update(t.local);
    return t.author->version() == 1;
  }));
  // The fake merger says it holds only version 0 (of another chain): behind the author.
  t.merger.says(0, 0, 1);
  ASSERT_TRUE(t.fake_merges(1));

  // The author's next edit goes to the merger, which is behind it: a real merger ignores it.
  ASSERT_TRUE(t.submit_edit(40));
  t.pump(300ms);  // still behind: nothing is sent again
  EXPECT_EQ(t.seen.submits.size(), 1u);

  // Caught up (version 1, the author's chain): the same submit comes again, once.
  t.merger.says(1, t.seen.chain, 1);
  ASSERT_TRUE(t.submits_reach(2));
  EXPECT_EQ(t.seen.submits[1], t.seen.submits[0]);
  t.pump(300ms);
  EXPECT_EQ(t.seen.submits.size(), 2u);
  EXPECT_EQ(t.author->stats().submits_resent, 1u);
}

TEST(SessionResend, ASubmitTheMergerCouldTakeIsNotSentAgain) {
  AuthorAndFakeMerger t;
  t.merger.says(0, 0, 1);
  ASSERT_TRUE(t.fake_merges(0));
  t.merger.says(0, t.seen.chain, 1);  // holds the author's version 0 and chain
  t.pump(100ms);
  ASSERT_TRUE(t.submit_edit(40));
  t.pump(400ms);
  EXPECT_EQ(t.seen.submits.size(), 1u);
  EXPECT_EQ(t.author->stats().submits_resent, 0u);
}

// A submit no version took (stale at the merger), whose edit the host then took back: the
// host's next submit (it submits while strokes are unacknowledged, as every host does) finds
// nothing to send, and the strokes are settled, not left unacknowledged for ever (a host
// waiting for them would wait for ever).
TEST(SessionResend, StrokesWithNothingLeftToSendAreNotLeftUnacknowledged) {
  const Mesh sphere = make_sphere(400);
  auto a = Session::create(sphere, fast_options(1, "a"));
  auto b = Session::join(a->invite(), fast_options(2, "b"));
  ASSERT_TRUE(wait_until([&] { return a->stats().members == 2 && b->stats().members == 2; }));
  Mesh mine = b->base();
  Mesh theirs = a->base();
  nudge(theirs, 3, 0.05f);
  a->submit(theirs, 1);
  ASSERT_TRUE(wait_until([&] {
    a->update(theirs);
    return a->version() == 1;
  }));
  // b edits on version 0, which the merger has left: its submit is never merged.
  nudge(mine, 100, 0.05f);
  ASSERT_TRUE(b->submit(mine, 2));
  mine = b->base();  // the host takes the edit back
  ASSERT_TRUE(wait_until([&] {
    b->update(mine);
    return b->version() == 1;
  }));
  EXPECT_EQ(b->stats().strokes_acknowledged, 0u);
  EXPECT_FALSE(b->submit(mine, 0));
  EXPECT_EQ(b->stats().strokes_submitted, 2u);
  EXPECT_EQ(b->stats().strokes_acknowledged, 2u);
  EXPECT_TRUE(mine.positions == b->base().positions);
}

// An edit the wire's quantisation rounds away entirely (a rebase's float rounding leaves such
// differences) is not sent: an empty submit would make an empty version, and a session that
// had converged would go on making versions, one per merger that takes it.
TEST(SessionResend, AnEditWithinTheWireToleranceIsNotSentAndMakesNoVersion) {
  const Mesh sphere = make_sphere(400);
  auto a = Session::create(sphere, fast_options(1, "a"));
  Mesh local = a->base();
  local.positions.at(7).x = std::nextafter(local.positions[7].x, 10.f);
  EXPECT_FALSE(a->submit(local, 1));
  EXPECT_TRUE(local.positions == a->base().positions);  // back to the base
  EXPECT_EQ(a->stats().strokes_acknowledged, 1u);
  EXPECT_FALSE(wait_until([&] { return a->update(local) > 0; }, 300ms));
  EXPECT_EQ(a->version(), 0u);
  EXPECT_EQ(a->stats().submits, 0u);
}

// A version left the author's submit out, and meanwhile the host made a stroke it has not
// submitted yet. update() does not send the submit again by itself: the resend would carry that
// stroke while saying it carries one stroke fewer, so the merger would count fewer strokes than
// the author acknowledges. The host's next submit carries both, counted.
TEST(SessionResend, AnUnmergedSubmitWaitsForTheHostsSubmitWhenTheHostEditedSince) {
  AuthorAndFakeMerger t;
  ASSERT_TRUE(t.fake_merges_version_0());
  ASSERT_TRUE(t.submit_edit(40));
  nudge(t.local, 120, 0.05f);  // a stroke, not submitted yet
  ASSERT_TRUE(t.publish(1, edit_message(t.author->base(), 0, 100), {}));
  t.pump(300ms);
  t.author->update(t.local);
  EXPECT_EQ(t.seen.submits.size(), 1u);
  ASSERT_TRUE(t.author->submit(t.local, 1));
  ASSERT_TRUE(t.submits_reach(2));
  EXPECT_EQ(t.seen.strokes[1], 2u);  // the unmerged stroke and the new one
  EXPECT_EQ(peek_diff_header(t.seen.submits[1]).base_version, 1u);
  const Bytes diff(t.seen.submits[1].begin(), t.seen.submits[1].end());
  ASSERT_TRUE(t.publish(2, diff, {{5, t.sequence_of(1), 2}}));
  EXPECT_EQ(t.author->stats().strokes_submitted, 2u);
  EXPECT_EQ(t.author->stats().strokes_acknowledged, 2u);
  EXPECT_TRUE(t.local.positions == t.author->base().positions);
}

// The same without the host's stroke: update() sends the submit again by itself, rebased, with
// its one stroke (an idle host has nothing else that would carry it).
TEST(SessionResend, AnUnmergedSubmitOfAnIdleHostGoesAgainFromUpdate) {
  AuthorAndFakeMerger t;
  ASSERT_TRUE(t.fake_merges_version_0());
  ASSERT_TRUE(t.submit_edit(40));
  ASSERT_TRUE(t.publish(1, edit_message(t.author->base(), 0, 100), {}));
  ASSERT_TRUE(t.submits_reach(2));
  EXPECT_EQ(t.seen.strokes[1], 1u);
  EXPECT_EQ(peek_diff_header(t.seen.submits[1]).base_version, 1u);
}

// Strokes that change nothing beyond a submit still waiting for its version are present only
// once that submit is: acknowledged with it, not at once ("acknowledged" means present).
TEST(SessionResend, StrokesThatChangeNothingBeyondASubmitInFlightAreAcknowledgedWithIt) {
  AuthorAndFakeMerger t;
  ASSERT_TRUE(t.fake_merges_version_0());
  ASSERT_TRUE(t.submit_edit(40));
  EXPECT_FALSE(t.author->submit(t.local, 2));  // nothing new to send
  EXPECT_EQ(t.author->stats().strokes_submitted, 3u);
  EXPECT_EQ(t.author->stats().strokes_acknowledged, 0u);
  const Bytes diff(t.seen.submits[0].begin(), t.seen.submits[0].end());
  ASSERT_TRUE(t.publish(1, diff, {{5, t.sequence_of(0), 1}}));
  EXPECT_EQ(t.author->stats().strokes_acknowledged, 3u);
}

}  // namespace
