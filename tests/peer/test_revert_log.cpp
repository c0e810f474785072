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

}  // namespace
