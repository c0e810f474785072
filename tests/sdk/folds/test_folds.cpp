// Fold-over counting (folds.h): the scorer's definition (shared/eval/score_merge.py `flipped`)
// on hand-made meshes where every face's fate is known, both overloads against a dense
// reference on random edits of a sphere, and opposed face pairs.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/folds.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"

namespace csculpt {
namespace {

/// Three separate triangles in the z = 0 plane, normals +z, 3 apart along x.
Mesh three_triangles() {
  Mesh m;
  for (std::uint32_t k = 0; k < 3; ++k) {
    const float x = 3.f * static_cast<float>(k);
    m.positions.push_back({x, 0, 0});
    m.positions.push_back({x + 1, 0, 0});
    m.positions.push_back({x, 1, 0});
    m.triangles.push_back({3 * k, 3 * k + 1, 3 * k + 2});
  }
  return m;
}

/// `base` with the given vertices moved.
Mesh moved(const Mesh& base, const std::vector<std::pair<std::uint32_t, Vec3f>>& moves) {
  Mesh m = base;
  for (const auto& [v, p] : moves) m.positions[v] = p;
  return m;
}

std::uint32_t both_overloads(const Mesh& base, const std::vector<const Diff*>& diffs,
                             const Diff& merged) {
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(base.vertex_count()), base.triangles);
  const std::uint32_t sparse = count_new_folds(topology, base, diffs, merged);
  EXPECT_EQ(sparse, count_new_folds(base, diffs, merged)) << "the overloads disagree";
  FoldCounter counter(topology);
  EXPECT_EQ(counter.count_new_folds(base, diffs, merged), sparse);
  EXPECT_EQ(counter.count_new_folds(base, diffs, merged), sparse) << "a reused counter";
  return sparse;
}

TEST(Folds, CountsFlipsTheMergeMadeButNoDiffDid) {
  const Mesh base = three_triangles();
  // A flips triangle 0 (its apex mirrored through the base edge); B nudges triangle 2.
  const Diff a = capture_diff(base, moved(base, {{2, {0, -1, 0}}}));
  const Diff b = capture_diff(base, moved(base, {{8, {6, 1, 0.1f}}}));
  // The merge flips triangle 0 as A did (not new), flips triangle 1 (new), and collapses
  // triangle 2 onto a line (zero normal: no fold).
  const Diff merged =
      capture_diff(base, moved(base, {{2, {0, -1, 0}}, {5, {3, -1, 0}}, {8, {6.5f, 0, 0}}}));
  EXPECT_EQ(both_overloads(base, {&a, &b}, merged), 1u);
  EXPECT_EQ(both_overloads(base, {&b, &a}, merged), 1u) << "order of the diffs";
  // Without A, triangle 0's flip is nobody's either.
  EXPECT_EQ(both_overloads(base, {&b}, merged), 2u);
  EXPECT_EQ(both_overloads(base, {}, merged), 2u);
  // A merge equal to one diff makes no new fold, whatever that diff flipped.
  EXPECT_EQ(both_overloads(base, {&a, &b}, a), 0u);
  // A flip is more than 90 degrees: a face tilted to 80 degrees is not one.
  const Diff tilt = capture_diff(base, moved(base, {{5, {3, 0.17f, 0.98f}}}));
  EXPECT_EQ(both_overloads(base, {}, tilt), 0u);
  const Diff past = capture_diff(base, moved(base, {{5, {3, -0.17f, 0.98f}}}));
  EXPECT_EQ(both_overloads(base, {}, past), 1u);
}

TEST(Folds, AFaceAroundSeveralMovedVerticesCountsOnce) {
  const Mesh base = three_triangles();
  // all three vertices of triangle 1 moved: mirrored in x
  const Diff merged =
      capture_diff(base, moved(base, {{3, {3, 0, 0}}, {4, {2, 0, 0}}, {5, {3, 1, 0}}}));
  EXPECT_EQ(both_overloads(base, {}, merged), 1u);
}

/// The scorer's definition, dense: every face, every diff applied to a copy of the base.
std::uint32_t reference_new_folds(const Mesh& base, const std::vector<Mesh>& edits,
                                  const Mesh& result) {
  auto normal = [](const Mesh& m, const Triangle& t) {
    const Vec3f &p0 = m.positions[t[0]], &p1 = m.positions[t[1]], &p2 = m.positions[t[2]];
    const double u[3] = {double(p1.x) - p0.x, double(p1.y) - p0.y, double(p1.z) - p0.z};
    const double v[3] = {double(p2.x) - p0.x, double(p2.y) - p0.y, double(p2.z) - p0.z};
    return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                 u[0] * v[1] - u[1] * v[0]};
  };
  auto flipped = [&](const Mesh& q, const Triangle& t) {
    const auto a = normal(base, t), b = normal(q, t);
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] < 0;
  };
  std::uint32_t folds = 0;
  for (const Triangle& t : base.triangles) {
    bool made = false;
    for (const Mesh& e : edits) made = made || flipped(e, t);
    folds += flipped(result, t) && !made ? 1u : 0u;
  }
  return folds;
}

TEST(Folds, SparseCountsEqualTheDenseDefinitionOnRandomEdits) {
  const Mesh base = make_sphere(2000);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.08f, 0.08f);
  std::uniform_int_distribution<std::uint32_t> vertex(
      0, static_cast<std::uint32_t>(base.vertex_count() - 1));
  auto random_edit = [&](int moves) {
    Mesh m = base;
    for (int i = 0; i < moves; ++i) {
      Vec3f& p = m.positions[vertex(rng)];
      p = {p.x + jitter(rng), p.y + jitter(rng), p.z + jitter(rng)};
    }
    return m;
  };
  // one counter over every round, as a session's merger keeps one
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(base.vertex_count()), base.triangles);
  FoldCounter session_counter(topology);
  std::uint32_t total = 0;
  for (int round = 0; round < 20; ++round) {
    const std::vector<Mesh> edits = {random_edit(150), random_edit(150)};
    const Mesh result = random_edit(300);
    const Diff da = capture_diff(base, edits[0]), db = capture_diff(base, edits[1]);
    const Diff merged = capture_diff(base, result);
    const std::uint32_t expected = reference_new_folds(base, edits, result);
    EXPECT_EQ(both_overloads(base, {&da, &db}, merged), expected) << round;
    const std::vector<const Diff*> diffs = {&da, &db};
    EXPECT_EQ(session_counter.count_new_folds(base, diffs, merged), expected) << round;
    total += expected;
  }
  EXPECT_GT(total, 0u) << "the edits should flip some faces";
}

TEST(Folds, AMismatchedTopologyOrDiffIsRefused) {
  const Mesh base = three_triangles();
  const Mesh other = make_sphere(200);
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(other.vertex_count()), other.triangles);
  const Diff merged = capture_diff(base, moved(base, {{5, {3, -1, 0}}}));
  EXPECT_THROW(FoldCounter(topology).count_new_folds(base, {}, merged), InvalidInput);
  const Diff past = capture_diff(other, moved(other, {{50, {0, 0, 0}}}));
  EXPECT_THROW(count_new_folds(base, {}, past), InvalidInput);
}

TEST(Folds, OpposedFacePairsAreCreasesAcrossAnEdge) {
  // A unit square split along 0-2 into two triangles, both normals +z.
  Mesh quad;
  quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  quad.triangles = {{0, 1, 2}, {0, 2, 3}};
  EXPECT_EQ(count_opposed_face_pairs(quad), 0u);
  // Vertex 3 folded over the diagonal onto triangle 0's side: a crease of almost 180 degrees.
  EXPECT_EQ(count_opposed_face_pairs(moved(quad, {{3, {1, 0, 0.1f}}})), 1u);
  // Folded up by 60 degrees only: no crease.
  EXPECT_EQ(count_opposed_face_pairs(moved(quad, {{3, {0.25f, 0.75f, 0.61f}}})), 0u);
  // Collapsed onto vertex 0: a degenerate face is in no pair.
  EXPECT_EQ(count_opposed_face_pairs(moved(quad, {{3, {0, 0, 0}}})), 0u);
  EXPECT_EQ(count_opposed_face_pairs(make_sphere(2000)), 0u);
}

TEST(Folds, AVertexSlidPastItsNeighboursFoldsItsFanOverTheRim) {
  // A sphere vertex moved along the surface past its ring of neighbours: part of its fan
  // folds back over the faces beyond the ring, both as new folds and as creases.
  const Mesh sphere = make_sphere(2000);
  const Topology topology =
      Topology::build(static_cast<std::uint32_t>(sphere.vertex_count()), sphere.triangles);
  const std::uint32_t v = 0;
  // the neighbour of a neighbour farthest from v: two rings out
  std::uint32_t far = v;
  auto distance2 = [&](std::uint32_t a, std::uint32_t b) {
    const Vec3f &p = sphere.positions[a], &q = sphere.positions[b];
    return (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) + (p.z - q.z) * (p.z - q.z);
  };
  for (std::uint32_t n : topology.vertex_vertices.row(v))
    for (std::uint32_t m : topology.vertex_vertices.row(n))
      if (distance2(v, m) > distance2(v, far)) far = m;
  const Mesh slid = moved(sphere, {{v, sphere.positions[far]}});
  EXPECT_GT(count_opposed_face_pairs(slid), 0u);
  EXPECT_GT(both_overloads(sphere, {}, capture_diff(sphere, slid)), 0u);
}

}  // namespace
}  // namespace csculpt
