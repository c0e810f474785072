// The multiresolution hierarchy of paper §3.1 ("Hierarchy Construction"): structural
// invariants of every level, the greedy selection property, determinism, statistics against
// the paper's figures, connected components, and input validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"
#include "test_meshes.h"

namespace csculpt {
namespace {

/// Connected components of the vertex graph (vertices on no triangle count alone).
std::uint32_t count_components(std::uint32_t vertex_count, const std::vector<Triangle>& tris) {
  std::vector<std::uint32_t> parent(vertex_count);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Triangle& t : tris) {
    for (int c = 1; c < 3; ++c) {
      const std::uint32_t a = find(t[0]), b = find(t[static_cast<std::size_t>(c)]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  }
  std::uint32_t n = 0;
  for (std::uint32_t v = 0; v < vertex_count; ++v) n += find(v) == v ? 1 : 0;
  return n;
}

/// Every invariant that does not depend on the particular mesh. Weights must be >= 0 here;
/// strict positivity of used slots is asserted on its own in HierarchyWeights (see there).
/// `sorted`: weights must be non-increasing along the slots (the paper's "K heaviest" in
/// order), which holds without linear precision only (that option moves weights afterwards).
void check_invariants(const Hierarchy& h, const std::vector<Triangle>& tris, bool sorted) {
  const auto levels = h.levels();
  const std::uint32_t K = h.max_parents();
  ASSERT_EQ(h.stride(), K);
  ASSERT_GE(levels.size(), 1u);
  const Topology& topo = h.topology();
  ASSERT_EQ(levels[0].node_count, topo.vertex_count);
  for (std::uint32_t v = 0; v < topo.vertex_count; ++v) ASSERT_EQ(levels[0].representative[v], v);

  for (std::size_t i = 0; i + 1 < levels.size(); ++i) {
    SCOPED_TRACE("level " + std::to_string(i));
    const HierarchyLevel& fine = levels[i];
    const HierarchyLevel& coarse = levels[i + 1];
    const std::uint32_t n = fine.node_count, m = coarse.node_count;
    ASSERT_LT(m, n);
    ASSERT_GE(m, 1u);
    ASSERT_EQ(fine.parent.size(), std::size_t{n} * K);
    ASSERT_EQ(fine.parent_weight.size(), std::size_t{n} * K);
    ASSERT_EQ(fine.parent_count.size(), n);
    ASSERT_EQ(coarse.child_weight_sum.size(), m);
    ASSERT_EQ(coarse.tree_child_count.size(), m);
    ASSERT_EQ(coarse.representative.size(), m);

    std::vector<double> child_sum(m, 0.0), tree_count(m, 0.0);
    int bad_count = 0, bad_weight = 0, bad_sum = 0, bad_unused = 0, bad_index = 0, bad_order = 0,
        bad_distinct = 0;
    double worst_sum = 0;
    for (std::uint32_t x = 0; x < n; ++x) {
      const std::uint32_t c = fine.parent_count[x];
      if (c < 1 || c > K) {
        ++bad_count;
        continue;
      }
      const std::uint32_t* p = fine.parent.data() + std::size_t{x} * K;
      const float* w = fine.parent_weight.data() + std::size_t{x} * K;
      double sum = 0;
      for (std::uint32_t k = 0; k < K; ++k) {
        if (p[k] >= m) {
          ++bad_index;
          continue;
        }
        if (k < c) {
          if (!(w[k] >= 0.f) || !std::isfinite(w[k])) ++bad_weight;
          if (sorted && k > 0 && w[k] > w[k - 1]) ++bad_order;  // first is the heaviest
          for (std::uint32_t j = 0; j < k; ++j) bad_distinct += p[j] == p[k] ? 1 : 0;
          sum += w[k];
          child_sum[p[k]] += w[k];
        } else if (w[k] != 0.f || p[k] != p[0]) {
          ++bad_unused;  // unused slots: weight 0, repeat the first parent
        }
      }
      if (p[0] < m) tree_count[p[0]] += 1;
      worst_sum = std::max(worst_sum, std::abs(sum - 1));
      bad_sum += std::abs(sum - 1) > 1e-5 ? 1 : 0;
    }
    EXPECT_EQ(bad_count, 0) << "parent_count outside 1..K";
    EXPECT_EQ(bad_index, 0) << "parent index >= next level's node count";
    EXPECT_EQ(bad_weight, 0) << "negative or non-finite weight in a used slot";
    EXPECT_EQ(bad_sum, 0) << "weights not summing to 1, worst |sum - 1| = " << worst_sum;
    EXPECT_EQ(bad_unused, 0) << "unused slot not (first parent, 0)";
    EXPECT_EQ(bad_order, 0) << "weights not in decreasing order";
    EXPECT_EQ(bad_distinct, 0) << "repeated parent among the used slots";

    int bad_child = 0, bad_tree = 0, childless = 0;  // (a coarse node is its copy's parent)
    double worst_child = 0;
    for (std::uint32_t c = 0; c < m; ++c) {
      const double d = std::abs(double(coarse.child_weight_sum[c]) - child_sum[c]);
      worst_child = std::max(worst_child, d);
      bad_child += d > 1e-4 ? 1 : 0;
      bad_tree += double(coarse.tree_child_count[c]) != tree_count[c] ? 1 : 0;
      childless += tree_count[c] > 0 ? 0 : 1;
    }
    EXPECT_EQ(bad_child, 0) << "child_weight_sum off by up to " << worst_child;
    EXPECT_EQ(bad_tree, 0) << "tree_child_count is not the number of first-parent children";
    EXPECT_EQ(childless, 0) << "coarse nodes with no children";

    // Each coarse node was selected from a fine node with the same representative; that node
    // is its own coarse copy's child, with the heaviest weight (its own set weighs 1 more
    // than anything its neighbours contribute).
    std::vector<std::uint32_t> node_of(topo.vertex_count, UINT32_MAX);
    for (std::uint32_t x = 0; x < n; ++x) node_of[fine.representative[x]] = x;
    int bad_rep = 0, bad_self = 0;
    for (std::uint32_t c = 0; c < m; ++c) {
      const std::uint32_t r = coarse.representative[c];
      if (r >= topo.vertex_count || node_of[r] == UINT32_MAX) {
        ++bad_rep;
        continue;
      }
      bad_self += fine.parent[std::size_t{node_of[r]} * K] != c ? 1 : 0;
    }
    EXPECT_EQ(bad_rep, 0) << "coarse representative not among the fine representatives";
    EXPECT_EQ(bad_self, 0) << "a selected node's first parent is not its own coarse copy";
  }

  // Coarsest level: no parents, one node per connected component.
  const HierarchyLevel& top = levels.back();
  EXPECT_TRUE(top.parent.empty());
  EXPECT_TRUE(top.parent_count.empty());
  EXPECT_EQ(top.node_count, count_components(topo.vertex_count, tris));

  // Level 1 is the paper's greedy selection on the mesh graph: representatives are pairwise
  // non-adjacent, and every vertex is one or is adjacent to one.
  if (levels.size() > 1) {
    std::vector<std::uint8_t> selected(topo.vertex_count, 0);
    for (std::uint32_t r : levels[1].representative) selected[r] = 1;
    int adjacent_pairs = 0, uncovered = 0;
    for (std::uint32_t v = 0; v < topo.vertex_count; ++v) {
      bool covered = selected[v] != 0;
      for (std::uint32_t u : topo.vertex_vertices.row(v)) {
        covered = covered || selected[u] != 0;
        adjacent_pairs += selected[v] && selected[u] ? 1 : 0;
      }
      uncovered += covered ? 0 : 1;
    }
    EXPECT_EQ(adjacent_pairs, 0) << "adjacent level-1 representatives";
    EXPECT_EQ(uncovered, 0) << "vertices neither selected nor next to a selected one";
  }

  // Stats agree with the levels.
  const HierarchyStats s = h.stats();
  EXPECT_EQ(s.vertices, topo.vertex_count);
  EXPECT_EQ(s.faces, tris.size());
  EXPECT_EQ(s.levels, levels.size());
  ASSERT_EQ(s.level_nodes.size(), levels.size());
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    EXPECT_EQ(s.level_nodes[i], levels[i].node_count);
    total += levels[i].node_count;
  }
  EXPECT_EQ(s.nodes, total);
  EXPECT_EQ(h.total_nodes(), total);
  EXPECT_EQ(s.top_nodes, top.node_count);
  EXPECT_GE(s.mean_parents, levels.size() > 1 ? 1.0 : 0.0);
  EXPECT_LE(s.mean_parents, double(K));
}

/// Vertex adjacency as built by Topology: symmetric, sorted, no self-links, exactly the
/// triangle edges.
void check_topology(const Topology& topo) {
  const auto& vv = topo.vertex_vertices;
  ASSERT_EQ(vv.rows(), topo.vertex_count);
  ASSERT_EQ(topo.vertex_faces.rows(), topo.vertex_count);
  std::size_t corners = 0;
  for (std::uint32_t v = 0; v < topo.vertex_count; ++v) {
    const auto row = vv.row(v);
    ASSERT_TRUE(std::is_sorted(row.begin(), row.end()));
    ASSERT_EQ(std::adjacent_find(row.begin(), row.end()), row.end());
    for (std::uint32_t u : row) {
      ASSERT_NE(u, v);
      const auto back = vv.row(u);
      ASSERT_TRUE(std::binary_search(back.begin(), back.end(), v)) << v << " - " << u;
    }
    for (std::uint32_t f : topo.vertex_faces.row(v)) {
      const Triangle& t = topo.triangles[f];
      ASSERT_TRUE(t[0] == v || t[1] == v || t[2] == v);
    }
    corners += topo.vertex_faces.row(v).size();
  }
  EXPECT_EQ(corners, 3 * topo.triangles.size());
}

Mesh two_spheres() {
  Mesh a = make_sphere(2000), b = make_sphere(1280);
  const auto offset = static_cast<std::uint32_t>(a.vertex_count());
  for (const Vec3f& p : b.positions) a.positions.push_back({p.x + 3.f, p.y, p.z});
  for (const Triangle& t : b.triangles)
    a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return a;
}

HierarchyOptions without_linear_precision(std::uint32_t k = 7) {
  HierarchyOptions o;
  o.max_parents = k;
  o.linear_precision = false;
  return o;
}

HierarchyOptions with_linear_precision(std::uint32_t k = 7) {
  HierarchyOptions o;
  o.max_parents = k;
  o.linear_precision = true;
  return o;
}

void expect_paper_statistics(const HierarchyStats& s) {
  EXPECT_EQ(s.top_nodes, 1u);
  EXPECT_GE(s.levels, 6u);
  EXPECT_LE(s.levels, 14u);
  EXPECT_GE(s.node_ratio, 1.2);  // paper: about 1.33
  EXPECT_LE(s.node_ratio, 1.6);
  EXPECT_GE(s.mean_level_ratio, 0.16);  // paper: 0.16..0.25 regular, 0.25..0.5 real
  EXPECT_LE(s.mean_level_ratio, 0.5);
  for (std::size_t i = 1; i < s.level_nodes.size(); ++i)
    EXPECT_LT(s.level_nodes[i], s.level_nodes[i - 1]);
}

TEST(HierarchySphere, InvariantsAndPaperStatistics) {
  const Mesh mesh = make_sphere(20000);
  ASSERT_GT(mesh.vertex_count(), 10000u);
  const Hierarchy h = Hierarchy::build(mesh);
  check_topology(h.topology());
  check_invariants(h, mesh.triangles, false);
  const HierarchyStats s = h.stats();
  expect_paper_statistics(s);
  EXPECT_GT(s.mean_parents, 2.0);  // K = 7 blends several parents on a regular mesh
  RecordProperty("stats", to_json(s));

  const Hierarchy plain = Hierarchy::build(mesh, without_linear_precision());
  check_invariants(plain, mesh.triangles, true);
  expect_paper_statistics(plain.stats());
}

TEST(HierarchySphere, LargeSphereStatistics) {
  const Mesh mesh = make_sphere(320000);
  ASSERT_GT(mesh.vertex_count(), 150000u);
  const HierarchyStats s = Hierarchy::build(mesh).stats();
  EXPECT_EQ(s.vertices, mesh.vertex_count());
  expect_paper_statistics(s);
  RecordProperty("stats", to_json(s));
}

TEST(HierarchyDeterminism, SameDigestEveryBuild) {
  const Mesh mesh = make_sphere(20000);
  const auto n = static_cast<std::uint32_t>(mesh.vertex_count());
  const Hierarchy a = Hierarchy::build(mesh);
  EXPECT_EQ(a.digest(), Hierarchy::build(mesh).digest());
  const Hierarchy connectivity_only = Hierarchy::build(n, mesh.triangles);
  EXPECT_EQ(connectivity_only.digest(), Hierarchy::build(n, mesh.triangles).digest());

  // Without positions (or without linear precision) it is a function of connectivity only.
  Mesh moved = mesh;
  for (Vec3f& p : moved.positions) p = {2 * p.x + 1, p.y * p.y, -p.z};
  EXPECT_EQ(Hierarchy::build(moved, without_linear_precision()).digest(),
            Hierarchy::build(mesh, without_linear_precision()).digest());
  EXPECT_EQ(Hierarchy::build(mesh, without_linear_precision()).digest(),
            connectivity_only.digest());
  // With linear precision the weights follow the positions (header: pass the session's
  // initial positions, which every peer holds bit for bit).
  EXPECT_NE(Hierarchy::build(moved, with_linear_precision()).digest(),
            Hierarchy::build(mesh, with_linear_precision()).digest());
  EXPECT_EQ(Hierarchy::build(moved, with_linear_precision()).digest(),
            Hierarchy::build(moved, with_linear_precision()).digest());
  // The default is connectivity only: moving the vertices changes nothing.
  EXPECT_EQ(Hierarchy::build(moved).digest(), a.digest());

  // The digest does see different connectivity and a different K.
  EXPECT_NE(Hierarchy::build(make_sphere(5000)).digest(), a.digest());
  HierarchyOptions k4;
  k4.max_parents = 4;
  EXPECT_NE(Hierarchy::build(mesh, k4).digest(), a.digest());
}

TEST(HierarchyK, SingleParentGivesATree) {
  const Mesh mesh = make_sphere(20000);
  HierarchyOptions tree;
  tree.max_parents = 1;
  const Hierarchy h = Hierarchy::build(mesh, tree);
  EXPECT_EQ(h.stride(), 1u);
  check_invariants(h, mesh.triangles, true);
  const auto levels = h.levels();
  for (std::size_t i = 0; i + 1 < levels.size(); ++i) {
    const HierarchyLevel& fine = levels[i];
    for (std::uint32_t x = 0; x < fine.node_count; ++x) {
      ASSERT_EQ(fine.parent_count[x], 1u) << "level " << i << " node " << x;
      ASSERT_EQ(fine.parent_weight[x], 1.f) << "level " << i << " node " << x;
    }
    // in a tree the child weight sums are the children counts
    const HierarchyLevel& coarse = levels[i + 1];
    for (std::uint32_t c = 0; c < coarse.node_count; ++c)
      ASSERT_EQ(coarse.child_weight_sum[c], coarse.tree_child_count[c]) << "level " << i + 1;
  }
  EXPECT_DOUBLE_EQ(h.stats().mean_parents, 1.0);

  // The tree is the K = 7 hierarchy's first parents (the same selection).
  const Hierarchy full = Hierarchy::build(mesh);
  ASSERT_EQ(full.levels().size(), levels.size());
  for (std::size_t i = 0; i < levels.size(); ++i) {
    ASSERT_EQ(full.levels()[i].node_count, levels[i].node_count);
    EXPECT_EQ(full.levels()[i].representative, levels[i].representative);
    EXPECT_EQ(full.levels()[i].tree_child_count, levels[i].tree_child_count);
    if (i + 1 < levels.size()) {
      for (std::uint32_t x = 0; x < levels[i].node_count; ++x)
        ASSERT_EQ(full.levels()[i].parent[std::size_t{x} * 7], levels[i].parent[x]) << x;
    }
  }
}

TEST(HierarchyK, AllValidKAreAccepted) {
  const Mesh mesh = make_sphere(500);
  for (std::uint32_t k : {2u, 3u, 7u, 32u}) {
    SCOPED_TRACE("K = " + std::to_string(k));
    HierarchyOptions o;
    o.max_parents = k;
    const Hierarchy h = Hierarchy::build(mesh, o);
    EXPECT_EQ(h.max_parents(), k);
    check_invariants(h, mesh.triangles, false);
    check_invariants(Hierarchy::build(mesh, without_linear_precision(k)), mesh.triangles, true);
  }
}

TEST(HierarchyComponents, TwoDisjointSpheresEndWithTwoTopNodes) {
  const Mesh mesh = two_spheres();
  const Hierarchy h = Hierarchy::build(mesh);
  check_invariants(h, mesh.triangles, false);
  const HierarchyLevel& top = h.levels().back();
  ASSERT_EQ(top.node_count, 2u);
  EXPECT_EQ(h.stats().top_nodes, 2u);
  // one top node per sphere
  const auto first_b = static_cast<std::uint32_t>(make_sphere(2000).vertex_count());
  const bool a0 = top.representative[0] < first_b, a1 = top.representative[1] < first_b;
  EXPECT_NE(a0, a1);
}

TEST(HierarchyComponents, IsolatedVerticesAndSmallPieces) {
  // vertex 7 is on no triangle; a lone triangle; two triangles sharing an edge
  const std::vector<Triangle> tris = {{0, 1, 2}, {3, 4, 5}, {4, 6, 5}};
  const Hierarchy h = Hierarchy::build(8, tris);
  check_invariants(h, tris, true);
  EXPECT_EQ(h.levels().back().node_count, 3u);
}

TEST(TopologyBorder, OpenRimsOnly) {
  // A closed surface has no border.
  const Mesh sphere = make_sphere(500);
  const Topology closed =
      Topology::build(static_cast<std::uint32_t>(sphere.vertex_count()), sphere.triangles);
  EXPECT_EQ(std::count(closed.border.begin(), closed.border.end(), 1), 0);
  // A fan of three triangles around vertex 0, open between 4 and 1 (the hub's edges to 1
  // and 4 belong to one triangle each); vertex 5 is on no triangle; three triangles share
  // edge 6-7 (non-manifold) and are open at their other edges.
  const std::vector<Triangle> tris = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {6, 7, 8}, {7, 6, 9},
                                      {6, 7, 10}};
  const Topology open = Topology::build(11, tris);
  const std::vector<std::uint8_t> expected = {1, 1, 1, 1, 1, 0, 1, 1, 1, 1, 1};
  EXPECT_EQ(open.border, expected);
  // A tetrahedron: every edge in two triangles.
  const std::vector<Triangle> tetra = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}};
  const Topology shut = Topology::build(4, tetra);
  EXPECT_EQ(std::count(shut.border.begin(), shut.border.end(), 1), 0);
}

TEST(HierarchyValidation, RejectsBadInput) {
  const std::vector<Triangle> bad = {{0, 1, 2}, {2, 1, 5}};
  EXPECT_THROW(Hierarchy::build(5, bad), InvalidInput);
  EXPECT_THROW(Topology::build(5, bad), InvalidInput);
  EXPECT_NO_THROW(Hierarchy::build(6, bad));
  const Mesh mesh = make_sphere(500);
  HierarchyOptions o;
  o.max_parents = 0;
  EXPECT_THROW(Hierarchy::build(mesh, o), InvalidInput);
  o.max_parents = 33;
  EXPECT_THROW(Hierarchy::build(mesh, o), InvalidInput);
  o.max_parents = 32;
  EXPECT_NO_THROW(Hierarchy::build(mesh, o));
}

/// A (n+1)^2 grid over [0,1]^2 with interior vertices jittered in the plane by up to 15% of
/// the spacing (deterministic), so that parent sets are irregular.
Mesh jittered_grid(int n) {
  Mesh mesh = test::make_grid(n);
  std::uint64_t state = 12345;
  auto next = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<float>(state >> 40) / static_cast<float>(1u << 24) - 0.5f;
  };
  const float h = 1.f / static_cast<float>(n);
  for (Vec3f& p : mesh.positions) {
    const float dx = next(), dy = next();
    if (p.x > 0 && p.x < 1 && p.y > 0 && p.y < 1) {
      p.x += 0.3f * h * dx;
      p.y += 0.3f * h * dy;
    }
  }
  return mesh;
}

/// Per level: mean |sum_k w_k X_parent_k - x| over nodes whose representative lies in
/// [lo, hi]^2 (away from the grid boundary).
std::vector<double> interior_residuals(const Hierarchy& h, const Mesh& mesh, float lo, float hi) {
  std::vector<double> out;
  const auto levels = h.levels();
  const std::uint32_t K = h.stride();
  for (std::size_t i = 0; i + 1 < levels.size(); ++i) {
    const HierarchyLevel& fine = levels[i];
    const HierarchyLevel& coarse = levels[i + 1];
    double sum = 0;
    std::size_t count = 0;
    for (std::uint32_t x = 0; x < fine.node_count; ++x) {
      const Vec3f& p = mesh.positions[fine.representative[x]];
      if (p.x < lo || p.x > hi || p.y < lo || p.y > hi) continue;
      double cx = 0, cy = 0, cz = 0;
      for (std::uint32_t k = 0; k < K; ++k) {
        const double w = fine.parent_weight[std::size_t{x} * K + k];
        const Vec3f& q = mesh.positions[coarse.representative[fine.parent[std::size_t{x} * K + k]]];
        cx += w * q.x;
        cy += w * q.y;
        cz += w * q.z;
      }
      sum += std::sqrt((cx - p.x) * (cx - p.x) + (cy - p.y) * (cy - p.y) + (cz - p.z) * (cz - p.z));
      ++count;
    }
    out.push_back(count ? sum / static_cast<double>(count) : 0.0);
  }
  return out;
}

// SDK ISSUE (reported, not weakened): with linear_precision (the default) weights that the
// adjustment clamps to 0 stay in used slots (slot < parent_count), so parent_count and
// mean_parents over-count and the "used slots have positive weights" invariant fails
// (sphere 20480 faces: thousands of such slots on levels >= 1). Without linear precision
// every used slot is positive.
TEST(HierarchyWeights, UsedSlotsArePositive) {
  const std::vector<Mesh> meshes = {make_sphere(20000), two_spheres(), jittered_grid(40)};
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    for (bool precise : {false, true}) {
      SCOPED_TRACE("mesh " + std::to_string(m) + (precise ? ", linear precision" : ""));
      HierarchyOptions o;
      o.linear_precision = precise;
      const Hierarchy h = Hierarchy::build(meshes[m], o);
      const auto levels = h.levels();
      for (std::size_t i = 0; i + 1 < levels.size(); ++i) {
        std::size_t non_positive = 0;
        for (std::uint32_t x = 0; x < levels[i].node_count; ++x)
          for (std::uint32_t k = 0; k < levels[i].parent_count[x]; ++k)
            non_positive += levels[i].parent_weight[std::size_t{x} * h.stride() + k] > 0.f ? 0 : 1;
        EXPECT_EQ(non_positive, 0u)
            << "level " << i << " of " << levels.size() << ": used slots with weight <= 0";
      }
    }
  }
}

TEST(HierarchyWeights, LinearPrecisionOnlyReweights) {
  // Same selection; each node keeps a subset of its parents (those the adjustment clamps
  // to zero are dropped), heaviest first; only the weights move.
  const Mesh mesh = make_sphere(20000);
  const Hierarchy a = Hierarchy::build(mesh, with_linear_precision());
  const Hierarchy b = Hierarchy::build(mesh, without_linear_precision());
  ASSERT_EQ(a.levels().size(), b.levels().size());
  bool any_weight_differs = false;
  for (std::size_t i = 0; i < a.levels().size(); ++i) {
    const HierarchyLevel& la = a.levels()[i];
    const HierarchyLevel& lb = b.levels()[i];
    EXPECT_EQ(la.node_count, lb.node_count);
    EXPECT_EQ(la.representative, lb.representative);
    const std::uint32_t K = a.stride();
    for (std::uint32_t x = 0; x < la.parent_count.size(); ++x) {
      ASSERT_LE(la.parent_count[x], lb.parent_count[x]);
      for (std::uint32_t k = 0; k < la.parent_count[x]; ++k) {
        const std::uint32_t p = la.parent[std::size_t{x} * K + k];
        bool found = false;
        for (std::uint32_t q = 0; q < lb.parent_count[x]; ++q)
          found |= lb.parent[std::size_t{x} * K + q] == p;
        ASSERT_TRUE(found) << "level " << i << " node " << x << " gained parent " << p;
        if (k > 0) {
          ASSERT_GE(la.parent_weight[std::size_t{x} * K + k - 1],
                    la.parent_weight[std::size_t{x} * K + k]);
        }
      }
    }
    any_weight_differs = any_weight_differs || la.parent_weight != lb.parent_weight;
  }
  EXPECT_TRUE(any_weight_differs);
}

TEST(HierarchyWeights, LinearPrecisionReproducesPositionsOnAJitteredGrid) {
  const Mesh mesh = jittered_grid(64);
  const Hierarchy precise = Hierarchy::build(mesh, with_linear_precision());
  const Hierarchy plain = Hierarchy::build(mesh, without_linear_precision());
  check_invariants(precise, mesh.triangles, false);
  check_invariants(plain, mesh.triangles, true);
  const std::vector<double> rp = interior_residuals(precise, mesh, 0.2f, 0.8f);
  const std::vector<double> rn = interior_residuals(plain, mesh, 0.2f, 0.8f);
  ASSERT_GE(rp.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE("level " + std::to_string(i));
    EXPECT_GT(rn[i], 1e-4);                  // jitter: the plain blend misses the node
    EXPECT_LT(rp[i], 0.05 * rn[i]);          // linear precision (nearly) reproduces it
    EXPECT_LT(rp[i], 1e-3 / 64 * (1 << i));  // well under the level's spacing
  }
}

class HierarchyRealMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(HierarchyRealMesh, Invariants) {
  const std::string path = std::string(CSCULPT_TEST_MODELS) + "/" + GetParam();
  // Skipped only when assimp-testmodels is not installed; a file that is there must read.
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent (assimp-testmodels)";
  Mesh mesh;
  try {
    mesh = read_mesh(path);
  } catch (const std::exception& e) {
    FAIL() << "read_mesh(" << path << ") failed: " << e.what();
  }
  ASSERT_GT(mesh.vertex_count(), 0u);
  const Hierarchy h = Hierarchy::build(mesh);
  check_topology(h.topology());
  check_invariants(h, mesh.triangles, false);
  EXPECT_EQ(h.digest(), Hierarchy::build(mesh).digest());
  check_invariants(Hierarchy::build(mesh, without_linear_precision()), mesh.triangles, true);
  RecordProperty("stats", to_json(h.stats()));
}

INSTANTIATE_TEST_SUITE_P(HierarchyAssimp, HierarchyRealMesh,
                         ::testing::Values("PLY/Wuson.ply", "OBJ/spider.obj",
                                           "STL/Spider_binary.stl", "OFF/Wuson.off"),
                         [](const auto& test_param) {
                           std::string name = test_param.param;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace csculpt
