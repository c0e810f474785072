#include "surface_normals.h"

#include <cmath>

void VertexTriangles::build(std::span<const uint32_t> corners, uint32_t vertex_count) {
  offsets.assign(size_t{vertex_count} + 1, 0);  // a counting sort by vertex
  for (uint32_t v : corners) ++offsets[v + 1];
  for (uint32_t v = 0; v < vertex_count; ++v) offsets[v + 1] += offsets[v];
  triangles.resize(corners.size());
  std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
  for (size_t i = 0; i < corners.size(); ++i)
    triangles[fill[corners[i]]++] = static_cast<uint32_t>(i / 3);
}

void compute_face_normals(const float* positions, std::span<const uint32_t> corners,
                          std::span<const uint32_t> faces, float* face_normals) {
  for (uint32_t t : faces) {
    const uint32_t* tri = &corners[3 * size_t{t}];
    const float* a = &positions[3 * size_t{tri[0]}];
    const float* b = &positions[3 * size_t{tri[1]}];
    const float* c = &positions[3 * size_t{tri[2]}];
    const float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float* n = &face_normals[3 * size_t{t}];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  }
}

void compute_vertex_normals(const VertexTriangles& around, const float* face_normals,
                            std::span<const uint32_t> vertices, float* normals) {
  for (uint32_t v : vertices) {
    float n[3] = {0.f, 0.f, 0.f};
    for (uint32_t k = around.offsets[v]; k < around.offsets[v + 1]; ++k) {
      const float* f = &face_normals[3 * size_t{around.triangles[k]}];
      n[0] += f[0];
      n[1] += f[1];
      n[2] += f[2];
    }
    const float length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const float scale = length > 0.f ? 1.f / length : 0.f;
    for (int c = 0; c < 3; ++c) normals[3 * size_t{v} + c] = n[c] * scale;
  }
}

void NormalsChange::resize(uint32_t vertex_count, uint32_t triangle_count) {
  triangle_marks_.resize(triangle_count);
  vertex_marks_.resize(vertex_count);
}

void NormalsChange::collect(std::span<const uint32_t> corners, const VertexTriangles& around,
                            std::span<const uint32_t> moved) {
  triangles.clear();
  for (uint32_t v : moved)
    for (uint32_t k = around.offsets[v]; k < around.offsets[v + 1]; ++k)
      if (triangle_marks_.mark(around.triangles[k])) triangles.push_back(around.triangles[k]);
  triangle_marks_.clear(triangles);
  collect_corners(corners);
}

void NormalsChange::collect_corners(std::span<const uint32_t> corners) {
  vertices.clear();
  for (uint32_t t : triangles)
    for (int c = 0; c < 3; ++c) {
      const uint32_t corner = corners[3 * size_t{t} + c];
      if (vertex_marks_.mark(corner)) vertices.push_back(corner);
    }
  vertex_marks_.clear(vertices);
}
