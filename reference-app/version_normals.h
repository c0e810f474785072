// The normals a session version brings, computed on the session worker: a landing version
// then costs the UI thread copies and the BVH's refit, not the geometry of the tens of
// thousands of triangles around what moved (10-35 ms of one frame on a loaded machine).
// surface_normals.h's functions over the same positions give the UI's bits exactly.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "surface_normals.h"

/** What moved vertices change of the normals, ready to be copied into the document. */
struct ChangedNormals {
  std::vector<uint32_t> moved;      // vertices whose positions changed
  std::vector<uint32_t> triangles;  // around them, with their face normals (3 each)
  std::vector<float> face_normals;
  std::vector<uint32_t> vertices;  // those triangles' corners, with their unit normals (3 each)
  std::vector<float> normals;
};

class VersionNormals {
 public:
  /** The session's triangles (3 corners each); fixed for the session. */
  void set_topology(std::vector<uint32_t> corners, uint32_t vertex_count);
  /** Fills `out` for `out.moved` from `positions` (every vertex's, as the document will hold
   *  them once it has taken the version). */
  void compute(const float* positions, ChangedNormals& out);
  const std::vector<uint32_t>& corners() const { return corners_; }

 private:
  std::vector<uint32_t> corners_;
  VertexTriangles around_;
  NormalsChange change_;       // the triangles around what moved, and their corners
  NormalsChange ring_;         // the triangles around those corners: their normals' inputs
  std::vector<float> face_;    // per triangle, valid for ring_'s triangles only
  std::vector<float> vertex_;  // per vertex, valid for change_'s vertices only
};
