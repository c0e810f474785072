// The mesh's triangles in clusters for drawing: a cluster whose every triangle faces away from
// the eye, or which lies outside the view, is not sent to GL at all. On a software renderer
// (llvmpipe) most of a frame at 320K faces is vertex and primitive work done before GL's own
// back-face culling, on one thread; skipping the back half of a closed mesh there is the
// largest saving a frame can get. Triangles are ordered along a Morton curve of their
// centroids and cut into runs of kTriangles, so each cluster is a compact patch. A cluster is
// culled when the cone of its normals proves it faces away (no per-triangle work) or, failing
// that, when every one of its triangles' planes has the eye behind it. After the mesh moves,
// the clusters around the moved vertices are drawn whole until recomputed, a bounded number
// per frame: a merged version that moved half the mesh costs no frame more than a dab does,
// and a culled cluster is always wholly back-facing.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <span>
#include <vector>

#include "marks.h"

class DrawClusters {
 public:
  static constexpr uint32_t kTriangles = 512;
  static constexpr uint32_t kRefitsPerFrame = 64;

  /** Orders the triangles and computes every cluster (after the mesh's layout changed). */
  void build(const std::vector<float>& positions, const std::vector<uint32_t>& triangles);

  /** Marks the clusters holding a triangle of any of `moved` as stale: drawn whole until
   *  refit_stale() recomputes them. */
  void mark_moved(std::span<const uint32_t> moved);
  /** Recomputes up to `budget` stale clusters, oldest first. */
  void refit_stale(const std::vector<float>& positions, const std::vector<uint32_t>& triangles,
                   uint32_t budget = kRefitsPerFrame);
  uint32_t stale_count() const { return static_cast<uint32_t>(stale_.size() - stale_next_); }

  /** The triangles' corner indices in cluster order (the index buffer to draw from). */
  const std::vector<uint32_t>& draw_order() const { return order_; }

  /** The index ranges to draw from eye `eye` through `view_projection` (clip = VP * world):
   *  runs of consecutive visible clusters as (first index, index count). Clusters facing away
   *  are left out only when `cull_back_faces`; clusters outside the view always. */
  void visible_ranges(const glm::mat4& view_projection, glm::vec3 eye, bool cull_back_faces,
                      std::vector<uint32_t>& first, std::vector<uint32_t>& count) const;

  /** Whether cluster `c` faces wholly away from `eye` (never while stale; for the tests). */
  bool faces_away(uint32_t c, glm::vec3 eye) const;
  uint32_t cluster_count() const { return static_cast<uint32_t>(clusters_.size()); }
  /** The triangles of cluster `c` (document indices). */
  std::span<const uint32_t> cluster_triangles(uint32_t c) const;

 private:
  struct Cluster {
    glm::vec3 center{0.f};
    float radius = 0.f;
    glm::vec3 axis{0.f};     // mean direction of its normals
    float sin_spread = 2.f;  // sine of the widest normal's angle to `axis`; > 1: never cull
  };
  void fit(uint32_t c, const std::vector<float>& positions, const std::vector<uint32_t>& triangles);

  std::vector<uint32_t> triangle_order_;  // document triangle of each drawn triangle
  std::vector<uint32_t> order_;           // 3 corners per drawn triangle
  std::vector<glm::vec4> planes_;         // per drawn triangle: unit normal, offset along it
  std::vector<Cluster> clusters_;
  // The clusters each vertex's triangles belong to (compressed rows), for mark_moved().
  std::vector<uint32_t> vertex_clusters_begin_, vertex_clusters_;
  Marks stale_marks_;
  std::vector<uint32_t> stale_;  // oldest first, from stale_next_ on
  size_t stale_next_ = 0;
};
