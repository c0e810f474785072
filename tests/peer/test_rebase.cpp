// The host side's rebase without sockets: a merged version replaces what this peer submitted,
// edits made since are kept, nothing is applied twice.
#include <gtest/gtest.h>

#include <algorithm>

#include "csculpt/error.h"
#include "csculpt/peer/session.h"
#include "pieces.h"
#include "rebase.h"

namespace {

using namespace csculpt;
using namespace csculpt::peer;
using namespace csculpt::peer::testing;

struct Host {
  Mesh base = sphere();
  Merger merger{*sphere_hierarchy()};
  MergeFrame frame = MergeFrame::fit(base.positions);
};

TEST(Rebase, EqualsBasePlusComparesBitwise) {
  const Mesh& base = sphere();
  const Mesh edited = stroked(base, {0, 0, 1}, {0.2f, 0, 0}, true);
  const Diff d = capture_diff(base, edited);
  EXPECT_TRUE(equals_base_plus(base, &d, edited));
  EXPECT_TRUE(equals_base_plus(base, nullptr, base));
  EXPECT_FALSE(equals_base_plus(base, nullptr, edited));
  Mesh nudged = edited;
  nudged.positions[d.positions.indices.back() == 0 ? 1 : 0].x += 1e-6f;
  EXPECT_FALSE(equals_base_plus(base, &d, nudged));
  Mesh restored = edited;
  restore(base, d, restored);
  EXPECT_EQ(mesh_digest(restored), mesh_digest(base));
}

TEST(Rebase, WithoutNewEditsLocalBecomesTheVersion) {
  Host h;
  const Mesh mine = stroked(h.base, {0, 0, 1}, {0.2f, 0, 0});
  const Diff ours = capture_diff(h.base, mine);
  // The merged version: our stroke (slightly changed by the merge) and someone else's.
  Mesh merged_mesh = stroked(mine, {0, 0, -1}, {0, 0.2f, 0});
  merged_mesh.positions[ours.positions.indices[0]].y += 0.01f;
  const Diff merged = capture_diff(h.base, merged_mesh);
  Mesh local = mine;
  EXPECT_FALSE(rebase_onto_version(h.base, &ours, merged, local, h.merger, h.frame));
  EXPECT_EQ(mesh_digest(h.base), mesh_digest(merged_mesh));
  EXPECT_EQ(mesh_digest(local), mesh_digest(merged_mesh));  // ours not applied twice
}

TEST(Rebase, EditsMadeSinceTheSubmitAreKept) {
  Host h;
  const Mesh sent = stroked(h.base, {0, 0, 1}, {0.2f, 0, 0});
  const Diff ours = capture_diff(h.base, sent);
  Mesh local = stroked(sent, {1, 0, 0}, {0, 0, 0.2f});  // made after the submit
  const Diff later = capture_diff(sent, local);
  const Mesh merged_mesh = stroked(sent, {0, 0, -1}, {0, 0.2f, 0});  // ours + someone else's
  const Diff merged = capture_diff(h.base, merged_mesh);
  EXPECT_TRUE(rebase_onto_version(h.base, &ours, merged, local, h.merger, h.frame));
  EXPECT_EQ(mesh_digest(h.base), mesh_digest(merged_mesh));
  // The later stroke is still there (on vertices the version did not touch, exactly) ...
  std::size_t kept = 0;
  for (std::uint32_t v : later.positions.indices)
    if (std::find(merged.positions.indices.begin(), merged.positions.indices.end(), v) ==
        merged.positions.indices.end()) {
      EXPECT_FALSE(local.positions[v] == merged_mesh.positions[v]) << v;
      ++kept;
    }
  EXPECT_GT(kept, 0u);
  // ... and the version's changes are in local too.
  for (std::uint32_t v : merged.positions.indices) {
    if (std::find(later.positions.indices.begin(), later.positions.indices.end(), v) ==
        later.positions.indices.end()) {
      EXPECT_NEAR(local.positions[v].y, merged_mesh.positions[v].y, 1e-4f) << v;
    }
  }
}

TEST(Rebase, AnEmptyLocalMeshBecomesTheBaseAndAForeignLayoutIsRefused) {
  Host h;
  const Mesh next = stroked(h.base, {0, 0, 1}, {0.2f, 0, 0});
  const Diff merged = capture_diff(h.base, next);
  Mesh empty;
  EXPECT_FALSE(rebase_onto_version(h.base, nullptr, merged, empty, h.merger, h.frame));
  EXPECT_EQ(mesh_digest(empty), mesh_digest(next));
  Mesh other = make_sphere(80);
  EXPECT_THROW(rebase_onto_version(h.base, nullptr, merged, other, h.merger, h.frame),
               InvalidInput);
  EXPECT_FALSE(same_layout(h.base, other));
}

TEST(Rebase, LocalEditsCarryOverToASnapshot) {
  Host h;
  Mesh local = stroked(h.base, {0, 0, 1}, {0.2f, 0, 0});
  const Diff mine = capture_diff(h.base, local);
  const Mesh snapshot = stroked(h.base, {0, 0, -1}, {0, 0.2f, 0});
  Mesh old_base = h.base;
  EXPECT_TRUE(rebase_onto_snapshot(h.base, snapshot, local, h.merger, h.frame));
  EXPECT_EQ(mesh_digest(h.base), mesh_digest(snapshot));
  for (std::uint32_t v : mine.positions.indices)
    EXPECT_FALSE(local.positions[v] == old_base.positions[v]) << v;
  Mesh none;
  EXPECT_FALSE(rebase_onto_snapshot(h.base, snapshot, none, h.merger, h.frame));
  EXPECT_EQ(mesh_digest(none), mesh_digest(snapshot));
}

}  // namespace
