// A bounding-volume hierarchy over the mesh's triangles for the brush's hit test and its
// region query. Built once per mesh layout (the topology never changes while sculpting, so
// the tree stays valid): after a dab the leaves its region query met are refitted exactly with
// their ancestors; a grab's move, which has no query, only grows boxes, tightened at the
// stroke's end. Each vertex belongs to one leaf holding a triangle
// of it, so the region query visits each vertex once, not once per triangle around it.
#pragma once

#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "marks.h"

/** A node's box, as another copy of the same tree hands it over. */
struct BvhBox {
  glm::vec3 lo, hi;
};

struct RayHit {
  bool hit = false;
  float distance = 0.f;
  uint32_t triangle = 0;
  glm::vec3 point{0.f};
};

class TriangleBvh {
 public:
  void build(const std::vector<float>& positions, const std::vector<uint32_t>& triangles);
  /** Grows the leaves holding a triangle of each `moved` vertex to hold it where it is now,
   *  and their ancestors as far as they must (cheap enough for every move of a grab: most
   *  stop at the leaf). A box may then be too large, never too small, until tighten(). */
  void refit(const std::vector<float>& positions, std::span<const uint32_t> moved);
  /** Refits exactly every box refit() grew since the last call, and their ancestors (at the
   *  end of a stroke). */
  void tighten(const std::vector<float>& positions, const std::vector<uint32_t>& triangles);
  /** Refits exactly the leaves holding a triangle of each `moved` vertex and their ancestors,
   *  with whatever refit() grew (after an undo or a merged version). */
  void refit_exactly(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                     std::span<const uint32_t> moved);
  /** Refits exactly the given leaves and their ancestors, with whatever refit() grew (after
   *  a dab, the leaves its region query visited: every triangle around what moved). */
  void refit_leaves(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                    std::span<const uint32_t> leaves);
  /** Lists the leaves holding a triangle of each `moved` vertex and their ancestors, each
   *  once, with their boxes (this tree must be tight): all that a copy of this tree, tight
   *  over positions that differ from these at `moved` only, lacks to equal it. */
  void boxes_around(std::span<const uint32_t> moved, std::vector<uint32_t>& nodes,
                    std::vector<BvhBox>& boxes);
  /** Takes boxes_around()'s result from a copy of this tree (the same build). */
  void set_boxes(std::span<const uint32_t> nodes, std::span<const BvhBox> boxes);
  /** Boxes that differ from an exact refit of every leaf over these positions (a check: 0
   *  whenever no stroke is under way). */
  uint32_t loose_boxes(const std::vector<float>& positions,
                       const std::vector<uint32_t>& triangles) const;
  /** Node n's box. */
  BvhBox box(uint32_t n) const { return {nodes_[n].lo, nodes_[n].hi}; }
  /** The nearest triangle the ray crosses (either side). */
  RayHit raycast(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                 glm::vec3 origin, glm::vec3 direction) const;
  /** Calls visit(leaf) for every leaf whose box meets the sphere: every triangle with a
   *  corner inside the sphere is held by one of them. */
  template <typename Visit>
  void for_each_leaf_near(glm::vec3 center, float radius, Visit&& visit) const;
  /** The vertices a leaf owns (each vertex is owned by one leaf) and the triangles it holds. */
  std::span<const uint32_t> owned_vertices(uint32_t leaf) const {
    return std::span(owned_).subspan(owned_begin_[leaf],
                                     owned_begin_[leaf + 1] - owned_begin_[leaf]);
  }
  std::span<const uint32_t> leaf_triangles(uint32_t leaf) const {
    return std::span(order_).subspan(nodes_[leaf].first, nodes_[leaf].count);
  }

  size_t node_count() const { return nodes_.size(); }

  /** The sizes of the tree's large arrays. A tree made with_room_for(them), on any thread, has
   *  each of those arrays allocated and its pages touched, so copy-assigning this tree to it
   *  allocates nothing: copying into new pages is mostly the kernel faulting them in. */
  std::vector<size_t> array_sizes() const;
  static TriangleBvh with_room_for(const std::vector<size_t>& sizes);

 private:
  struct Node {
    glm::vec3 lo, hi;
    uint32_t first = 0;  // leaf: first index into order_; inner: index of the right child
    uint32_t count = 0;  // leaf: triangles; inner: 0 (the left child is the next node)
  };
  uint32_t build_node(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                      std::vector<glm::vec3>& centroids, uint32_t begin, uint32_t end,
                      uint32_t parent, uint8_t depth);
  /** Calls take(vertex) for every corner of node n's triangles, in order (none: inner node). */
  template <typename Take>
  void each_corner(const std::vector<uint32_t>& triangles, uint32_t n, Take&& take) const;
  /** Gives each vertex to the first leaf (in node order) holding a triangle of it. */
  void assign_vertices(const std::vector<uint32_t>& triangles, size_t vertex_count);
  /** Lists, for each vertex, the leaves holding a triangle of it (what refit grows). */
  void index_vertex_leaves(const std::vector<uint32_t>& triangles, size_t vertex_count);
  void fit_leaf(Node& node, const std::vector<float>& positions,
                const std::vector<uint32_t>& triangles) const;

  std::vector<Node> nodes_;  // pre-order: children come after their parent
  std::vector<uint32_t> order_, parent_;
  std::vector<uint8_t> depth_;  // of each node: refits go deepest first
  // The vertices node n owns: owned_[owned_begin_[n] .. owned_begin_[n + 1]) (leaves only).
  std::vector<uint32_t> owned_, owned_begin_;
  // The leaves holding a triangle of vertex v: vertex_leaves_[vertex_leaves_begin_[v] ..
  // vertex_leaves_begin_[v + 1]), one to three on a typical mesh. A dab moves thousands of
  // vertices and touches twice as many triangles: growing boxes by vertex reads each moved
  // position once, where growing by triangle read every corner of every triangle around.
  std::vector<uint32_t> vertex_leaves_, vertex_leaves_begin_;
  // Scratch reused between refits: the leaves one refit grows, the leaves grown since the
  // last tighten (they and their ancestors may be loose), and tighten's nodes by depth.
  Marks growing_marks_, loose_marks_, tighten_marks_, listed_marks_;
  std::vector<uint32_t> growing_, loose_, tightening_;
  std::vector<std::vector<uint32_t>> by_depth_;
  mutable std::vector<uint32_t> stack_;

  // The uint32_t arrays a copy carries, in one order for array_sizes and with_room_for.
  template <typename Tree>
  static auto uint32_arrays(Tree& t) {
    return std::array{&t.order_,       &t.parent_,        &t.owned_,
                      &t.owned_begin_, &t.vertex_leaves_, &t.vertex_leaves_begin_,
                      &t.growing_,     &t.loose_,         &t.tightening_};
  }
};

template <typename Visit>
void TriangleBvh::for_each_leaf_near(glm::vec3 center, float radius, Visit&& visit) const {
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
      visit(index);
    } else {
      stack_.push_back(node.first);
      stack_.push_back(index + 1);
    }
  }
}
