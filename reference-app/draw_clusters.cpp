#include "draw_clusters.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "morton.h"

namespace {

glm::vec3 corner(const std::vector<float>& positions, uint32_t v) {
  return {positions[3 * size_t{v}], positions[3 * size_t{v} + 1], positions[3 * size_t{v} + 2]};
}

// A cluster whose normals spread to within this cosine of its axis (about 87 degrees) is never
// culled: from some eye outside it, part of it faces that eye.
constexpr float kMinUsefulCosine = 0.05f;
// Float rounding in the normals and in GL's own facing test: cull only with this much margin.
constexpr float kSpreadMargin = 1e-3f;
// The same for one triangle's plane: the eye must be behind it by this share of its distance.
constexpr float kPlaneMargin = 1e-5f;

}  // namespace

void DrawClusters::build(const std::vector<float>& positions,
                         const std::vector<uint32_t>& triangles) {
  const uint32_t triangle_count = static_cast<uint32_t>(triangles.size() / 3);
  const uint32_t vertex_count = static_cast<uint32_t>(positions.size() / 3);
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (uint32_t v = 0; v < vertex_count; ++v) {
    lo = glm::min(lo, corner(positions, v));
    hi = glm::max(hi, corner(positions, v));
  }
  const glm::vec3 extent = hi - lo;
  auto scale = [](float e) { return e > 0.f ? 1024.f / e : 0.f; };
  const glm::vec3 cells(scale(extent.x), scale(extent.y), scale(extent.z));
  std::vector<uint32_t> codes(triangle_count);
  for (uint32_t t = 0; t < triangle_count; ++t) {
    const glm::vec3 c = (corner(positions, triangles[3 * size_t{t}]) +
                         corner(positions, triangles[3 * size_t{t} + 1]) +
                         corner(positions, triangles[3 * size_t{t} + 2])) /
                        3.f;
    codes[t] = morton_code(morton_cell(c.x, lo.x, cells.x), morton_cell(c.y, lo.y, cells.y),
                           morton_cell(c.z, lo.z, cells.z));
  }
  triangle_order_.resize(triangle_count);
  std::iota(triangle_order_.begin(), triangle_order_.end(), 0u);
  std::stable_sort(triangle_order_.begin(), triangle_order_.end(),
                   [&](uint32_t a, uint32_t b) { return codes[a] < codes[b]; });
  order_.resize(triangles.size());
  for (uint32_t i = 0; i < triangle_count; ++i)
    std::copy_n(&triangles[3 * size_t{triangle_order_[i]}], 3, &order_[3 * size_t{i}]);

  planes_.resize(triangle_count);
  clusters_.assign((triangle_count + kTriangles - 1) / kTriangles, Cluster{});
  // Each vertex's clusters, once each: drawn triangles come in cluster order, so a vertex's
  // last recorded cluster tells whether this one is new for it. Counted, then filled.
  std::vector<uint32_t> last(vertex_count, UINT32_MAX);
  vertex_clusters_begin_.assign(size_t{vertex_count} + 1, 0);
  auto for_each_new_pair = [&](auto&& visit) {
    std::fill(last.begin(), last.end(), UINT32_MAX);
    for (uint32_t i = 0; i < order_.size(); ++i) {
      const uint32_t v = order_[i], c = i / (3 * kTriangles);
      if (last[v] == c) continue;
      last[v] = c;
      visit(v, c);
    }
  };
  for_each_new_pair([&](uint32_t v, uint32_t) { ++vertex_clusters_begin_[v + 1]; });
  std::partial_sum(vertex_clusters_begin_.begin(), vertex_clusters_begin_.end(),
                   vertex_clusters_begin_.begin());
  vertex_clusters_.resize(vertex_clusters_begin_.back());
  std::vector<uint32_t> next(vertex_clusters_begin_.begin(), vertex_clusters_begin_.end() - 1);
  for_each_new_pair([&](uint32_t v, uint32_t c) { vertex_clusters_[next[v]++] = c; });

  stale_marks_.resize(clusters_.size());
  stale_.clear();
  stale_next_ = 0;
  for (uint32_t c = 0; c < clusters_.size(); ++c) fit(c, positions, triangles);
}

std::span<const uint32_t> DrawClusters::cluster_triangles(uint32_t c) const {
  const size_t first = size_t{c} * kTriangles;
  return std::span(triangle_order_)
      .subspan(first, std::min<size_t>(kTriangles, triangle_order_.size() - first));
}

// The cluster's triangles' planes, its bounding sphere (its box's) and its cone of unit face
// normals. Zero-area triangles have no facing and cover no pixel: their plane has every eye
// behind it, and they do not widen the cone.
void DrawClusters::fit(uint32_t c, const std::vector<float>& positions,
                       const std::vector<uint32_t>& triangles) {
  glm::vec3 lo(INFINITY), hi(-INFINITY), sum(0.f);
  const size_t first = size_t{c} * kTriangles;
  const std::span<const uint32_t> members = cluster_triangles(c);
  for (size_t i = 0; i < members.size(); ++i) {
    const uint32_t t = members[i];
    const glm::vec3 a = corner(positions, triangles[3 * size_t{t}]);
    const glm::vec3 b = corner(positions, triangles[3 * size_t{t} + 1]);
    const glm::vec3 d = corner(positions, triangles[3 * size_t{t} + 2]);
    lo = glm::min(lo, glm::min(a, glm::min(b, d)));
    hi = glm::max(hi, glm::max(b, glm::max(a, d)));
    glm::vec3 n = glm::cross(b - a, d - a);
    const float length = glm::length(n);
    if (length > 0.f && std::isfinite(length)) {
      n /= length;
      planes_[first + i] = glm::vec4(n, glm::dot(n, a));
      sum += n;
    } else {
      planes_[first + i] = glm::vec4(0.f, 0.f, 0.f, INFINITY);
    }
  }
  Cluster& cluster = clusters_[c];
  cluster.center = (lo + hi) * 0.5f;
  cluster.radius = 0.5f * glm::length(hi - lo);
  cluster.sin_spread = 2.f;
  const float sum_length = glm::length(sum);
  if (!(sum_length > 0.f) || !std::isfinite(sum_length)) return;
  cluster.axis = sum / sum_length;
  float min_cosine = 1.f;
  for (size_t i = 0; i < members.size(); ++i)
    if (std::isfinite(planes_[first + i].w))
      min_cosine = std::min(min_cosine, glm::dot(glm::vec3(planes_[first + i]), cluster.axis));
  if (min_cosine < kMinUsefulCosine) return;
  cluster.sin_spread = std::sqrt(1.f - min_cosine * min_cosine) + kSpreadMargin;
}

void DrawClusters::mark_moved(std::span<const uint32_t> moved) {
  for (uint32_t v : moved)
    for (uint32_t k = vertex_clusters_begin_[v]; k < vertex_clusters_begin_[v + 1]; ++k)
      if (stale_marks_.mark(vertex_clusters_[k])) stale_.push_back(vertex_clusters_[k]);
}

void DrawClusters::refit_stale(const std::vector<float>& positions,
                               const std::vector<uint32_t>& triangles, uint32_t budget) {
  const size_t end = std::min(stale_.size(), stale_next_ + budget);
  for (size_t i = stale_next_; i < end; ++i) {
    fit(stale_[i], positions, triangles);
    stale_marks_.unmark(stale_[i]);  // one by one: the rest of its word may still be stale
  }
  stale_next_ = end;
  if (stale_next_ == stale_.size()) {
    stale_.clear();
    stale_next_ = 0;
  }
}

// Every triangle faces away from the eye when, for every point p of the cluster's sphere and
// every normal n of its cone, n . (p - eye) > 0: the angle between the axis and p - eye must
// stay under 90 degrees minus the spread, for the sphere's nearest and farthest points alike.
// That proof is cheap but loose near the silhouette; there the triangles' planes decide, each
// with the eye behind it by a margin for rounding (the first one facing the eye ends the scan).
bool DrawClusters::faces_away(uint32_t c, glm::vec3 eye) const {
  if (stale_marks_.marked(c)) return false;
  const Cluster& cluster = clusters_[c];
  const glm::vec3 d = cluster.center - eye;
  const float distance = glm::length(d);
  const float along_axis = glm::dot(cluster.axis, d);
  if (cluster.sin_spread <= 1.f &&
      along_axis > cluster.sin_spread * distance + cluster.radius * (1.f + cluster.sin_spread))
    return true;
  if (!(along_axis > -cluster.radius)) return false;  // it mostly faces the eye: no scan
  const float margin = kPlaneMargin * (distance + cluster.radius);
  const size_t first = size_t{c} * kTriangles;
  const size_t size = cluster_triangles(c).size();
  for (size_t i = first; i < first + size; ++i)
    if (!(planes_[i].w - glm::dot(glm::vec3(planes_[i]), eye) > margin)) return false;
  return true;
}

void DrawClusters::visible_ranges(const glm::mat4& view_projection, glm::vec3 eye,
                                  bool cull_back_faces, std::vector<uint32_t>& first,
                                  std::vector<uint32_t>& count) const {
  first.clear();
  count.clear();
  // The view's six planes (left, right, bottom, top, near, far), inside where positive.
  glm::vec4 planes[6];
  for (int axis = 0; axis < 3; ++axis) {
    const glm::vec4 row(view_projection[0][axis], view_projection[1][axis],
                        view_projection[2][axis], view_projection[3][axis]);
    const glm::vec4 w(view_projection[0][3], view_projection[1][3], view_projection[2][3],
                      view_projection[3][3]);
    planes[2 * axis] = w + row;
    planes[2 * axis + 1] = w - row;
  }
  auto outside_view = [&](uint32_t c) {
    if (stale_marks_.marked(c)) return false;
    const Cluster& cluster = clusters_[c];
    for (const glm::vec4& p : planes)
      if (glm::dot(glm::vec3(p), cluster.center) + p.w <
          -cluster.radius * glm::length(glm::vec3(p)))
        return true;
    return false;
  };
  const uint32_t index_count = static_cast<uint32_t>(order_.size());
  for (uint32_t c = 0; c < clusters_.size(); ++c) {
    if (outside_view(c) || (cull_back_faces && faces_away(c, eye))) continue;
    const uint32_t begin = c * 3 * kTriangles;
    const uint32_t size = std::min(3 * kTriangles, index_count - begin);
    if (!first.empty() && first.back() + count.back() == begin)
      count.back() += size;
    else {
      first.push_back(begin);
      count.push_back(size);
    }
  }
}
