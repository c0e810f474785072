#include "mesh_document.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "abi_error.h"
#include "icosphere.h"

namespace {

struct MeshDeleter {
  void operator()(csc_mesh* mesh) const { csc_mesh_destroy(mesh); }
};
using MeshHandle = std::unique_ptr<csc_mesh, MeshDeleter>;

csc_mesh* make_csc_mesh(std::span<const float> positions, std::span<const uint32_t> triangles,
                        const std::vector<MeshChannel>& channels, std::string& error) {
  std::vector<csc_channel_desc> descs;
  std::vector<const float*> values;
  for (const MeshChannel& channel : channels) {
    descs.push_back({channel.name.c_str(), channel.width, channel.linearisation, channel.min_value,
                     channel.max_value});
    values.push_back(channel.values.data());
  }
  csc_mesh_desc desc = CSC_MESH_DESC_INIT;
  desc.vertex_count = static_cast<uint32_t>(positions.size() / 3);
  desc.positions = positions.data();
  desc.triangle_count = static_cast<uint32_t>(triangles.size() / 3);
  desc.triangles = triangles.data();
  desc.channel_count = static_cast<uint32_t>(channels.size());
  desc.channels = descs.data();
  desc.channel_values = values.data();
  csc_mesh* mesh = nullptr;
  if (csc_status s = csc_mesh_create(&mesh, &desc); s != CSC_OK) {
    error = abi_error("cannot make a mesh of the edited arrays", s);
    return nullptr;
  }
  return mesh;
}

}  // namespace

bool MeshDocument::load(const std::string& path, std::string& error) {
  csc_mesh* raw = nullptr;
  if (csc_status s = csc_mesh_read(&raw, path.c_str()); s != CSC_OK) {
    error = abi_error(("cannot open " + path).c_str(), s);
    return false;
  }
  MeshHandle mesh(raw);
  if (csc_status s = csc_mesh_add_material_channels(mesh.get()); s != CSC_OK) {
    error = abi_error("cannot add the material channels", s);
    return false;
  }
  return adopt(mesh.get(), path, error);
}

void MeshDocument::make_sphere(uint32_t target_faces) {
  TriangleMesh sphere = make_geodesic_sphere(target_faces);
  csc_mesh_desc desc = CSC_MESH_DESC_INIT;
  desc.vertex_count = static_cast<uint32_t>(sphere.positions.size() / 3);
  desc.positions = sphere.positions.data();
  desc.triangle_count = static_cast<uint32_t>(sphere.triangles.size() / 3);
  desc.triangles = sphere.triangles.data();
  csc_mesh* raw = nullptr;
  std::string error;
  // The sphere is made by this program; failing here is a bug, not an artist's problem.
  if (csc_mesh_create(&raw, &desc) != CSC_OK || csc_mesh_add_material_channels(raw) != CSC_OK ||
      !adopt(raw, "built-in sphere", error)) {
    csc_mesh_destroy(raw);
    std::fprintf(stderr, "csculpt-app: cannot build the sphere: %s\n", csc_last_error());
    std::abort();
  }
  csc_mesh_destroy(raw);
}

bool MeshDocument::adopt(const csc_mesh* mesh, const std::string& new_label, std::string& error) {
  const uint32_t vertex_count = csc_mesh_vertex_count(mesh);
  const uint32_t triangle_count = csc_mesh_triangle_count(mesh);
  std::vector<MeshChannel> new_channels(csc_mesh_channel_count(mesh));
  for (uint32_t c = 0; c < new_channels.size(); ++c) {
    csc_channel_view view = CSC_CHANNEL_VIEW_INIT;
    if (csc_status s = csc_mesh_channel(mesh, c, &view); s != CSC_OK) {
      error = abi_error("cannot read a channel", s);
      return false;
    }
    MeshChannel& channel = new_channels[c];
    channel.name = view.desc.name;
    channel.width = view.desc.width;
    channel.linearisation = view.desc.linearisation;
    channel.min_value = view.desc.min_value;
    channel.max_value = view.desc.max_value;
    channel.values.assign(view.values, view.values + size_t{vertex_count} * view.desc.width);
  }
  const float* p = csc_mesh_positions(mesh);
  const uint32_t* t = csc_mesh_triangles(mesh);
  positions.assign(p, p + size_t{vertex_count} * 3);
  triangles.assign(t, t + size_t{triangle_count} * 3);
  channels = std::move(new_channels);
  label = new_label;
  finish_layout();
  return true;
}

void MeshDocument::finish_layout() {
  find_material_channels();
  build_topology();
  recompute_all_normals();
  channel_pointers_.clear();
  for (MeshChannel& channel : channels) channel_pointers_.push_back(channel.values.data());
}

void MeshDocument::find_material_channels() {
  albedo = metallic = roughness = -1;
  for (size_t c = 0; c < channels.size(); ++c) {
    const int index = static_cast<int>(c);
    if (channels[c].name == "albedo" && channels[c].width == 3) albedo = index;
    if (channels[c].name == "metallic" && channels[c].width == 1) metallic = index;
    if (channels[c].name == "roughness" && channels[c].width == 1) roughness = index;
  }
}

csc_mesh* MeshContent::to_csc_mesh(std::string& error) const {
  return make_csc_mesh(positions, triangles, channels, error);
}

csc_mesh* MeshDocument::to_csc_mesh(std::string& error) const {
  return make_csc_mesh(positions, triangles, channels, error);
}

bool MeshDocument::save(const std::string& path, std::string& error) const {
  MeshHandle mesh(to_csc_mesh(error));
  if (!mesh) return false;
  if (csc_status s = csc_mesh_write(mesh.get(), path.c_str()); s != CSC_OK) {
    error = abi_error(("cannot save " + path).c_str(), s);
    return false;
  }
  return true;
}

csc_vertex_arrays MeshDocument::vertex_arrays() {
  csc_vertex_arrays arrays = CSC_VERTEX_ARRAYS_INIT;
  arrays.vertex_count = vertex_count();
  arrays.positions = positions.data();
  arrays.channel_count = static_cast<uint32_t>(channel_pointers_.size());
  arrays.channels = channel_pointers_.data();
  return arrays;
}

uint32_t MeshDocument::values_per_vertex() const {
  uint32_t count = 3;
  for (const MeshChannel& channel : channels) count += channel.width;
  return count;
}

void MeshDocument::copy_vertex_values(uint32_t vertex, float* out) const {
  out = std::copy_n(&positions[3 * size_t{vertex}], 3, out);
  for (const MeshChannel& channel : channels)
    out = std::copy_n(&channel.values[size_t{vertex} * channel.width], channel.width, out);
}

void MeshDocument::set_vertex_values(uint32_t vertex, const float* in) {
  std::copy_n(in, 3, &positions[3 * size_t{vertex}]);
  in += 3;
  for (MeshChannel& channel : channels) {
    std::copy_n(in, channel.width, &channel.values[size_t{vertex} * channel.width]);
    in += channel.width;
  }
}

void MeshDocument::build_topology() {
  const uint32_t vertex_count_ = vertex_count();
  around.build(triangles, vertex_count_);
  // Neighbours: the other corners of those triangles, sorted and unique.
  neighbour_offsets.assign(vertex_count_ + 1, 0);
  neighbours.clear();
  neighbours.reserve(triangles.size() * 2);
  std::vector<uint32_t> ring;
  for (uint32_t v = 0; v < vertex_count_; ++v) {
    ring.clear();
    for (uint32_t k = around.offsets[v]; k < around.offsets[v + 1]; ++k) {
      const uint32_t* tri = &triangles[3 * size_t{around.triangles[k]}];
      for (int c = 0; c < 3; ++c)
        if (tri[c] != v) ring.push_back(tri[c]);
    }
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    neighbours.insert(neighbours.end(), ring.begin(), ring.end());
    neighbour_offsets[v + 1] = static_cast<uint32_t>(neighbours.size());
  }
}

void MeshDocument::recompute_face_normals(std::span<const uint32_t> faces) {
  compute_face_normals(positions.data(), triangles, faces, face_normals.data());
}

void MeshDocument::recompute_normals(std::span<const uint32_t> vertices) {
  compute_vertex_normals(around, face_normals.data(), vertices, normals.data());
}

void MeshDocument::set_normals(std::span<const uint32_t> faces, std::span<const float> face_values,
                               std::span<const uint32_t> vertices,
                               std::span<const float> vertex_values) {
  for (size_t i = 0; i < faces.size(); ++i)
    std::copy_n(&face_values[3 * i], 3, &face_normals[3 * size_t{faces[i]}]);
  for (size_t i = 0; i < vertices.size(); ++i)
    std::copy_n(&vertex_values[3 * i], 3, &normals[3 * size_t{vertices[i]}]);
}

uint32_t MeshDocument::stale_normals() const {
  MeshDocument fresh;
  fresh.positions = positions;
  fresh.triangles = triangles;
  fresh.around = around;
  fresh.recompute_all_normals();
  auto differing = [](const std::vector<float>& a, const std::vector<float>& b) {
    uint32_t count = 0;
    for (size_t i = 0; i < a.size(); i += 3)
      count += std::memcmp(&a[i], &b[i], 3 * sizeof(float)) != 0;
    return count;
  };
  return differing(fresh.normals, normals) + differing(fresh.face_normals, face_normals);
}

void MeshDocument::recompute_all_normals() {
  face_normals.assign(triangles.size(), 0.f);
  std::vector<uint32_t> all(std::max(vertex_count(), triangle_count()));
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  recompute_face_normals(std::span(all).first(triangle_count()));
  normals.assign(positions.size(), 0.f);
  recompute_normals(std::span(all).first(vertex_count()));
}
