// The host's revert log: stepping an agreed mesh back to a fork point, exactly.
#include <gtest/gtest.h>

#include "csculpt/peer/session.h"
#include "pieces.h"
#include "revert_log.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;

/// Applies `n` strokes (geometry and paint) to `mesh` as versions 1..n, recording each; returns
/// the mesh after each version (index 0: before any).
std::vector<Mesh> apply_versions(Mesh& mesh, RevertLog& log, std::size_t n,
                                 std::uint64_t first = 1) {
  std::vector<Mesh> states{mesh};
  for (std::size_t i = 0; i < n; ++i) {
    const Diff d = stroke_diff(mesh, {0.f, 0.2f * float(i), 1.f}, {0.05f, 0.f, 0.f}, i % 2 == 1);
    log.record(first + i, d, mesh);
    apply_diff(d, mesh);
    states.push_back(mesh);
  }
  return states;
}

TEST(RevertLog, StepsBackToEveryEarlierVersionBitForBit) {
  Mesh mesh = sphere();
  RevertLog log;
  const std::vector<Mesh> states = apply_versions(mesh, log, 5);
  for (std::uint64_t target = 0; target <= 5; ++target) {
    Mesh m = mesh;
    EXPECT_EQ(log.revert(m, 5, target), target);
    EXPECT_EQ(mesh_digest(m), mesh_digest(states[target])) << "to version " << target;
  }
}

TEST(RevertLog, SaysHowFarItReachedWhenItsHistoryIsShort) {
  Mesh mesh = sphere();
  RevertLog small(1);  // one entry's bytes at most: only the latest version is kept
  const std::vector<Mesh> states = apply_versions(mesh, small, 4);
  Mesh m = mesh;
  EXPECT_EQ(small.revert(m, 4, 0), 3u);
  EXPECT_EQ(mesh_digest(m), mesh_digest(states[3]));
  // A mesh of another version than the log's latest is left alone.
  Mesh other = mesh;
  EXPECT_EQ(small.revert(other, 7, 0), 7u);
  EXPECT_EQ(mesh_digest(other), mesh_digest(mesh));
}

TEST(RevertLog, AVersionThatDoesNotFollowStartsAgain) {
  Mesh mesh = sphere();
  RevertLog log;
  apply_versions(mesh, log, 3);
  const std::vector<Mesh> later = apply_versions(mesh, log, 2, 10);  // versions 10 and 11
  Mesh m = mesh;
  EXPECT_EQ(log.revert(m, 11, 0), 9u);  // 1..3 were another history
  EXPECT_EQ(mesh_digest(m), mesh_digest(later[0]));
}

TEST(RevertLog, StepsBackOverASnapshotToAForkBeforeIt) {
  Mesh mesh = sphere();
  RevertLog log;
  const std::vector<Mesh> ours = apply_versions(mesh, log, 5);  // versions 1..5
  // Our branch lost at a fork at 3: the base steps back there and becomes a snapshot of 8.
  Mesh from = mesh;
  ASSERT_EQ(log.revert(from, 5, 3), 3u);
  Mesh snapshot = from;
  apply_diff(stroke_diff(snapshot, {1.f, 0.f, 0.f}, {0.f, 0.1f, 0.f}, false), snapshot);
  log.jumped(3, from, 8, snapshot);
  Mesh now = snapshot;
  const std::vector<Mesh> after = apply_versions(now, log, 2, 9);  // versions 9 and 10
  // A later fork at 9 steps back version by version; one at 2 steps over the snapshot to the
  // state both branches held, then on.
  Mesh m = now;
  EXPECT_EQ(log.revert(m, 10, 9), 9u);
  EXPECT_EQ(mesh_digest(m), mesh_digest(after[1]));
  m = now;
  EXPECT_EQ(log.revert(m, 10, 2), 2u);
  EXPECT_EQ(mesh_digest(m), mesh_digest(ours[2]));
  // A fork inside the snapshot's step (at 5, a version of the lost branch) reaches back
  // before it, to 3: more is carried, nothing is dropped.
  m = now;
  EXPECT_EQ(log.revert(m, 10, 5), 3u);
  EXPECT_EQ(mesh_digest(m), mesh_digest(ours[3]));
}

TEST(RevertLog, ASnapshotAfterTheLogWasClearedStartsItAgain) {
  Mesh mesh = sphere();
  RevertLog log;
  apply_versions(mesh, log, 3);
  Mesh snapshot = mesh;
  apply_diff(stroke_diff(snapshot, {1.f, 0.f, 0.f}, {0.f, 0.1f, 0.f}, false), snapshot);
  // The base was at 7, a version the log does not end at: its entries describe another state.
  log.jumped(7, mesh, 12, snapshot);
  Mesh m = snapshot;
  EXPECT_EQ(log.revert(m, 12, 0), 7u);
  EXPECT_EQ(mesh_digest(m), mesh_digest(mesh));
}

}  // namespace
