// The built-in mesh: a geodesic sphere (an icosahedron whose faces are split into n x n
// triangles), so the face count can be chosen finely (20 n^2) instead of by powers of 4.
#pragma once

#include <cstdint>
#include <vector>

struct TriangleMesh {
  std::vector<float> positions;     // 3 per vertex
  std::vector<uint32_t> triangles;  // 3 per triangle, counter-clockwise seen from outside
};

/** A unit sphere of about `target_faces` faces (20 n^2 with n = round(sqrt(target / 20))).
 *  Vertices are ordered along a Morton curve so a brush's vertices lie close in memory and
 *  its re-upload is a few contiguous runs. Deterministic: every process builds it bit for bit. */
TriangleMesh make_geodesic_sphere(uint32_t target_faces);
