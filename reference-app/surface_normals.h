// Face and vertex normals of a triangle mesh, and what moving some vertices changes of them
// (after a dab, an undo or a merged version). For the same positions they give the same bits
// whatever moved them, so an undone stroke redraws exactly as before it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "marks.h"

/** The triangles around each vertex, in increasing triangle order (compressed rows). */
struct VertexTriangles {
  std::vector<uint32_t> offsets, triangles;
  /** From the triangles' corner indices (3 per triangle). */
  void build(std::span<const uint32_t> corners, uint32_t vertex_count);
};

/** Recomputes the face normals of `faces` (unnormalised: twice the area) from the positions. */
void compute_face_normals(const float* positions, std::span<const uint32_t> corners,
                          std::span<const uint32_t> faces, float* face_normals);
/** Recomputes the unit normals of `vertices`: the sum of the face normals around each
 *  (area-weighted), in the fixed order of `around`, so equal positions give equal bits. */
void compute_vertex_normals(const VertexTriangles& around, const float* face_normals,
                            std::span<const uint32_t> vertices, float* normals);

/** What moving some vertices changes: the triangles around them (their face normals) and
 *  those triangles' corners (their vertex normals), each listed once. */
class NormalsChange {
 public:
  void resize(uint32_t vertex_count, uint32_t triangle_count);
  void collect(std::span<const uint32_t> corners, const VertexTriangles& around,
               std::span<const uint32_t> moved);
  /** For a caller that listed the triangles itself (each once, a superset of those around
   *  what moved is fine: recomputing an unchanged normal gives the same bits): their corners. */
  void collect_corners(std::span<const uint32_t> corners);
  std::vector<uint32_t> triangles, vertices;

 private:
  Marks triangle_marks_, vertex_marks_;
};
