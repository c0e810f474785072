// The C ABI of meshes (csc_mesh): built from a host's arrays or a file, material channels, views.
#include <cmath>
#include <cstring>
#include <string>

#include "capi_internal.h"
#include "csculpt/io.h"

using namespace csculpt::capi;
using csculpt::InvalidInput;

extern "C" {

CSC_API csc_status csc_mesh_create(csc_mesh** out, const csc_mesh_desc* desc_in) {
  return guarded("csc_mesh_create", [&] {
    require_pointer(out, "out");
    const csc_mesh_desc defaults = CSC_MESH_DESC_INIT;
    const csc_mesh_desc description = read_in(desc_in, defaults, "desc");
    const csc_mesh_desc* desc = &description;
    if (desc->vertex_count > 0 && desc->positions == nullptr)
      bad_argument("desc->positions is NULL");
    if (desc->triangle_count > 0 && desc->triangles == nullptr)
      bad_argument("desc->triangles is NULL");
    if (desc->channel_count > 0 && desc->channels == nullptr)
      bad_argument("desc->channels is NULL");
    if (desc->channel_count > 256)
      bad_argument("desc->channel_count is " + std::to_string(desc->channel_count) +
                   " (at most 256)");
    auto h = std::make_unique<csc_mesh>();
    csculpt::Mesh& m = h->mesh;
    m.positions.resize(desc->vertex_count);
    if (desc->vertex_count)
      std::memcpy(static_cast<void*>(m.positions.data()), desc->positions,
                  std::size_t{desc->vertex_count} * 12);
    m.triangles.resize(desc->triangle_count);
    if (desc->triangle_count)
      std::memcpy(static_cast<void*>(m.triangles.data()), desc->triangles,
                  std::size_t{desc->triangle_count} * 12);
    for (std::uint32_t c = 0; c < desc->channel_count; ++c) {
      const csc_channel_desc& cd = desc->channels[c];
      const std::string what = "channel " + std::to_string(c);
      if (cd.name == nullptr)
        bad_argument("desc->channels[" + std::to_string(c) + "].name is NULL");
      const std::size_t len = strnlen(cd.name, 256);
      if (len == 0 || len > 255) throw InvalidInput(what + ": name must be 1 to 255 bytes");
      if (cd.width < 1 || cd.width > 4)
        throw InvalidInput(what + " '" + cd.name + "': width " + std::to_string(cd.width) +
                           " (1 to 4 allowed)");
      if (std::isnan(cd.min_value) || std::isnan(cd.max_value) || cd.min_value > cd.max_value)
        throw InvalidInput(what + " '" + cd.name + "': min_value must be <= max_value");
      csculpt::ChannelDesc d{std::string(cd.name, len), cd.width,
                             to_linearisation(cd.linearisation), cd.min_value, cd.max_value};
      if (m.find_channel(d.name) >= 0)
        throw InvalidInput(what + ": the name '" + d.name + "' is used twice");
      csculpt::Channel channel{std::move(d), {}};
      const std::size_t n = std::size_t{desc->vertex_count} * cd.width;
      channel.values.assign(n, 0.f);
      if (desc->channel_values != nullptr && desc->channel_values[c] != nullptr && n)
        std::memcpy(channel.values.data(), desc->channel_values[c], n * sizeof(float));
      m.channels.push_back(std::move(channel));
    }
    csculpt::validate(m, "mesh");
    *out = h.release();
  });
}

CSC_API csc_status csc_mesh_add_material_channels(csc_mesh* mesh) {
  return guarded("csc_mesh_add_material_channels", [&] {
    csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    // Check every existing channel first, so a conflict changes nothing.
    for (const csculpt::ChannelDesc& d : csculpt::material_channels()) {
      const int i = m.find_channel(d.name);
      if (i >= 0 && m.channels[static_cast<std::size_t>(i)].desc.width != d.width)
        throw InvalidInput("the mesh has a channel '" + d.name + "' of width " +
                           std::to_string(m.channels[static_cast<std::size_t>(i)].desc.width) +
                           " (the material channel has width " + std::to_string(d.width) + ")");
    }
    csculpt::Mesh copy = m;
    for (const csculpt::ChannelDesc& d : csculpt::material_channels())
      copy.add_channel(d, csculpt::default_material_fill(d));
    m = std::move(copy);
  });
}

CSC_API csc_status csc_mesh_read(csc_mesh** out, const char* path) {
  return guarded("csc_mesh_read", [&] {
    require_pointer(out, "out");
    require_pointer(path, "path");
    auto h = std::make_unique<csc_mesh>();
    h->mesh = csculpt::read_mesh(path);
    *out = h.release();
  });
}

CSC_API csc_status csc_mesh_write(const csc_mesh* mesh, const char* path) {
  return guarded("csc_mesh_write", [&] {
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    require_pointer(path, "path");
    csculpt::write_mesh(m, path);
  });
}

CSC_API csc_status csc_mesh_clone(csc_mesh** out, const csc_mesh* mesh) {
  return guarded("csc_mesh_clone", [&] {
    require_pointer(out, "out");
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    auto h = std::make_unique<csc_mesh>();
    h->mesh = m;
    *out = h.release();
  });
}

CSC_API void csc_mesh_destroy(csc_mesh* mesh) {
  destroy(mesh, Tag::mesh);
}

CSC_API uint32_t csc_mesh_vertex_count(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? static_cast<uint32_t>(mesh->mesh.vertex_count()) : 0;
}
CSC_API uint32_t csc_mesh_triangle_count(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? static_cast<uint32_t>(mesh->mesh.face_count()) : 0;
}
CSC_API uint32_t csc_mesh_channel_count(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? static_cast<uint32_t>(mesh->mesh.channels.size()) : 0;
}
CSC_API const float* csc_mesh_positions(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? floats(mesh->mesh.positions).data() : nullptr;
}
CSC_API const uint32_t* csc_mesh_triangles(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? mesh->mesh.triangles.data()->data() : nullptr;
}

CSC_API csc_status csc_mesh_channel(const csc_mesh* mesh, uint32_t index, csc_channel_view* out) {
  return guarded("csc_mesh_channel", [&] {
    const csculpt::Mesh& m = handle(mesh, Tag::mesh, "mesh").mesh;
    if (index >= m.channels.size())
      bad_argument("channel index " + std::to_string(index) + " out of range (" +
                   std::to_string(m.channels.size()) + " channels)");
    const csculpt::Channel& c = m.channels[index];
    csc_channel_view v = CSC_CHANNEL_VIEW_INIT;
    v.desc = {c.desc.name.c_str(), c.desc.width, from_linearisation(c.desc.linearisation),
              c.desc.min_value, c.desc.max_value};
    v.values = c.values.data();
    write_out(out, v, "out");
  });
}

CSC_API int32_t csc_mesh_find_channel(const csc_mesh* mesh, const char* name) {
  if (!is(mesh, Tag::mesh) || name == nullptr) return -1;
  return mesh->mesh.find_channel(name);
}

CSC_API float csc_mesh_bbox_diagonal(const csc_mesh* mesh) {
  return is(mesh, Tag::mesh) ? csculpt::bbox_diagonal(mesh->mesh.positions) : 0.f;
}

}  // extern "C"
