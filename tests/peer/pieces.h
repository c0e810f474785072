// Helpers for the socket-free tests of the peer layer's pieces (peer/src).
#pragma once

#include <cstdint>
#include <memory>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"

namespace csculpt::peer::testing {

/// A sphere with material channels: the session mesh of these tests.
inline const Mesh& sphere() {
  static const Mesh m = make_sphere(320, true);
  return m;
}

/// `base` with a grab stroke at `center` (and, with `paint`, a paint stroke there).
/// The hierarchy of sphere() (built once).
inline std::shared_ptr<const Hierarchy> sphere_hierarchy() {
  static const auto h = std::make_shared<const Hierarchy>(
      Hierarchy::build(static_cast<std::uint32_t>(sphere().vertex_count()), sphere().triangles));
  return h;
}

inline Mesh stroked(const Mesh& base, Vec3f center, Vec3f axis, bool paint = false) {
  Mesh m = base;
  Stroke s;
  s.kind = Stroke::Kind::grab;
  s.center = center;
  s.axis = axis;
  s.radius = 0.4f;
  s.strength = 0.2f;
  apply_stroke(m, s);
  if (paint) {
    s.kind = Stroke::Kind::paint;
    apply_stroke(m, s);
  }
  return m;
}

inline Diff stroke_diff(const Mesh& base, Vec3f center, Vec3f axis, bool paint = false) {
  return capture_diff(base, stroked(base, center, axis, paint));
}

}  // namespace csculpt::peer::testing
