// Internal: the sparse per-vertex isometry kernel shared by the merge and
// vertex_isometries(). Works only on the faces around changed vertices.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/dual_quat.h"
#include "csculpt/hierarchy.h"
#include "csculpt/isometry.h"

namespace csculpt::detail {

/// Maps mesh coordinates into the merge's working frame (centred, unit diagonal), in which
/// the magnitude |q - 1| weighs rotation and translation alike whatever the model's units.
struct Frame {
  Vec3f center{0, 0, 0};
  float inv_scale = 1;
  Vec3f to_local(const Vec3f& p) const {
    return {(p.x - center.x) * inv_scale, (p.y - center.y) * inv_scale,
            (p.z - center.z) * inv_scale};
  }
};

inline bool face_rotation_kernel(const Vec3f& a0, const Vec3f& a1, const Vec3f& a2,
                                 const Vec3f& b0, const Vec3f& b1, const Vec3f& b2, Quat& out) {
  struct D3 {
    double x, y, z;
  };
  auto sub = [](const Vec3f& p, const Vec3f& q) -> D3 {
    return {double(p.x) - q.x, double(p.y) - q.y, double(p.z) - q.z};
  };
  auto cross = [](const D3& u, const D3& v) -> D3 {
    return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  };
  auto norm2 = [](const D3& u) { return u.x * u.x + u.y * u.y + u.z * u.z; };
  const D3 e0a = sub(a1, a0), e1a = sub(a2, a0), e0b = sub(b1, b0), e1b = sub(b2, b0);
  const D3 ca = cross(e0a, e1a), cb = cross(e0b, e1b);
  const double da2 = norm2(ca), db2 = norm2(cb);
  // Degenerate before or after: no usable frame, no rotation from this face. A triangle
  // flattened in float arithmetic keeps a cross product of rounding noise (sin of its
  // angles ~1e-7), whose normal would be arbitrary, so the bound sits well above float
  // resolution: sin(angle between the edges) > 1e-5.
  const double tol = 1e-10;
  if (!(da2 > tol * norm2(e0a) * norm2(e1a))) return false;
  if (!(db2 > tol * norm2(e0b) * norm2(e1b))) return false;
  const double da = std::sqrt(da2), db = std::sqrt(db2);
  const D3 na{ca.x / da, ca.y / da, ca.z / da};
  const D3 nb{cb.x / db, cb.y / db, cb.z / db};
  // Rows of (e0a, e1a, na)^-1: (e1a x na)/|ca|, (na x e0a)/|ca|, na.
  D3 r0 = cross(e1a, na), r1 = cross(na, e0a);
  r0 = {r0.x / da, r0.y / da, r0.z / da};
  r1 = {r1.x / da, r1.y / da, r1.z / da};
  const double bx[3] = {e0b.x, e0b.y, e0b.z}, by[3] = {e1b.x, e1b.y, e1b.z},
               bn[3] = {nb.x, nb.y, nb.z};
  const double ar0[3] = {r0.x, r0.y, r0.z}, ar1[3] = {r1.x, r1.y, r1.z},
               an[3] = {na.x, na.y, na.z};
  double m[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[3 * i + j] = bx[i] * ar0[j] + by[i] * ar1[j] + bn[i] * an[j];
  return closest_rotation(m, out);
}

struct VertexIsometryScratch {
  std::vector<std::uint32_t> face_stamp;
  std::vector<std::uint32_t> vertex_stamp;
  std::vector<Quat> rotation_sum;  ///< sum of (q_face - 1) over changed faces
  std::uint32_t epoch = 0;

  void resize(std::size_t vertices, std::size_t faces) {
    if (face_stamp.size() < faces) face_stamp.resize(faces, 0);
    if (vertex_stamp.size() < vertices) {
      vertex_stamp.resize(vertices, 0);
      rotation_sum.resize(vertices);
    }
  }
  std::uint32_t next_epoch() {
    if (++epoch == 0) {  // wrapped: forget every stamp
      std::fill(face_stamp.begin(), face_stamp.end(), 0);
      std::fill(vertex_stamp.begin(), vertex_stamp.end(), 0);
      epoch = 1;
    }
    return epoch;
  }
};

/// For every vertex on a face that has a changed vertex: q = q_R + eps q_T with q_R the
/// normalised sum of its incident face rotations (unchanged and degenerate faces count as
/// the identity) and q_T such that the vertex lands exactly on its edited position.
/// Writes out[v] for those vertices and lists them in `touched` (in a deterministic order).
template <class EditedPosition>
void compute_vertex_isometries(const Topology& topology, std::span<const Vec3f> base,
                               std::span<const std::uint32_t> changed, EditedPosition&& edited,
                               VertexIsometryScratch& scratch, std::span<DualQuat> out,
                               std::vector<std::uint32_t>& touched, const Frame& frame = {}) {
  const std::uint32_t epoch = scratch.next_epoch();
  touched.clear();
  const auto& vf = topology.vertex_faces;
  for (std::uint32_t v : changed) {
    if (scratch.vertex_stamp[v] != epoch) {  // also a changed vertex on no face
      scratch.vertex_stamp[v] = epoch;
      scratch.rotation_sum[v] = {0, 0, 0, 0};
      touched.push_back(v);
    }
    for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
      const std::uint32_t f = vf.items[i];
      if (scratch.face_stamp[f] == epoch) continue;
      scratch.face_stamp[f] = epoch;
      const Triangle& t = topology.triangles[f];
      for (std::uint32_t u : t) {
        if (scratch.vertex_stamp[u] != epoch) {
          scratch.vertex_stamp[u] = epoch;
          scratch.rotation_sum[u] = {0, 0, 0, 0};
          touched.push_back(u);
        }
      }
      Quat q;
      if (!face_rotation_kernel(base[t[0]], base[t[1]], base[t[2]], edited(t[0]), edited(t[1]),
                                edited(t[2]), q))
        continue;
      const Quat offset{q.w - 1.f, q.x, q.y, q.z};
      for (std::uint32_t u : t) scratch.rotation_sum[u] = scratch.rotation_sum[u] + offset;
    }
  }
  for (std::uint32_t u : touched) {
    const Quat& s = scratch.rotation_sum[u];
    const float degree = static_cast<float>(vf.offsets[u + 1] - vf.offsets[u]);
    Quat r{degree + s.w, s.x, s.y, s.z};
    const float n2 = dot(r, r);
    r = n2 > 1e-30f ? (1.f / std::sqrt(n2)) * r : Quat{};
    out[u] = canonical(DualQuat::from_rotation_and_points(r, frame.to_local(base[u]),
                                                          frame.to_local(edited(u))));
  }
}

}  // namespace csculpt::detail
