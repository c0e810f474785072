// The merger role without sockets: which submits it keeps, and the version record a merge makes
// (chain, strokes, conflicts, contributions), checked by a replica as any peer would.
#include <gtest/gtest.h>

#include "csculpt/error.h"
#include "merger_role.h"
#include "pieces.h"
#include "replication.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;

struct Fixture {
  Mesh base = sphere();
  MergeFrame frame = MergeFrame::fit(base.positions);
  MergerRole role{sphere_hierarchy()};

  Bytes submit(const Diff& d, std::uint64_t version, std::uint64_t sequence) const {
    DiffHeader h;
    h.base_version = version;
    h.sequence = sequence;
    h.author = "test";
    return encode_diff(d, base, h, session_wire_options({}, frame));
  }
};

// A peer's submit is held to the host's own rule (host_values.h): a vertex thrown far out of
// the session's reach would turn the merge's rotations around it into noise for everyone.
TEST(MergerRole, RefusesASubmitThatThrowsAVertexOutOfReach) {
  Fixture f;
  Mesh far = f.base;
  far.positions[3].x = 1e6f;
  try {
    f.role.accept(1, f.submit(capture_diff(f.base, far), 0, 1), 1, f.base, 0, f.frame);
    ADD_FAILURE() << "accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("beyond 1000 x"), std::string::npos) << e.what();
  }
  Mesh grabbed = f.base;  // a long legitimate grab passes
  grabbed.positions[3].x += 50 * f.frame.scale;
  EXPECT_TRUE(
      f.role.accept(1, f.submit(capture_diff(f.base, grabbed), 0, 1), 1, f.base, 0, f.frame));
}

TEST(MergerRole, KeepsOnlySubmitsOnTheAgreedVersionAndTheLatestPerAuthor) {
  Fixture f;
  const Diff a = stroke_diff(f.base, {0, 0, 1}, {0.2f, 0, 0});
  EXPECT_FALSE(
      f.role.accept(1, f.submit(a, 5, 1), 1, f.base, 4, f.frame));  // based on another version
  EXPECT_TRUE(f.role.empty());
  EXPECT_TRUE(f.role.accept(1, f.submit(a, 4, 2), 1, f.base, 4, f.frame));
  const Diff b = stroke_diff(f.base, {0, 1, 0}, {0, 0, 0.2f});
  EXPECT_TRUE(
      f.role.accept(1, f.submit(b, 4, 1), 7, f.base, 4, f.frame));  // older sequence: ignored
  const MergeOutcome o = f.role.merge(f.role.take_pending(), f.base, 4, 99, f.frame, {});
  ASSERT_EQ(o.record.merged.size(), 1u);
  EXPECT_EQ(o.record.merged[0].sequence, 2u);
  EXPECT_EQ(o.merged_strokes, 1u);
  EXPECT_TRUE(f.role.empty());  // taken for the merge, no longer held
  EXPECT_THROW(f.role.accept(1, Bytes{1, 2, 3}, 1, f.base, 5, f.frame), InvalidInput);
}

TEST(MergerRole, MergeMakesAVersionEveryReplicaAccepts) {
  Fixture f;
  const Diff a = stroke_diff(f.base, {0, 0, 1}, {0.2f, 0, 0}, true);
  const Diff b = stroke_diff(f.base, {0, 0, -1}, {0, 0.2f, 0});
  ASSERT_TRUE(f.role.accept(10, f.submit(a, 0, 1), 3, f.base, 0, f.frame));
  ASSERT_TRUE(f.role.accept(20, f.submit(b, 0, 1), 4, f.base, 0, f.frame));
  const MergeOutcome o = f.role.merge(f.role.take_pending(), f.base, 0, kGenesisChain, f.frame, {});
  const VersionRecord& r = o.record;
  EXPECT_EQ(r.version, 1u);
  EXPECT_EQ(r.parent_chain, kGenesisChain);
  EXPECT_EQ(o.merged_strokes, 7u);
  EXPECT_EQ(r.conflicting, 0u);  // opposite sides of the sphere
  ASSERT_EQ(r.contributions.size(), 2u);
  EXPECT_EQ(r.contributions[0].peer, 10u);
  EXPECT_GT(r.contributions[0].scale, 0.f);
  Replication replica;
  replica.reset(0, kGenesisChain);
  Mesh mesh = f.base;
  const Diff merged = replica.accept(r, mesh);  // throws if the chain were wrong
  EXPECT_EQ(replica.chain(), r.chain);
  // Both edits are in: every vertex either stroke moved has moved.
  for (const Diff* d : {&a, &b})
    for (std::uint32_t v : d->positions.indices)
      EXPECT_FALSE(mesh.positions[v] == f.base.positions[v]) << v;
}

TEST(MergerRole, CountsConflictingStrokes) {
  Fixture f;
  const Diff a = stroke_diff(f.base, {0, 0, 1}, {0.2f, 0, 0});
  const Diff b = stroke_diff(f.base, {0, 0, 1}, {0, 0.2f, 0});
  const Diff c = stroke_diff(f.base, {0, 0, -1}, {0, 0.2f, 0});
  f.role.accept(1, f.submit(a, 0, 1), 2, f.base, 0, f.frame);
  f.role.accept(2, f.submit(b, 0, 1), 3, f.base, 0, f.frame);
  f.role.accept(3, f.submit(c, 0, 1), 5, f.base, 0, f.frame);
  EXPECT_EQ(
      f.role.merge(f.role.take_pending(), f.base, 0, kGenesisChain, f.frame, {}).record.conflicting,
      5u);
}

TEST(MergerRole, ForgetsALeaversSubmit) {
  Fixture f;
  f.role.accept(1, f.submit(stroke_diff(f.base, {0, 0, 1}, {0.2f, 0, 0}), 0, 1), 1, f.base, 0,
                f.frame);
  f.role.forget(1);
  EXPECT_TRUE(f.role.empty());
}

TEST(MergerRole, SessionWireOptionsUseTheFrameUnlessAScaleIsGiven) {
  MergeFrame frame;
  frame.scale = 4.f;
  EXPECT_EQ(session_wire_options({}, frame).position_scale, 4.0);
  EncodeOptions fixed;
  fixed.position_scale = 2.0;
  EXPECT_EQ(session_wire_options(fixed, frame).position_scale, 2.0);
}

}  // namespace
