#include "csculpt/openmesh_interop.h"

#include <cstdint>
#include <string>
#include <unordered_set>
#include <vector>

#include "csculpt/error.h"
#include "io_detail.h"

namespace csculpt {
namespace {

using io_detail::cat;

template <std::uint32_t W>
struct PropertyType;
template <>
struct PropertyType<1> {
  using type = float;
  static constexpr const char* name = "float";
};
template <>
struct PropertyType<2> {
  using type = OpenMesh::Vec2f;
  static constexpr const char* name = "Vec2f";
};
template <>
struct PropertyType<3> {
  using type = OpenMesh::Vec3f;
  static constexpr const char* name = "Vec3f";
};
template <>
struct PropertyType<4> {
  using type = OpenMesh::Vec4f;
  static constexpr const char* name = "Vec4f";
};

template <std::uint32_t W>
void export_channel(OpenMeshTriMesh& om, const Channel& channel) {
  using T = typename PropertyType<W>::type;
  OpenMesh::VPropHandleT<T> handle;
  om.add_property(handle, channel.desc.name);
  om.property(handle).set_persistent(true);
  for (std::size_t v = 0; v < om.n_vertices(); ++v) {
    const float* src = channel.values.data() + v * W;
    T& dst = om.property(handle, OpenMesh::VertexHandle(static_cast<int>(v)));
    if constexpr (W == 1) {
      dst = src[0];
    } else {
      for (std::uint32_t k = 0; k < W; ++k) dst[static_cast<int>(k)] = src[k];
    }
  }
}

template <std::uint32_t W>
void import_channel(const OpenMeshTriMesh& om, Channel& channel) {
  using T = typename PropertyType<W>::type;
  OpenMesh::VPropHandleT<T> handle;
  if (!om.get_property_handle(handle, channel.desc.name)) {
    throw InvalidInput(cat("from_openmesh: no vertex property '", channel.desc.name, "' of type ",
                           PropertyType<W>::name, " for channel ", channel.desc.name, " (width ", W,
                           ")"));
  }
  channel.values.resize(om.n_vertices() * W);
  for (std::size_t v = 0; v < om.n_vertices(); ++v) {
    const T& src = om.property(handle, OpenMesh::VertexHandle(static_cast<int>(v)));
    float* dst = channel.values.data() + v * W;
    if constexpr (W == 1) {
      dst[0] = src;
    } else {
      for (std::uint32_t k = 0; k < W; ++k) dst[k] = src[static_cast<int>(k)];
    }
  }
}

template <std::uint32_t W>
bool holds(const OpenMesh::BaseProperty& p) {
  return dynamic_cast<const OpenMesh::PropertyT<typename PropertyType<W>::type>*>(&p) != nullptr;
}

}  // namespace

OpenMeshTriMesh to_openmesh(const Mesh& mesh) {
  validate(mesh, "to_openmesh");
  for (const Channel& c : mesh.channels) {
    if (c.desc.name.starts_with("v:")) {
      throw InvalidInput(cat("to_openmesh: channel name ", c.desc.name,
                             " is reserved for OpenMesh's own properties"));
    }
  }
  OpenMeshTriMesh om;
  om.reserve(mesh.vertex_count(), 3 * mesh.face_count() / 2, mesh.face_count());
  for (const Vec3f& p : mesh.positions) om.add_vertex(OpenMeshTriMesh::Point(p.x, p.y, p.z));

  // A directed edge used by two triangles is what OpenMesh most often rejects ("complex
  // edge"); catching it here gives a precise message and keeps OpenMesh from logging.
  std::unordered_set<std::uint64_t> directed_edges;
  directed_edges.reserve(3 * mesh.face_count());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[static_cast<std::size_t>(k)];
      const std::uint32_t b = tri[static_cast<std::size_t>((k + 1) % 3)];
      if (!directed_edges.insert(std::uint64_t{a} << 32 | b).second) {
        throw InvalidInput(cat("to_openmesh: triangle ", t, " (", tri[0], ", ", tri[1], ", ",
                               tri[2], ") is rejected by OpenMesh: edge ", a, "->", b,
                               " is already used in this direction by an earlier triangle "
                               "(non-manifold edge or inconsistent orientation)"));
      }
    }
    const OpenMesh::FaceHandle fh = om.add_face(OpenMesh::VertexHandle(static_cast<int>(tri[0])),
                                                OpenMesh::VertexHandle(static_cast<int>(tri[1])),
                                                OpenMesh::VertexHandle(static_cast<int>(tri[2])));
    if (!fh.is_valid()) {
      throw InvalidInput(cat("to_openmesh: triangle ", t, " (", tri[0], ", ", tri[1], ", ", tri[2],
                             ") is rejected by OpenMesh (non-manifold vertex or edge)"));
    }
  }
  for (const Channel& c : mesh.channels) {
    switch (c.desc.width) {
      case 1:
        export_channel<1>(om, c);
        break;
      case 2:
        export_channel<2>(om, c);
        break;
      case 3:
        export_channel<3>(om, c);
        break;
      default:
        export_channel<4>(om, c);
        break;
    }
  }
  return om;
}

Mesh from_openmesh(const OpenMeshTriMesh& om, std::span<const ChannelDesc> channels) {
  // Handles index our arrays directly, so deleted elements would leave holes.
  if (om.has_vertex_status()) {
    for (auto vh : om.all_vertices()) {
      if (om.status(vh).deleted()) {
        throw InvalidInput("from_openmesh: mesh has deleted vertices (call garbage_collection())");
      }
    }
  }
  if (om.has_face_status()) {
    for (auto fh : om.all_faces()) {
      if (om.status(fh).deleted()) {
        throw InvalidInput("from_openmesh: mesh has deleted faces (call garbage_collection())");
      }
    }
  }
  Mesh mesh;
  mesh.positions.reserve(om.n_vertices());
  for (auto vh : om.all_vertices()) {
    const auto& p = om.point(vh);
    mesh.positions.push_back({p[0], p[1], p[2]});
  }
  mesh.triangles.reserve(om.n_faces());
  for (auto fh : om.all_faces()) {
    Triangle tri{};
    std::size_t k = 0;
    for (auto vh : om.fv_range(fh)) {
      if (k < 3) tri[k] = static_cast<std::uint32_t>(vh.idx());
      ++k;
    }
    if (k != 3) {
      throw InvalidInput(cat("from_openmesh: face ", fh.idx(), " has ", k, " vertices"));
    }
    mesh.triangles.push_back(tri);
  }
  for (const ChannelDesc& d : channels) {
    Channel c;
    c.desc = d;
    switch (d.width) {
      case 1:
        import_channel<1>(om, c);
        break;
      case 2:
        import_channel<2>(om, c);
        break;
      case 3:
        import_channel<3>(om, c);
        break;
      case 4:
        import_channel<4>(om, c);
        break;
      default:
        throw InvalidInput(
            cat("from_openmesh: channel ", d.name, " has width ", d.width, " (must be 1..4)"));
    }
    mesh.channels.push_back(std::move(c));
  }
  validate(mesh, "from_openmesh");
  return mesh;
}

Mesh from_openmesh(const OpenMeshTriMesh& om) {
  std::vector<ChannelDesc> channels;
  for (auto it = om.vprops_begin(); it != om.vprops_end(); ++it) {
    const OpenMesh::BaseProperty* p = *it;
    if (p == nullptr || !p->persistent() || p->name().starts_with("v:")) continue;
    std::uint32_t width = 0;
    if (holds<1>(*p)) width = 1;
    if (holds<2>(*p)) width = 2;
    if (holds<3>(*p)) width = 3;
    if (holds<4>(*p)) width = 4;
    if (width == 0) continue;
    channels.push_back(default_channel(p->name(), width));
  }
  return from_openmesh(om, channels);
}

}  // namespace csculpt
