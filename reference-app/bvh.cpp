#include "bvh.h"

#include <algorithm>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>

namespace {

constexpr uint32_t kLeafSize = 8;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

glm::vec3 vertex(const std::vector<float>& positions, uint32_t v) {
  return {positions[3 * size_t{v}], positions[3 * size_t{v} + 1], positions[3 * size_t{v} + 2]};
}

// Slab test: the entry distance of the ray into the box, or infinity.
float box_entry(glm::vec3 lo, glm::vec3 hi, glm::vec3 origin, glm::vec3 inverse_direction,
                float best) {
  float t0 = 0.f, t1 = best;
  for (int a = 0; a < 3; ++a) {
    float near = (lo[a] - origin[a]) * inverse_direction[a];
    float far = (hi[a] - origin[a]) * inverse_direction[a];
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return std::numeric_limits<float>::infinity();
  }
  return t0;
}

}  // namespace

void TriangleBvh::build(const std::vector<float>& positions,
                        const std::vector<uint32_t>& triangles) {
  const uint32_t count = static_cast<uint32_t>(triangles.size() / 3);
  nodes_.clear();
  nodes_.reserve(2 * count / kLeafSize + 1);
  parent_.clear();
  order_.resize(count);
  std::vector<glm::vec3> centroids(count);
  for (uint32_t t = 0; t < count; ++t) {
    order_[t] = t;
    centroids[t] = (vertex(positions, triangles[3 * t]) + vertex(positions, triangles[3 * t + 1]) +
                    vertex(positions, triangles[3 * t + 2])) /
                   3.f;
  }
  depth_.clear();
  if (count > 0) build_node(positions, triangles, centroids, 0, count, kNone, 0);
  assign_vertices(triangles, positions.size() / 3);
  index_vertex_leaves(triangles, positions.size() / 3);
  for (Marks* m : {&growing_marks_, &loose_marks_, &tighten_marks_, &listed_marks_})
    m->resize(nodes_.size());
  loose_.clear();
}

uint32_t TriangleBvh::build_node(const std::vector<float>& positions,
                                 const std::vector<uint32_t>& triangles,
                                 std::vector<glm::vec3>& centroids, uint32_t begin, uint32_t end,
                                 uint32_t parent, uint8_t depth) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.emplace_back();
  parent_.push_back(parent);
  depth_.push_back(depth);
  if (end - begin <= kLeafSize) {
    nodes_[index].first = begin;
    nodes_[index].count = end - begin;
    fit_leaf(nodes_[index], positions, triangles);
    return index;
  }
  // Median split of the centroids along their widest axis: balanced, and cheap to build.
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (uint32_t i = begin; i < end; ++i) {
    lo = glm::min(lo, centroids[order_[i]]);
    hi = glm::max(hi, centroids[order_[i]]);
  }
  const glm::vec3 extent = hi - lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const uint32_t middle = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                   [&](uint32_t a, uint32_t b) { return centroids[a][axis] < centroids[b][axis]; });
  const auto below = static_cast<uint8_t>(depth + 1);  // median splits: depth ~ log2(leaves)
  build_node(positions, triangles, centroids, begin, middle, index, below);
  const uint32_t right = build_node(positions, triangles, centroids, middle, end, index, below);
  Node& node = nodes_[index];
  node.first = right;
  node.count = 0;
  node.lo = glm::min(nodes_[index + 1].lo, nodes_[right].lo);
  node.hi = glm::max(nodes_[index + 1].hi, nodes_[right].hi);
  return index;
}

template <typename Take>
void TriangleBvh::each_corner(const std::vector<uint32_t>& triangles, uint32_t n,
                              Take&& take) const {
  const Node& node = nodes_[n];
  for (uint32_t i = node.first; node.count > 0 && i < node.first + node.count; ++i)
    for (int c = 0; c < 3; ++c) take(triangles[3 * size_t{order_[i]} + c]);
}

void TriangleBvh::assign_vertices(const std::vector<uint32_t>& triangles, size_t vertex_count) {
  std::vector<uint8_t> taken(vertex_count, 0);
  owned_.clear();
  owned_begin_.assign(nodes_.size() + 1, 0);
  for (uint32_t n = 0; n < nodes_.size(); ++n) {
    owned_begin_[n] = static_cast<uint32_t>(owned_.size());
    each_corner(triangles, n, [&](uint32_t v) {
      if (taken[v]) return;
      taken[v] = 1;
      owned_.push_back(v);
    });
  }
  owned_begin_[nodes_.size()] = static_cast<uint32_t>(owned_.size());
}

void TriangleBvh::index_vertex_leaves(const std::vector<uint32_t>& triangles, size_t vertex_count) {
  // Two passes over the leaves in node order (counts, then entries); a vertex meets its
  // leaves in increasing order, so comparing with the last one it got removes repeats.
  std::vector<uint32_t> last(vertex_count, kNone);
  vertex_leaves_begin_.assign(vertex_count + 1, 0);
  auto each_new = [&](auto&& take) {
    for (uint32_t n = 0; n < nodes_.size(); ++n)
      each_corner(triangles, n, [&](uint32_t v) {
        if (last[v] == n) return;
        last[v] = n;
        take(v, n);
      });
  };
  each_new([&](uint32_t v, uint32_t) { ++vertex_leaves_begin_[v + 1]; });
  for (size_t v = 0; v < vertex_count; ++v) vertex_leaves_begin_[v + 1] += vertex_leaves_begin_[v];
  vertex_leaves_.resize(vertex_leaves_begin_[vertex_count]);
  std::vector<uint32_t> next(vertex_leaves_begin_.begin(), vertex_leaves_begin_.end() - 1);
  std::fill(last.begin(), last.end(), kNone);
  each_new([&](uint32_t v, uint32_t n) { vertex_leaves_[next[v]++] = n; });
}

void TriangleBvh::fit_leaf(Node& node, const std::vector<float>& positions,
                           const std::vector<uint32_t>& triangles) const {
  node.lo = glm::vec3(std::numeric_limits<float>::max());
  node.hi = glm::vec3(-std::numeric_limits<float>::max());
  for (uint32_t i = node.first; i < node.first + node.count; ++i)
    for (int c = 0; c < 3; ++c) {
      const glm::vec3 p = vertex(positions, triangles[3 * size_t{order_[i]} + c]);
      node.lo = glm::min(node.lo, p);
      node.hi = glm::max(node.hi, p);
    }
}

void TriangleBvh::refit(const std::vector<float>& positions, std::span<const uint32_t> moved) {
  for (uint32_t v : moved) {
    const glm::vec3 p = vertex(positions, v);
    for (uint32_t k = vertex_leaves_begin_[v]; k < vertex_leaves_begin_[v + 1]; ++k) {
      const uint32_t leaf = vertex_leaves_[k];
      Node& node = nodes_[leaf];
      node.lo = glm::min(node.lo, p);
      node.hi = glm::max(node.hi, p);
      if (growing_marks_.mark(leaf)) growing_.push_back(leaf);
    }
  }
  for (uint32_t leaf : growing_) {
    if (loose_marks_.mark(leaf)) loose_.push_back(leaf);
    for (uint32_t child = leaf, n = parent_[leaf]; n != kNone; child = n, n = parent_[n]) {
      Node& node = nodes_[n];
      const glm::vec3 lo = glm::min(node.lo, nodes_[child].lo);
      const glm::vec3 hi = glm::max(node.hi, nodes_[child].hi);
      if (lo == node.lo && hi == node.hi) break;  // holds it: so does every ancestor
      node.lo = lo;
      node.hi = hi;
    }
  }
  growing_marks_.clear(growing_);
  growing_.clear();
}

void TriangleBvh::refit_exactly(const std::vector<float>& positions,
                                const std::vector<uint32_t>& triangles,
                                std::span<const uint32_t> moved) {
  for (uint32_t v : moved)
    for (uint32_t k = vertex_leaves_begin_[v]; k < vertex_leaves_begin_[v + 1]; ++k)
      if (loose_marks_.mark(vertex_leaves_[k])) loose_.push_back(vertex_leaves_[k]);
  tighten(positions, triangles);
}

void TriangleBvh::boxes_around(std::span<const uint32_t> moved, std::vector<uint32_t>& nodes,
                               std::vector<BvhBox>& boxes) {
  nodes.clear();
  boxes.clear();
  for (uint32_t v : moved)
    for (uint32_t k = vertex_leaves_begin_[v]; k < vertex_leaves_begin_[v + 1]; ++k)
      for (uint32_t n = vertex_leaves_[k]; n != kNone && listed_marks_.mark(n); n = parent_[n]) {
        nodes.push_back(n);
        boxes.push_back(box(n));
      }
  listed_marks_.clear(nodes);
}

uint32_t TriangleBvh::loose_boxes(const std::vector<float>& positions,
                                  const std::vector<uint32_t>& triangles) const {
  TriangleBvh exact = *this;
  std::vector<uint32_t> leaves;
  for (uint32_t n = 0; n < nodes_.size(); ++n)
    if (nodes_[n].count > 0) leaves.push_back(n);
  exact.refit_leaves(positions, triangles, leaves);
  uint32_t loose = 0;
  for (uint32_t n = 0; n < nodes_.size(); ++n)
    loose += nodes_[n].lo != exact.nodes_[n].lo || nodes_[n].hi != exact.nodes_[n].hi;
  return loose;
}

void TriangleBvh::set_boxes(std::span<const uint32_t> nodes, std::span<const BvhBox> boxes) {
  for (size_t i = 0; i < nodes.size(); ++i) {
    nodes_[nodes[i]].lo = boxes[i].lo;
    nodes_[nodes[i]].hi = boxes[i].hi;
  }
}

void TriangleBvh::refit_leaves(const std::vector<float>& positions,
                               const std::vector<uint32_t>& triangles,
                               std::span<const uint32_t> leaves) {
  for (uint32_t leaf : leaves)
    if (loose_marks_.mark(leaf)) loose_.push_back(leaf);
  tighten(positions, triangles);
}

void TriangleBvh::tighten(const std::vector<float>& positions,
                          const std::vector<uint32_t>& triangles) {
  for (uint32_t leaf : loose_) {
    fit_leaf(nodes_[leaf], positions, triangles);
    for (uint32_t n = parent_[leaf]; n != kNone && tighten_marks_.mark(n); n = parent_[n]) {
      tightening_.push_back(n);
      if (depth_[n] >= by_depth_.size()) by_depth_.resize(depth_[n] + 1u);
      by_depth_[depth_[n]].push_back(n);
    }
  }
  // Deepest first, so every child is exact before its parent (bucketed by depth: sorting the
  // thousands of nodes a stroke touches would cost as much as refitting them).
  for (size_t d = by_depth_.size(); d-- > 0;) {
    for (uint32_t n : by_depth_[d]) {
      Node& node = nodes_[n];
      node.lo = glm::min(nodes_[n + 1].lo, nodes_[node.first].lo);
      node.hi = glm::max(nodes_[n + 1].hi, nodes_[node.first].hi);
    }
    by_depth_[d].clear();
  }
  tighten_marks_.clear(tightening_);
  tightening_.clear();
  loose_marks_.clear(loose_);
  loose_.clear();
}

RayHit TriangleBvh::raycast(const std::vector<float>& positions,
                            const std::vector<uint32_t>& triangles, glm::vec3 origin,
                            glm::vec3 direction) const {
  RayHit best;
  best.distance = std::numeric_limits<float>::max();
  if (nodes_.empty()) return best;
  const glm::vec3 inverse = 1.f / direction;
  stack_.clear();
  stack_.push_back(0);
  while (!stack_.empty()) {
    const uint32_t index = stack_.back();
    stack_.pop_back();
    const Node& node = nodes_[index];
    if (box_entry(node.lo, node.hi, origin, inverse, best.distance) >= best.distance) continue;
    if (node.count == 0) {
      stack_.push_back(node.first);
      stack_.push_back(index + 1);
      continue;
    }
    for (uint32_t i = node.first; i < node.first + node.count; ++i) {
      // Möller–Trumbore ray/triangle intersection.
      const uint32_t t = order_[i];
      const glm::vec3 a = vertex(positions, triangles[3 * size_t{t}]);
      const glm::vec3 e1 = vertex(positions, triangles[3 * size_t{t} + 1]) - a;
      const glm::vec3 e2 = vertex(positions, triangles[3 * size_t{t} + 2]) - a;
      const glm::vec3 p = glm::cross(direction, e2);
      const float det = glm::dot(e1, p);
      if (std::abs(det) < 1e-12f) continue;
      const float inv_det = 1.f / det;
      const glm::vec3 s = origin - a;
      const float u = glm::dot(s, p) * inv_det;
      if (u < 0.f || u > 1.f) continue;
      const glm::vec3 q = glm::cross(s, e1);
      const float v = glm::dot(direction, q) * inv_det;
      if (v < 0.f || u + v > 1.f) continue;
      const float distance = glm::dot(e2, q) * inv_det;
      if (distance > 0.f && distance < best.distance) {
        best = {true, distance, t, origin + direction * distance};
      }
    }
  }
  return best;
}

std::vector<size_t> TriangleBvh::array_sizes() const {
  std::vector<size_t> sizes{nodes_.size(), depth_.size()};
  for (const std::vector<uint32_t>* a : uint32_arrays(*this)) sizes.push_back(a->size());
  for (const std::vector<uint32_t>& level : by_depth_) sizes.push_back(level.size());
  return sizes;
}

TriangleBvh TriangleBvh::with_room_for(const std::vector<size_t>& sizes) {
  TriangleBvh t;  // resize() writes every element: each page is faulted in here
  size_t i = 0;
  t.nodes_.resize(sizes[i++]);
  t.depth_.resize(sizes[i++]);
  for (std::vector<uint32_t>* a : uint32_arrays(t)) a->resize(sizes[i++]);
  t.by_depth_.resize(sizes.size() - i);
  for (std::vector<uint32_t>& level : t.by_depth_) level.resize(sizes[i++]);
  for (Marks* m : {&t.growing_marks_, &t.loose_marks_, &t.tighten_marks_, &t.listed_marks_})
    m->resize(t.nodes_.size());  // as build() sizes them
  return t;
}
