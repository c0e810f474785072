// Small 3-vector helpers for strokes, generators, the merge and tests: Vec3f (the mesh's
// positions) and Vec3d (double-precision arithmetic on them).
#pragma once

#include <cmath>

#include "csculpt/mesh.h"

namespace csculpt {

inline Vec3f add(Vec3f a, Vec3f b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3f sub(Vec3f a, Vec3f b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3f scale(Vec3f a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline float dot(Vec3f a, Vec3f b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3f cross(Vec3f a, Vec3f b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// a / |a|, or a unchanged when it is zero
inline Vec3f unit(Vec3f a) {
  const float n = std::sqrt(dot(a, a));
  return n > 0 ? scale(a, 1.f / n) : a;
}

/// Double precision, for sums, distances and normals computed from float positions (each
/// operation in the order written, so results match numpy's on the same values).
struct Vec3d {
  double x = 0, y = 0, z = 0;
};
inline Vec3d widen(Vec3f p) {
  return {p.x, p.y, p.z};
}
/// Back to float, each coordinate rounded to nearest.
inline Vec3f narrow(Vec3d p) {
  return {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
}
inline Vec3d add(Vec3d a, Vec3d b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3d sub(Vec3d a, Vec3d b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3d scale(Vec3d a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline double dot(Vec3d a, Vec3d b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3d cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm2(Vec3d a) {
  return dot(a, a);
}
inline double length(Vec3d a) {
  return std::sqrt(dot(a, a));
}

}  // namespace csculpt
