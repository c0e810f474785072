// A stroke of the built-in artist (csculpt/testkit/generate.h) from the four values the unit tests
// vary; the rest keep Stroke's defaults.
#pragma once

#include "csculpt/testkit/generate.h"

namespace csculpt::test {

inline Stroke stroke(Stroke::Kind kind, Vec3f center, float radius, float strength) {
  Stroke s;
  s.kind = kind;
  s.center = center;
  s.radius = radius;
  s.strength = strength;
  return s;
}

}  // namespace csculpt::test
