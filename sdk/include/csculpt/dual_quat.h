// Unit dual quaternions for rigid motions (paper §3.1 "Rotational Invariance", after
// Kavan et al. 2008), and the magnitude-weighted blend that the merge uses at every node.
//
// Convention: a quaternion is (w, x, y, z); q1 * q2 applies q2 first, then q1. A unit dual
// quaternion r + eps*d encodes the motion p -> R(r) p + t with d = 1/2 (0,t) r.
#pragma once

#include <cmath>

#include "csculpt/mesh.h"

namespace csculpt {

struct Quat {
  float w = 1, x = 0, y = 0, z = 0;
  friend bool operator==(const Quat&, const Quat&) = default;
};

inline Quat operator*(const Quat& a, const Quat& b) {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
inline Quat operator+(const Quat& a, const Quat& b) {
  return {a.w + b.w, a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Quat operator-(const Quat& a, const Quat& b) {
  return {a.w - b.w, a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Quat operator*(float s, const Quat& a) {
  return {s * a.w, s * a.x, s * a.y, s * a.z};
}
inline Quat conjugate(const Quat& a) {
  return {a.w, -a.x, -a.y, -a.z};
}
inline float dot(const Quat& a, const Quat& b) {
  return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
}

/// Rotates v by the unit quaternion q (q v q*), expanded for speed.
inline Vec3f rotate(const Quat& q, const Vec3f& v) {
  // t = 2 (q.xyz x v); v' = v + w t + q.xyz x t
  const float tx = 2 * (q.y * v.z - q.z * v.y);
  const float ty = 2 * (q.z * v.x - q.x * v.z);
  const float tz = 2 * (q.x * v.y - q.y * v.x);
  return {v.x + q.w * tx + (q.y * tz - q.z * ty), v.y + q.w * ty + (q.z * tx - q.x * tz),
          v.z + q.w * tz + (q.x * ty - q.y * tx)};
}

struct DualQuat {
  Quat real;              ///< rotation
  Quat dual{0, 0, 0, 0};  ///< 1/2 (0, t) * real

  static constexpr DualQuat identity() { return {}; }
  friend bool operator==(const DualQuat&, const DualQuat&) = default;

  /// The motion p -> R(rotation) p + translation.
  static DualQuat from_rotation_translation(const Quat& rotation, const Vec3f& t) {
    return {rotation, 0.5f * (Quat{0, t.x, t.y, t.z} * rotation)};
  }

  /// The rigid motion with rotation `rotation` that moves `from` exactly onto `to`
  /// (paper §3.1: q_T = quat(0, p_b/2) q_R - q_R quat(0, p_a/2)).
  static DualQuat from_rotation_and_points(const Quat& rotation, const Vec3f& from,
                                           const Vec3f& to) {
    const Quat pb{0, 0.5f * to.x, 0.5f * to.y, 0.5f * to.z};
    const Quat pa{0, 0.5f * from.x, 0.5f * from.y, 0.5f * from.z};
    return {rotation, pb * rotation - rotation * pa};
  }

  Vec3f translation() const {
    const Quat t = dual * conjugate(real);  // (0, t/2) for a unit dual quaternion
    return {2 * t.x, 2 * t.y, 2 * t.z};
  }

  Vec3f apply(const Vec3f& p) const {
    const Vec3f r = rotate(real, p);
    const Vec3f t = translation();
    return {r.x + t.x, r.y + t.y, r.z + t.z};
  }
};

/// Composition: (a * b) applies b first, then a.
inline DualQuat operator*(const DualQuat& a, const DualQuat& b) {
  return {a.real * b.real, a.real * b.dual + a.dual * b.real};
}

/// Inverse of a unit dual quaternion: the quaternion conjugate of both parts.
inline DualQuat inverse(const DualQuat& q) {
  return {conjugate(q.real), conjugate(q.dual)};
}

/// Sign-canonical form: the paper's rule (§3.1) keeps the real primal component positive, so
/// that q and -q (the same motion) blend alike and the sum of many operands is associative.
/// A zero real component keeps its sign (only possible at exactly 180 degrees).
inline DualQuat canonical(const DualQuat& q) {
  if (q.real.w < 0) return {-1.f * q.real, -1.f * q.dual};
  return q;
}

/// acc += w q, over the 8 components: the weighted sums the blends are made of.
inline void add_scaled(DualQuat& acc, float w, const DualQuat& q) {
  acc.real = acc.real + w * q.real;
  acc.dual = acc.dual + w * q.dual;
}
/// acc += w (q - 1): the sum over a set whose absent members are the identity.
inline void add_scaled_offset(DualQuat& acc, float w, const DualQuat& q) {
  acc.real = acc.real + w * Quat{q.real.w - 1.f, q.real.x, q.real.y, q.real.z};
  acc.dual = acc.dual + w * q.dual;
}

/// Projects an 8-vector onto the unit dual quaternions: real part to unit length, dual part
/// made orthogonal to it. A (near) zero real part gives the identity.
inline DualQuat normalized(const float v[8]) {
  const float n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3];
  if (!(n2 > 1e-30f)) return DualQuat::identity();
  const float inv = 1.f / std::sqrt(n2);
  const Quat r{v[0] * inv, v[1] * inv, v[2] * inv, v[3] * inv};
  Quat d{v[4] * inv, v[5] * inv, v[6] * inv, v[7] * inv};
  const float rd = dot(r, d);
  d = d - rd * r;
  return {r, d};
}
inline DualQuat normalized(const DualQuat& q) {
  const float v[8] = {q.real.w, q.real.x, q.real.y, q.real.z,
                      q.dual.w, q.dual.x, q.dual.y, q.dual.z};
  return normalized(v);
}

/// The paper's magnitude m(q) = |q - 1| over the 8 components (of the canonical form).
inline float magnitude(const DualQuat& q) {
  const DualQuat c = canonical(q);
  const float dw = c.real.w - 1.f;
  return std::sqrt(dw * dw + c.real.x * c.real.x + c.real.y * c.real.y + c.real.z * c.real.z +
                   c.dual.w * c.dual.w + c.dual.x * c.dual.x + c.dual.y * c.dual.y +
                   c.dual.z * c.dual.z);
}

/// Closest rotation quaternion (w >= 0) to a proper rotation matrix given row-major.
Quat quat_from_matrix(const float m[9]);

}  // namespace csculpt
