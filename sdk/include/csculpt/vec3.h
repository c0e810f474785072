// Small Vec3f helpers for strokes, generators and tests (the merge's hot loops spell their
// arithmetic out in double where precision matters).
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

}  // namespace csculpt
