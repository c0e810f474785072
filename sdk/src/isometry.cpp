#include "csculpt/isometry.h"

#include <Eigen/Dense>
#include <cmath>

#include "simd/vertex_isometry_kernel.h"

namespace csculpt {
namespace {

double det3(const double m[9]) {
  return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
         m[2] * (m[3] * m[7] - m[4] * m[6]);
}

}  // namespace

/// Quaternion (w >= 0) of a rotation matrix, Shepperd's method (largest pivot first).
Quat quat_from_rotation_matrix(const double m[9]) {
  // Shepperd: the largest of 4w^2, 4x^2, 4y^2, 4z^2 gives a well-conditioned pivot.
  const double tr = m[0] + m[4] + m[8];
  double w, x, y, z;
  if (tr > 0) {
    const double s = std::sqrt(tr + 1.0) * 2, inv = 1.0 / s;
    w = 0.25 * s;
    x = (m[7] - m[5]) * inv;
    y = (m[2] - m[6]) * inv;
    z = (m[3] - m[1]) * inv;
  } else if (m[0] > m[4] && m[0] > m[8]) {
    const double s = std::sqrt(1.0 + m[0] - m[4] - m[8]) * 2, inv = 1.0 / s;
    w = (m[7] - m[5]) * inv;
    x = 0.25 * s;
    y = (m[1] + m[3]) * inv;
    z = (m[2] + m[6]) * inv;
  } else if (m[4] > m[8]) {
    const double s = std::sqrt(1.0 + m[4] - m[0] - m[8]) * 2, inv = 1.0 / s;
    w = (m[2] - m[6]) * inv;
    x = (m[1] + m[3]) * inv;
    y = 0.25 * s;
    z = (m[5] + m[7]) * inv;
  } else {
    const double s = std::sqrt(1.0 + m[8] - m[0] - m[4]) * 2, inv = 1.0 / s;
    w = (m[3] - m[1]) * inv;
    x = (m[2] + m[6]) * inv;
    y = (m[5] + m[7]) * inv;
    z = 0.25 * s;
  }
  // R is orthonormal to rounding, so (w, x, y, z) is unit to rounding: no renormalisation.
  const double sign = w < 0 ? -1.0 : 1.0;
  return {static_cast<float>(w * sign), static_cast<float>(x * sign), static_cast<float>(y * sign),
          static_cast<float>(z * sign)};
}

namespace {
Quat quat_from_rotation(const double m[9]) {
  return quat_from_rotation_matrix(m);
}
}  // namespace

Quat quat_from_matrix(const float m[9]) {
  double d[9];
  for (int i = 0; i < 9; ++i) d[i] = m[i];
  return quat_from_rotation(d);
}

bool closest_rotation_svd(const double a[9], Quat& out) {
  Eigen::Matrix3d m;
  m << a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8];
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  if (!(s(1) > 1e-12 * std::max(1.0, s(0)))) return false;
  Eigen::Matrix3d u = svd.matrixU();
  const Eigen::Matrix3d v = svd.matrixV();
  if ((u * v.transpose()).determinant() < 0) u.col(2) = -u.col(2);
  const Eigen::Matrix3d r = u * v.transpose();
  double rm[9];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rm[3 * i + j] = r(i, j);
  out = quat_from_rotation(rm);
  return true;
}

bool closest_rotation(const double a[9], Quat& out) {
  double x[9];
  for (int i = 0; i < 9; ++i) x[i] = a[i];
  double scale2 = 0;
  for (double v : x) scale2 += v * v;
  if (!(scale2 > 0) || !std::isfinite(scale2)) return false;
  // Newton's iteration X <- (g X + X^-T / g) / 2 converges to the orthogonal polar factor,
  // which is the closest rotation when det > 0. Reflections and near-singular maps go to
  // the SVD, which handles them exactly.
  const double d0 = det3(x);
  if (!(d0 > 1e-9 * scale2 * std::sqrt(scale2))) return closest_rotation_svd(a, out);
  for (int iter = 0; iter < 30; ++iter) {
    double c[9];  // cofactor matrix: X^-T = c / det
    c[0] = x[4] * x[8] - x[5] * x[7];
    c[1] = x[5] * x[6] - x[3] * x[8];
    c[2] = x[3] * x[7] - x[4] * x[6];
    c[3] = x[2] * x[7] - x[1] * x[8];
    c[4] = x[0] * x[8] - x[2] * x[6];
    c[5] = x[1] * x[6] - x[0] * x[7];
    c[6] = x[1] * x[5] - x[2] * x[4];
    c[7] = x[2] * x[3] - x[0] * x[5];
    c[8] = x[0] * x[4] - x[1] * x[3];
    const double det = x[0] * c[0] + x[1] * c[1] + x[2] * c[2];
    if (!(det > 0)) return closest_rotation_svd(a, out);
    // determinant scaling (Higham): brings the singular values towards 1 quickly
    const double g = std::cbrt(1.0 / det);
    const double ga = 0.5 * g, gb = 0.5 / (g * det);
    double change = 0;
    for (int i = 0; i < 9; ++i) {
      const double next = ga * x[i] + gb * c[i];
      change += (next - x[i]) * (next - x[i]);
      x[i] = next;
    }
    if (change < 1e-22) break;
  }
  out = quat_from_rotation(x);
  return true;
}

bool face_rotation(const Vec3f& a0, const Vec3f& a1, const Vec3f& a2, const Vec3f& b0,
                   const Vec3f& b1, const Vec3f& b2, Quat& out) {
  return detail::face_rotation_kernel(a0, a1, a2, b0, b1, b2, out);
}

std::vector<DualQuat> vertex_isometries(const Topology& topology, std::span<const Vec3f> base,
                                        std::span<const Vec3f> edited) {
  std::vector<DualQuat> result(topology.vertex_count);
  detail::VertexIsometryScratch scratch;
  scratch.resize(topology.vertex_count, topology.triangles.size());
  std::vector<std::uint32_t> changed;
  for (std::uint32_t v = 0; v < topology.vertex_count; ++v)
    if (!(base[v] == edited[v])) changed.push_back(v);
  std::vector<std::uint32_t> touched;
  detail::compute_vertex_isometries(
      topology, base, changed, [&](std::uint32_t v) -> const Vec3f& { return edited[v]; }, scratch,
      [&](std::uint32_t v, const DualQuat& q) { result[v] = q; }, touched);
  return result;
}

}  // namespace csculpt
