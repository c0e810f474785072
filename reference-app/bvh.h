// A bounding-volume hierarchy over the mesh's triangles for the brush's hit test and its
// region query. Built once per mesh layout; after a dab only the boxes above the changed
// triangles are refitted (the topology never changes while sculpting, so the tree stays valid,
// only looser where the surface moved far).
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <span>
#include <vector>

struct RayHit {
  bool hit = false;
  float distance = 0.f;
  uint32_t triangle = 0;
  glm::vec3 point{0.f};
};

class TriangleBvh {
 public:
  void build(const std::vector<float>& positions, const std::vector<uint32_t>& triangles);
  /** Refits the boxes of `changed_triangles` and their ancestors. */
  void refit(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
             std::span<const uint32_t> changed_triangles);
  /** The nearest triangle the ray crosses (either side). */
  RayHit raycast(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                 glm::vec3 origin, glm::vec3 direction) const;
  /** Calls visit(triangle) for every triangle whose box meets the sphere. */
  template <typename Visit>
  void for_each_triangle_near(glm::vec3 center, float radius, Visit&& visit) const;

  size_t node_count() const { return nodes_.size(); }

 private:
  struct Node {
    glm::vec3 lo, hi;
    uint32_t first = 0;  // leaf: first index into order_; inner: index of the right child
    uint32_t count = 0;  // leaf: triangles; inner: 0 (the left child is the next node)
  };
  uint32_t build_node(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                      std::vector<glm::vec3>& centroids, uint32_t begin, uint32_t end,
                      uint32_t parent);
  void fit_leaf(Node& node, const std::vector<float>& positions,
                const std::vector<uint32_t>& triangles) const;

  std::vector<Node> nodes_;  // pre-order: children come after their parent
  std::vector<uint32_t> order_, parent_, leaf_of_triangle_;
  std::vector<uint32_t> refit_stamp_, refit_nodes_;  // scratch, reused between refits
  uint32_t refit_epoch_ = 0;
  mutable std::vector<uint32_t> stack_;
};

template <typename Visit>
void TriangleBvh::for_each_triangle_near(glm::vec3 center, float radius, Visit&& visit) const {
  if (nodes_.empty()) return;
  stack_.clear();
  stack_.push_back(0);
  const float r2 = radius * radius;
  while (!stack_.empty()) {
    const Node& node = nodes_[stack_.back()];
    const uint32_t index = stack_.back();
    stack_.pop_back();
    float d2 = 0.f;  // squared distance from the sphere's centre to the box
    for (int a = 0; a < 3; ++a) {
      const float e = center[a] < node.lo[a]   ? node.lo[a] - center[a]
                      : center[a] > node.hi[a] ? center[a] - node.hi[a]
                                               : 0.f;
      d2 += e * e;
    }
    if (d2 > r2) continue;
    if (node.count > 0) {
      for (uint32_t i = node.first; i < node.first + node.count; ++i) visit(order_[i]);
    } else {
      stack_.push_back(node.first);
      stack_.push_back(index + 1);
    }
  }
}
