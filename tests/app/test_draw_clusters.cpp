// The renderer's clusters (reference-app/draw_clusters.cpp): a cluster left out of a draw as
// facing away holds no triangle that faces the eye — on a sculpted surface, with degenerate
// triangles, from eyes near and far, and after the surface moved (the clusters around the
// moved vertices are drawn whole until recomputed, a few per frame) — while most of what faces
// away on a sphere is left out;
// the draw order holds every triangle once, with its winding.
#include <gtest/gtest.h>

#include <glm/ext/matrix_clip_space.hpp>
#include <glm/ext/matrix_transform.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "draw_clusters.h"
#include "icosphere.h"

namespace {

using Vec = std::array<double, 3>;

Vec at(const TriangleMesh& m, uint32_t v) {
  return {m.positions[3 * size_t{v}], m.positions[3 * size_t{v} + 1],
          m.positions[3 * size_t{v} + 2]};
}

// Whether triangle t faces the eye (or is seen edge-on), in double: the sign GL's back-face
// test takes.
bool faces_eye(const TriangleMesh& m, uint32_t t, glm::vec3 eye) {
  const Vec a = at(m, m.triangles[3 * size_t{t}]), b = at(m, m.triangles[3 * size_t{t} + 1]),
            c = at(m, m.triangles[3 * size_t{t} + 2]);
  const Vec e1{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const Vec n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
              e1[0] * e2[1] - e1[1] * e2[0]};
  if (n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) return false;  // covers no pixel
  return n[0] * (eye.x - a[0]) + n[1] * (eye.y - a[1]) + n[2] * (eye.z - a[2]) >= 0.0;
}

// Every culled cluster's triangles face away; returns the fraction of triangles culled.
double check_culling(const DrawClusters& clusters, const TriangleMesh& m, glm::vec3 eye) {
  size_t culled = 0;
  for (uint32_t c = 0; c < clusters.cluster_count(); ++c) {
    if (!clusters.faces_away(c, eye)) continue;
    for (uint32_t t : clusters.cluster_triangles(c)) {
      EXPECT_FALSE(faces_eye(m, t, eye)) << "cluster " << c << " triangle " << t;
      ++culled;
    }
  }
  return double(culled) / double(m.triangles.size() / 3);
}

std::vector<glm::vec3> eyes(std::mt19937& rng, int count) {
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> distance(0.3f, 6.f);
  std::vector<glm::vec3> out;
  for (int i = 0; i < count; ++i)
    out.push_back(glm::normalize(glm::vec3(gauss(rng), gauss(rng), gauss(rng))) * distance(rng));
  return out;
}

// Bumps along the normal (a sculpted surface), and a few vertices welded onto a neighbour
// (zero-area triangles, as meshes ship).
TriangleMesh sculpted_sphere(std::mt19937& rng) {
  TriangleMesh m = make_geodesic_sphere(20000);
  std::uniform_real_distribution<float> bump(-0.03f, 0.03f);
  for (size_t v = 0; v < m.positions.size() / 3; ++v) {
    const float scale = 1.f + bump(rng);
    for (int k = 0; k < 3; ++k) m.positions[3 * v + k] *= scale;
  }
  for (size_t t = 0; t < m.triangles.size() / 3; t += 997)
    std::copy_n(&m.positions[3 * size_t{m.triangles[3 * t]}], 3,
                &m.positions[3 * size_t{m.triangles[3 * t + 1]}]);
  return m;
}

}  // namespace

TEST(DrawClusters, DrawOrderHoldsEveryTriangleOnceWithItsWinding) {
  const TriangleMesh m = make_geodesic_sphere(5000);
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  std::vector<std::array<uint32_t, 3>> original, drawn;
  auto rotate_lowest_first = [](std::array<uint32_t, 3> t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  for (size_t i = 0; i < m.triangles.size(); i += 3) {
    original.push_back(
        rotate_lowest_first({m.triangles[i], m.triangles[i + 1], m.triangles[i + 2]}));
    const auto& o = clusters.draw_order();
    drawn.push_back(rotate_lowest_first({o[i], o[i + 1], o[i + 2]}));
  }
  std::sort(original.begin(), original.end());
  std::sort(drawn.begin(), drawn.end());
  EXPECT_EQ(original, drawn);
  size_t listed = 0;
  for (uint32_t c = 0; c < clusters.cluster_count(); ++c)
    listed += clusters.cluster_triangles(c).size();
  EXPECT_EQ(listed, m.triangles.size() / 3);
}

TEST(DrawClusters, ACulledClusterHoldsNoTriangleFacingTheEye) {
  std::mt19937 rng(7);
  const TriangleMesh m = sculpted_sphere(rng);
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  for (const glm::vec3& eye : eyes(rng, 200)) check_culling(clusters, m, eye);
}

TEST(DrawClusters, LeavesOutMostOfWhatFacesAwayOnASphereSeenFromOutside) {
  const TriangleMesh m = make_geodesic_sphere(80000);
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  for (const glm::vec3 eye : {glm::vec3(0, 0, 3), glm::vec3(2, -2, 1), glm::vec3(0, 5, 0)}) {
    const double culled = check_culling(clusters, m, eye);
    // From distance d a unit sphere shows (1 - 1/d) / 2 of its area; the rest faces away.
    const double faces_away = (1.0 + 1.0 / glm::length(eye)) / 2.0;
    EXPECT_GT(culled, 0.75 * faces_away) << "eye " << eye.x << " " << eye.y << " " << eye.z;
  }
}

TEST(DrawClusters, AfterTheSurfaceMovesTheClustersAroundItStayExactWhileRecomputedBitByBit) {
  std::mt19937 rng(11);
  TriangleMesh m = sculpted_sphere(rng);
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  // A rough patch: vertices near one pole thrown about by a third of the radius, so its
  // triangles face every way (the clusters' old cones would cull some that face the eye).
  std::uniform_real_distribution<float> throw_by(-0.3f, 0.3f);
  std::vector<uint32_t> moved;
  for (uint32_t v = 0; v < m.positions.size() / 3; ++v) {
    if (m.positions[3 * size_t{v} + 2] < 0.8f) continue;
    for (int k = 0; k < 3; ++k) m.positions[3 * size_t{v} + k] += throw_by(rng);
    moved.push_back(v);
  }
  ASSERT_GT(moved.size(), 100u);
  clusters.mark_moved(moved);
  const uint32_t stale = clusters.stale_count();
  ASSERT_GT(stale, 2u);
  // Stale clusters are drawn whole: before any refit, and after a partial one (the clusters
  // left over share bitmap words with those refitted), no culled cluster faces the eye.
  for (const glm::vec3& eye : eyes(rng, 50)) check_culling(clusters, m, eye);
  clusters.refit_stale(m.positions, m.triangles, stale / 2);
  EXPECT_EQ(clusters.stale_count(), stale - stale / 2);
  for (const glm::vec3& eye : eyes(rng, 50)) check_culling(clusters, m, eye);
  while (clusters.stale_count() > 0) clusters.refit_stale(m.positions, m.triangles, 3);
  for (const glm::vec3& eye : eyes(rng, 200)) check_culling(clusters, m, eye);
}

TEST(DrawClusters, AStaleClusterIsNeitherCulledNorLeftOutOfView) {
  const TriangleMesh m = make_geodesic_sphere(20000);
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  const glm::vec3 eye(0, 0, 3);
  uint32_t culled = 0;
  while (culled < clusters.cluster_count() && !clusters.faces_away(culled, eye)) ++culled;
  ASSERT_LT(culled, clusters.cluster_count());
  clusters.mark_moved(std::span(m.triangles)
                          .subspan(3 * size_t{clusters.cluster_triangles(culled)[0]},
                                   1));  // a corner of its first triangle
  EXPECT_FALSE(clusters.faces_away(culled, eye));
  const glm::mat4 away = glm::perspective(0.785f, 1.6f, 0.1f, 20.f) *
                         glm::lookAt(eye, glm::vec3(0, 0, 6), glm::vec3(0, 1, 0));
  std::vector<uint32_t> first, count;
  clusters.visible_ranges(away, eye, true, first, count);
  ASSERT_FALSE(first.empty());  // only the stale clusters, although none is in view
  clusters.refit_stale(m.positions, m.triangles);
  EXPECT_TRUE(clusters.faces_away(culled, eye));
  clusters.visible_ranges(away, eye, true, first, count);
  EXPECT_TRUE(first.empty());
}

TEST(DrawClusters, VisibleRangesLeaveOutWhatIsBehindTheViewOrFacingAway) {
  const TriangleMesh m = make_geodesic_sphere(20000);
  DrawClusters clusters;
  clusters.build(m.positions, m.triangles);
  const glm::mat4 projection = glm::perspective(0.785f, 1.6f, 0.1f, 20.f);
  const glm::vec3 eye(0, 0, 3);
  std::vector<uint32_t> first, count;
  auto drawn = [&] {
    size_t indices = 0;
    for (size_t i = 0; i < first.size(); ++i) {
      indices += count[i];
      if (i > 0) {  // adjacent runs are merged
        EXPECT_GT(first[i], first[i - 1] + count[i - 1]);
      }
    }
    return indices / 3;
  };
  const glm::mat4 toward = projection * glm::lookAt(eye, glm::vec3(0), glm::vec3(0, 1, 0));
  clusters.visible_ranges(toward, eye, false, first, count);
  EXPECT_EQ(drawn(), m.triangles.size() / 3);  // all in view, none culled by facing
  ASSERT_EQ(first.size(), 1u);
  clusters.visible_ranges(toward, eye, true, first, count);
  EXPECT_LT(drawn(), m.triangles.size() * 6 / 10 / 3);
  const glm::mat4 away = projection * glm::lookAt(eye, glm::vec3(0, 0, 6), glm::vec3(0, 1, 0));
  clusters.visible_ranges(away, eye, false, first, count);
  EXPECT_EQ(drawn(), 0u);
}
