// The fold repair that ends `full`'s position merge (sdk/src/fold_repair.h): the merge turns
// no face inside out that none of its diffs does, and the repair stays local.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/folds.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/testkit/generate.h"
#include "fold_repair.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;

/// An n x n grid of unit spacing in the z = 0 plane, triangles facing +z.
Mesh grid(std::uint32_t n) {
  Mesh m;
  for (std::uint32_t y = 0; y < n; ++y)
    for (std::uint32_t x = 0; x < n; ++x) m.positions.push_back({float(x), float(y), 0.f});
  for (std::uint32_t y = 0; y + 1 < n; ++y)
    for (std::uint32_t x = 0; x + 1 < n; ++x) {
      const std::uint32_t v = y * n + x;
      m.triangles.push_back({v, v + 1, v + n + 1});
      m.triangles.push_back({v, v + n + 1, v + n});
    }
  return m;
}

Diff moving(const Mesh& base, std::uint32_t v, Vec3f by) {
  Diff d;
  d.vertex_count = static_cast<std::uint32_t>(base.vertex_count());
  const Vec3f p = base.positions[v];
  d.positions.indices = {v};
  d.positions.values = {p.x + by.x, p.y + by.y, p.z + by.z};
  return d;
}

std::uint32_t ring_distance(std::uint32_t n, std::uint32_t a, std::uint32_t b) {
  const int dx = std::abs(int(a % n) - int(b % n)), dy = std::abs(int(a / n) - int(b / n));
  return static_cast<std::uint32_t>(std::max(dx, dy));
}

// Two artists each push one vertex 0.6 of an edge to the right: neither folds a face; both
// together (1.2 edges, as plain addition gives) do. The repair unfolds them by spreading the
// push over the neighbours, keeping both artists' pushes in sum, and every vertex more than a
// few rings away keeps the merged position bit for bit.
TEST(FoldRepair, UnfoldsWhatNoDiffFoldedAndStaysLocal) {
  const std::uint32_t n = 25, c = 12 * n + 12;
  const Mesh base = grid(n);
  const Topology topology = Topology::build(std::uint32_t(base.vertex_count()), base.triangles);
  const Diff a = moving(base, c, {0.6f, 0.f, 0.f});
  const Diff b = moving(base, c, {0.6f, 0.f, 0.05f});
  const Diff* diffs[] = {&a, &b};
  ASSERT_EQ(count_new_folds(base, std::span(diffs), a), 0u);

  // The merge's changed vertices: a band around c, all shifted a little, c by the sum.
  std::vector<std::uint32_t> vertices;
  std::vector<Vec3f> moved;
  for (std::uint32_t v = 0; v < base.vertex_count(); ++v)
    if (ring_distance(n, v, c) <= 10) {
      vertices.push_back(v);
      const Vec3f p = base.positions[v];
      moved.push_back(v == c ? Vec3f{p.x + 1.2f, p.y, p.z + 0.05f} : Vec3f{p.x, p.y, p.z + 0.01f});
    }
  const std::vector<Vec3f> before = moved;
  Diff merged;
  merged.vertex_count = a.vertex_count;
  merged.positions.indices = vertices;
  for (const Vec3f& p : moved)
    merged.positions.values.insert(merged.positions.values.end(), {p.x, p.y, p.z});
  const std::uint32_t folds_before = count_new_folds(base, std::span(diffs), merged);
  ASSERT_GT(folds_before, 0u);

  detail::FoldRepairScratch scratch;
  detail::WorkerPool pool(2);
  const std::uint32_t found = detail::repair_new_folds(
      topology, base.positions, vertices, std::span(diffs), {}, moved, scratch, pool, 4);
  EXPECT_EQ(found, folds_before);
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    float* out = merged.positions.values.data() + 3 * i;
    out[0] = moved[i].x;
    out[1] = moved[i].y;
    out[2] = moved[i].z;
  }
  EXPECT_EQ(count_new_folds(base, std::span(diffs), merged), 0u);
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (ring_distance(n, vertices[i], c) > 8) {
      EXPECT_EQ(moved[i], before[i]) << "vertex " << vertices[i] << " is far from the fold";
    }
  // The repair gave way, it did not erase: the pushes' sum stays (smoothing a displacement
  // moves it between neighbours; pulling toward one artist's edit would drop the other's
  // 0.6), and c is still pushed further than any neighbour.
  double pushed = 0;
  for (std::size_t i = 0; i < vertices.size(); ++i)
    pushed += moved[i].x - base.positions[vertices[i]].x;
  EXPECT_GE(pushed, 0.9 * 1.2 - 1e-6);
  const std::size_t ci =
      std::size_t(std::find(vertices.begin(), vertices.end(), c) - vertices.begin());
  for (std::size_t i = 0; i < vertices.size(); ++i)
    if (i != ci) {
      EXPECT_LT(moved[i].x - base.positions[vertices[i]].x, moved[ci].x - base.positions[c].x);
    }

  // The scratch is clean for the next call: the same call again gives the same result.
  std::vector<Vec3f> again = before;
  detail::repair_new_folds(topology, base.positions, vertices, std::span(diffs), {}, again, scratch,
                           pool, 4);
  EXPECT_EQ(again, moved);
}

/// A diff moving v by `by` and u > v by `u_by`.
Diff moving_two(const Mesh& base, std::uint32_t v, Vec3f by, std::uint32_t u, Vec3f u_by) {
  Diff d = moving(base, v, by);
  const Vec3f p = add(base.positions[u], u_by);
  d.positions.indices.push_back(u);
  d.positions.values.insert(d.positions.values.end(), {p.x, p.y, p.z});
  return d;
}

/// The new folds of the merged positions `moved` (of `vertices`) of `coarse` and `carried`
/// before and after the repair, told that `coarse` carried `carried` (the transport's w = 1);
/// `moved` holds the repaired positions afterwards.
std::pair<std::uint32_t, std::uint32_t> repair_carried(const Mesh& base, const Diff& coarse,
                                                       const Diff& carried,
                                                       const std::vector<std::uint32_t>& vertices,
                                                       std::vector<Vec3f>& moved) {
  const Topology topology = Topology::build(std::uint32_t(base.vertex_count()), base.triangles);
  const Diff* diffs[] = {&coarse, &carried};
  const double carrying[] = {0, 1, 0, 0};
  auto new_folds = [&] {
    Diff d;
    d.vertex_count = static_cast<std::uint32_t>(base.vertex_count());
    d.positions.indices = vertices;
    for (const Vec3f& p : moved)
      d.positions.values.insert(d.positions.values.end(), {p.x, p.y, p.z});
    return count_new_folds(base, std::span(diffs), d);
  };
  const std::uint32_t before = new_folds();
  detail::FoldRepairScratch scratch;
  detail::WorkerPool pool(1);
  detail::repair_new_folds(topology, base.positions, vertices, std::span(diffs), {}, moved, scratch,
                           pool, 4, carrying);
  return {before, new_folds()};
}

// A coarse stroke that nearly flattens two faces (c pushed 0.99 of an edge toward its right
// neighbour) and folds a face beside them itself, carrying another artist's stroke that moves
// c by a fiftieth of an edge: added, the two faces turn over. Addition folds them too and the
// coarse stroke's own fold is beside them, but no artist folded these two: the repair ends
// them (left as the artists' crumpling, such folds stayed in quiet four-peer demos, seeds 3
// and 11).
TEST(FoldRepair, RepairsAFoldATinyCarriedStrokeTipsBesideTheCarriersOwn) {
  const std::uint32_t n = 25, c = 12 * n + 12;
  const Mesh base = grid(n);
  const Diff coarse = moving_two(base, c, {0.99f, 0.f, 0.f}, c + n, {1.5f, 0.f, 0.f});
  const Diff tiny = moving(base, c, {0.02f, 0.f, 0.f});
  const std::vector<std::uint32_t> vertices = {c, c + n};
  const std::vector<Vec3f> coarse_at = {add(base.positions[c], Vec3f{0.99f, 0.f, 0.f}),
                                        add(base.positions[c + n], Vec3f{1.5f, 0.f, 0.f})};
  std::vector<Vec3f> moved = {add(coarse_at[0], Vec3f{0.02f, 0.f, 0.f}), coarse_at[1]};
  const auto [before, after] = repair_carried(base, coarse, tiny, vertices, moved);
  ASSERT_EQ(before, 2u);
  EXPECT_EQ(after, 0u);
  // What gave way is the tiny stroke's push, not the coarse stroke (its own fold included).
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Vec3f d = sub(moved[i], coarse_at[i]);
    EXPECT_LE(std::sqrt(dot(d, d)), 0.02f) << "vertex " << vertices[i];
  }
}

// A coarse stroke lifts c and pushes it 0.99 of an edge toward its right neighbour (two faces
// nearly on edge), carrying another artist's pinch that pushes c on by 0.13 of an edge and
// folds faces of its own around c's upper neighbour. Added, the two faces turn over. The fold
// beside is the carried pinch's: the coarse stroke moved the pinch's crumple there, and the
// repair ends it (a grab carrying a pinch that folded a hundred faces of its own left one to
// three such folds in quiet four-peer demos).
TEST(FoldRepair, RepairsAFoldBesideACarriedDetailsOwnCrumple) {
  const std::uint32_t n = 25, c = 12 * n + 12;
  const Mesh base = grid(n);
  const Diff coarse = moving(base, c, {0.99f, 0.f, 1.f});
  const Diff pinch = moving_two(base, c, {0.13f, 0.f, 0.f}, c + n, {1.5f, 0.f, 0.f});
  std::vector<Vec3f> moved = {add(base.positions[c], Vec3f{1.12f, 0.f, 1.f}),
                              add(base.positions[c + n], Vec3f{1.5f, 0.f, 0.f})};
  const auto [before, after] = repair_carried(base, coarse, pinch, {c, c + n}, moved);
  ASSERT_EQ(before, 2u);
  EXPECT_EQ(after, 0u);
}

TEST(FoldRepair, NothingFoldedLeavesEveryPositionBitIdentical) {
  const std::uint32_t n = 9, c = 4 * n + 4;
  const Mesh base = grid(n);
  const Topology topology = Topology::build(std::uint32_t(base.vertex_count()), base.triangles);
  const Diff a = moving(base, c, {0.2f, 0.f, 0.3f});
  const Diff* diffs[] = {&a};
  std::vector<std::uint32_t> vertices = {c};
  std::vector<Vec3f> moved = {{base.positions[c].x + 0.2f, base.positions[c].y, 0.3f}};
  const std::vector<Vec3f> before = moved;
  detail::FoldRepairScratch scratch;
  detail::WorkerPool pool(1);
  EXPECT_EQ(detail::repair_new_folds(topology, base.positions, vertices, std::span(diffs), {},
                                     moved, scratch, pool, 4),
            0u);
  EXPECT_EQ(moved, before);
}

/// The authored cases whose frame-carrying merge folded faces no single edit folds: a strong
/// detail closed on itself by a 170-degree bend, a grab over a detail on a shipped engine.
TEST(FoldRepair, FullFoldsNothingNewOnTheAuthoredCasesThatFolded) {
  for (const char* name : {"bend_plus_strong_detail_capsule", "grab_plus_detail_engine_shipped"}) {
    const fs::path d = fs::path(CSCULPT_REPO_CASES) / name;
    ASSERT_TRUE(fs::is_regular_file(d / "base.ply")) << d;
    const Mesh base = read_mesh((d / "base.ply").string());
    std::vector<Diff> diffs;
    for (const char* e : {"a.ply", "b.ply"})
      diffs.push_back(capture_diff(base, read_mesh((d / e).string())));
    const Hierarchy h = Hierarchy::build(base);
    Merger merger(h);
    const Diff merged = merger.merge(base, std::span<const Diff>(diffs), MergeMethod::full);
    EXPECT_GT(merger.last_timings().new_folds_repaired, 0u)
        << name << ": the repair had nothing to do";
    std::vector<const Diff*> inputs = {&diffs[0], &diffs[1]};
    EXPECT_EQ(count_new_folds(h.topology(), base, inputs, merged), 0u) << name;
  }
}

// Captured from a quiet four-peer demo (seed 3), cut to the 16 rings around the fold: a face
// an earlier stroke crumpled to a tenth of an edge, turned over among its neighbours, which
// two artists' grabs move by 4-5 edges (30-60 of its own sizes) in different directions.
// Either grab alone keeps it as it was; added, they turn it back (addition folds it too).
// Pulled toward the grab that moves it most, placed where that grab alone puts it, the
// region's fade was as steep as the other grab is long and folded the face again; placed
// where the merge put the region, only the other grab's change of shape gives way.
TEST(FoldRepair, AFaceCrumpledInTheBaseKeepsItsSideUnderTwoGrabs) {
  const fs::path d = fs::path(CSCULPT_SDK_TEST_DATA) / "crumpled_face_under_two_grabs";
  const Mesh base = read_mesh((d / "base.ply").string());
  std::vector<Diff> diffs;
  for (const char* e : {"a.ply", "b.ply"})
    diffs.push_back(capture_diff(base, read_mesh((d / e).string())));
  const Hierarchy h = Hierarchy::build(base);
  std::vector<const Diff*> inputs = {&diffs[0], &diffs[1]};
  Merger merger(h);
  ASSERT_GT(count_new_folds(h.topology(), base, inputs,
                            merger.merge(base, std::span<const Diff>(diffs), MergeMethod::sum)),
            0u);
  const Diff merged = merger.merge(base, std::span<const Diff>(diffs), MergeMethod::full);
  EXPECT_GT(merger.last_timings().new_folds_repaired, 0u) << "the merge folded nothing to repair";
  EXPECT_EQ(count_new_folds(h.topology(), base, inputs, merged), 0u);
}

// What a session merges under load: each of four artists' scripted strokes (the demo's
// scripts) accumulated over a long interval, all merged at once. Strong brushes of two or
// three artists cross there; repairing their folds toward one artist's edit over a narrow
// band of rings folded the band's edge instead (a `csculpt demo --peers 4` merge: 162 folds
// left after the first phase, 401 after the second; 585 over the session).
TEST(FoldRepair, LongScriptedSessionsOfFourArtistsMergeWithoutNewFolds) {
  const Mesh base = make_sphere(80000);
  const Hierarchy h = Hierarchy::build(base);
  Merger merger(h);
  for (std::uint64_t seed : {3u, 7u, 11u, 13u, 17u, 19u}) {
    for (std::uint32_t strokes : {12u, 24u, 48u}) {
      std::vector<Diff> diffs;
      for (std::uint32_t k = 0; k < 4; ++k) {
        Mesh edit = base;
        const auto script = scripted_strokes(base, seed * 7919 + k, strokes, /*paint=*/false);
        for (const Stroke& s : script) apply_stroke(edit, s, &h.topology());
        diffs.push_back(capture_diff(base, edit));
      }
      std::vector<const Diff*> inputs;
      for (const Diff& d : diffs) inputs.push_back(&d);
      const Diff merged = merger.merge(base, diffs, MergeMethod::full);
      EXPECT_EQ(count_new_folds(h.topology(), base, inputs, merged), 0u)
          << "seed " << seed << ", " << strokes << " strokes per artist";
    }
  }
}

// The same at the demo's resolution (320K faces) with what a loaded machine merges at once:
// three artists' ~100 strokes each (20 s at 5 strokes a second), every vertex moved by all
// three, 10-18 edges at a time. Smoothing over three rings kept some folds whatever its
// sweeps (the harmonic fill of a region folds where the displacements around it differ by
// more than it is wide), and the pull toward one artist's edit that followed folded its own
// fade: 9,372 new folds on seed 3, and a 10 s merge that stalled a four-peer demo's
// heartbeats. The repair now undoes a phase that leaves more folds than it found and ends
// with smoothing that widens while folds remain.
TEST(FoldRepair, HundredStrokeRunsOfThreeArtistsAtTheDemosResolution) {
  const Mesh base = make_sphere(320000);
  const Hierarchy h = Hierarchy::build(base);
  Merger merger(h);
  for (std::uint64_t seed : {3u, 7u, 11u}) {
    std::vector<Diff> diffs;
    for (std::uint32_t k = 0; k < 3; ++k) {
      Mesh edit = base;
      const auto script = scripted_strokes(base, seed * 7919 + k, 96, /*paint=*/false);
      for (const Stroke& s : script) apply_stroke(edit, s, &h.topology());
      diffs.push_back(capture_diff(base, edit));
    }
    std::vector<const Diff*> inputs;
    for (const Diff& d : diffs) inputs.push_back(&d);
    const Diff merged = merger.merge(base, diffs, MergeMethod::full);
    EXPECT_EQ(count_new_folds(h.topology(), base, inputs, merged), 0u) << "seed " << seed;
  }
}

/// The grid with its middle column split: the cells right of it use copies of the column's
/// vertices (coincident, unconnected, as a UV seam leaves them). `twins` gets the pairs.
Mesh split_grid(std::uint32_t n, std::vector<std::pair<std::uint32_t, std::uint32_t>>& twins) {
  Mesh m = grid(n);
  const std::uint32_t seam = n / 2;
  std::vector<std::uint32_t> copy(m.vertex_count(), 0);
  for (std::uint32_t y = 0; y < n; ++y) {
    const std::uint32_t v = y * n + seam;
    copy[v] = static_cast<std::uint32_t>(m.positions.size());
    m.positions.push_back(m.positions[v]);
    twins.push_back({v, copy[v]});
  }
  for (Triangle& t : m.triangles) {
    float x = 0;
    for (std::uint32_t v : t) x += m.positions[v].x;
    if (x / 3 > float(seam))
      for (std::uint32_t& v : t)
        if (v < n * n && v % n == seam) v = copy[v];
  }
  return m;
}

// Two artists each push the same seam vertex, both of its copies together, along the seam:
// together they fold faces on both sides, and the repair, smoothing each side with its own
// neighbours, must still leave the copies together (no crack), as the artists left them.
TEST(FoldRepair, ASplitSeamMovedTogetherStaysClosedThroughTheRepair) {
  const std::uint32_t n = 25;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> twins;
  const Mesh base = split_grid(n, twins);
  const Hierarchy h = Hierarchy::build(base);
  const auto [c, twin] = twins[n / 2];
  auto pushed = [&](Vec3f by) {
    Mesh e = base;
    for (std::uint32_t v : {c, twin}) e.positions[v] = add(e.positions[v], by);
    // a soft shoulder on the left side only, so the two sides' neighbourhoods differ
    e.positions[c - 1] = add(e.positions[c - 1], scale(by, 0.5f));
    return capture_diff(base, e);
  };
  const Diff diffs[] = {pushed({0.f, 0.6f, 0.f}), pushed({0.f, 0.6f, 0.05f})};
  Merger merger(h);
  const Diff merged = merger.merge(base, diffs, MergeMethod::full);
  EXPECT_GT(merger.last_timings().new_folds_repaired, 0u) << "the merge folded nothing to repair";
  const Diff* inputs[] = {&diffs[0], &diffs[1]};
  EXPECT_EQ(count_new_folds(base, inputs, merged), 0u);
  Mesh result = base;
  apply_diff(merged, result);
  for (const auto& [v, w] : twins) EXPECT_EQ(result.positions[v], result.positions[w]) << v;
  EXPECT_GT(result.positions[c].y - base.positions[c].y, 0.3f);
}

}  // namespace
}  // namespace csculpt
