#include "version_normals.h"

#include <utility>

namespace {

/** out = the 3 floats of each of `items` in `all` (3 per item), in the items' order. */
void gather3(std::span<const uint32_t> items, const std::vector<float>& all,
             std::vector<float>& out) {
  out.resize(3 * items.size());
  for (size_t i = 0; i < items.size(); ++i)
    for (size_t c = 0; c < 3; ++c) out[3 * i + c] = all[3 * size_t{items[i]} + c];
}

}  // namespace

void VersionNormals::set_topology(std::vector<uint32_t> corners, uint32_t vertex_count) {
  corners_ = std::move(corners);
  around_.build(corners_, vertex_count);
  const auto triangle_count = static_cast<uint32_t>(corners_.size() / 3);
  change_.resize(vertex_count, triangle_count);
  ring_.resize(vertex_count, triangle_count);
  face_.assign(corners_.size(), 0.f);
  vertex_.assign(3 * size_t{vertex_count}, 0.f);
}

void VersionNormals::compute(const float* positions, ChangedNormals& out) {
  change_.collect(corners_, around_, out.moved);
  // A corner's normal sums every triangle around it, also those whose corners did not move:
  // their face normals are recomputed here from the same positions the document holds.
  ring_.collect(corners_, around_, change_.vertices);
  compute_face_normals(positions, corners_, ring_.triangles, face_.data());
  compute_vertex_normals(around_, face_.data(), change_.vertices, vertex_.data());
  out.triangles = change_.triangles;
  gather3(out.triangles, face_, out.face_normals);
  out.vertices = change_.vertices;
  gather3(out.vertices, vertex_, out.normals);
}
