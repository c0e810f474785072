// The brush's spatial index (reference-app/bvh.cpp): after any sequence of dabs that move
// vertices (refit grows boxes, tighten refits them exactly, refit_exactly both at once,
// refit_leaves refits the leaves a dab's region query met), the region query finds exactly
// the vertices a brute-force search finds, each once, and a ray hits what brute force hits.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "bvh.h"
#include "icosphere.h"

namespace {

glm::vec3 at(const TriangleMesh& m, uint32_t v) {
  return {m.positions[3 * size_t{v}], m.positions[3 * size_t{v} + 1],
          m.positions[3 * size_t{v} + 2]};
}

std::vector<uint32_t> query(const TriangleBvh& bvh, const TriangleMesh& m, glm::vec3 c, float r) {
  std::vector<uint32_t> out;
  bvh.for_each_leaf_near(c, r, [&](uint32_t leaf) {  // as the brush's region query walks it
    for (uint32_t v : bvh.owned_vertices(leaf))
      if (glm::length(at(m, v) - c) <= r) out.push_back(v);
  });
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<uint32_t> brute_force(const TriangleMesh& m, glm::vec3 c, float r) {
  std::vector<bool> used(m.positions.size() / 3, false);
  for (uint32_t v : m.triangles) used[v] = true;
  std::vector<uint32_t> out;
  for (uint32_t v = 0; v < used.size(); ++v)
    if (used[v] && glm::length(at(m, v) - c) <= r) out.push_back(v);
  return out;
}

/// Moves the vertices within `r` of `c` outward by up to `depth` (a draw dab), returning them.
std::vector<uint32_t> dab(TriangleMesh& m, glm::vec3 c, float r, float depth) {
  std::vector<uint32_t> moved;
  for (uint32_t v = 0; v < m.positions.size() / 3; ++v) {
    const float d = glm::length(at(m, v) - c);
    if (d > r) continue;
    const glm::vec3 p = at(m, v) * (1.f + depth * (1.f - d / r));
    for (int k = 0; k < 3; ++k) m.positions[3 * size_t{v} + k] = p[k];
    moved.push_back(v);
  }
  return moved;
}

TEST(AppBvh, QueriesAndRaysMatchBruteForceThroughGrownTightenedAndExactRefits) {
  TriangleMesh m = make_geodesic_sphere(20000);
  TriangleBvh bvh;
  bvh.build(m.positions, m.triangles);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  auto random_point = [&] { return glm::normalize(glm::vec3(u(rng), u(rng), u(rng))); };
  for (int step = 0; step < 60; ++step) {
    // A stroke of dabs pushing out (and, every other stroke, in), tightened at its end.
    const glm::vec3 c = random_point();
    const float depth = step % 2 ? -0.15f : 0.3f;
    // The leaves the dab's region meets hold every triangle with a corner in it, each once:
    // the app's dab recomputes those triangles' normals and refits those leaves.
    std::vector<uint32_t> leaves;
    bvh.for_each_leaf_near(c, 0.3f, [&](uint32_t leaf) { leaves.push_back(leaf); });
    std::vector<int> held(m.triangles.size() / 3, 0);
    for (uint32_t leaf : leaves)
      for (uint32_t t : bvh.leaf_triangles(leaf)) ++held[t];
    for (uint32_t t = 0; t < held.size(); ++t) {
      bool inside = false;
      for (int k = 0; k < 3; ++k) inside |= glm::length(at(m, m.triangles[3 * t + k]) - c) <= 0.3f;
      ASSERT_EQ(held[t], inside ? 1 : held[t]) << "step " << step << " triangle " << t;
      ASSERT_LE(held[t], 1);
    }
    const std::vector<uint32_t> moved = dab(m, c, 0.3f, depth);
    if (step % 4 == 3)
      bvh.refit_exactly(m.positions, m.triangles, moved);  // an undo or a merged version
    else if (step % 4 == 1)
      bvh.refit_leaves(m.positions, m.triangles, leaves);  // a dab
    else
      bvh.refit(m.positions, moved);  // a grab's move
    if (step % 3 == 2) bvh.tighten(m.positions, m.triangles);
    for (int q = 0; q < 5; ++q) {
      const glm::vec3 qc = q == 0 ? c * 1.2f : random_point() * (0.8f + 0.4f * (u(rng) + 1.f));
      const float qr = 0.1f + 0.2f * (u(rng) + 1.f);
      // Each vertex once: query() would show a repeat as a duplicate.
      std::vector<uint32_t> found = query(bvh, m, qc, qr);
      EXPECT_TRUE(std::adjacent_find(found.begin(), found.end()) == found.end());
      ASSERT_EQ(found, brute_force(m, qc, qr)) << "step " << step << " query " << q;
    }
    // A ray from outside towards the centre hits the nearest triangle brute force finds.
    const glm::vec3 origin = random_point() * 3.f, direction = glm::normalize(-origin);
    const RayHit hit = bvh.raycast(m.positions, m.triangles, origin, direction);
    ASSERT_TRUE(hit.hit);
    float nearest = INFINITY;
    for (uint32_t t = 0; t < m.triangles.size() / 3; ++t) {
      const glm::vec3 a = at(m, m.triangles[3 * t]);
      const glm::vec3 e1 = at(m, m.triangles[3 * t + 1]) - a,
                      e2 = at(m, m.triangles[3 * t + 2]) - a;
      const glm::vec3 p = glm::cross(direction, e2);
      const float det = glm::dot(e1, p);
      if (std::abs(det) < 1e-12f) continue;
      const glm::vec3 s = origin - a;
      const float bu = glm::dot(s, p) / det;
      const glm::vec3 qv = glm::cross(s, e1);
      const float bv = glm::dot(direction, qv) / det;
      const float d = glm::dot(e2, qv) / det;
      if (bu >= 0.f && bv >= 0.f && bu + bv <= 1.f && d > 0.f) nearest = std::min(nearest, d);
    }
    EXPECT_NEAR(hit.distance, nearest, 1e-4f) << "step " << step;
  }
}

}  // namespace

namespace {

bool same_box(const BvhBox& a, const BvhBox& b) {
  return a.lo == b.lo && a.hi == b.hi;
}

}  // namespace

// The session worker keeps a copy of the UI's tree: refitted to a version's positions there,
// the boxes it hands over around the moved vertices make the UI's copy, whose document now
// holds those positions, equal a tree refitted in place, box for box.
TEST(AppBvh, BoxesHandedOverFromACopyEqualARefitInPlace) {
  TriangleMesh m = make_geodesic_sphere(20000);
  TriangleBvh ui;
  ui.build(m.positions, m.triangles);
  TriangleBvh worker = ui, reference = ui;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-0.05f, 0.05f);
  std::vector<uint32_t> moved;
  for (uint32_t v = 0; v < m.positions.size() / 3; ++v) {
    if (m.positions[3 * size_t{v}] > 0.7f) moved.push_back(v);  // a version's cap
    if (v % 97 == 0) moved.push_back(v);                        // and scattered vertices
  }
  for (uint32_t v : moved)
    for (int c = 0; c < 3; ++c) m.positions[3 * size_t{v} + size_t(c)] += u(rng);
  worker.refit_exactly(m.positions, m.triangles, moved);
  std::vector<uint32_t> nodes;
  std::vector<BvhBox> boxes;
  worker.boxes_around(moved, nodes, boxes);
  ASSERT_FALSE(nodes.empty());
  ASSERT_EQ(nodes.size(), boxes.size());
  ASSERT_EQ(std::set<uint32_t>(nodes.begin(), nodes.end()).size(), nodes.size()) << "listed twice";
  ASSERT_LT(nodes.size(), ui.node_count());  // the boxes around, not the whole tree
  ui.set_boxes(nodes, boxes);
  reference.refit_exactly(m.positions, m.triangles, moved);
  for (uint32_t n = 0; n < ui.node_count(); ++n)
    ASSERT_TRUE(same_box(ui.box(n), reference.box(n))) << "node " << n;
}
