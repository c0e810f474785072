// Strokes of the built-in artist (csculpt/testkit/generate.h) in tests: one from the four values
// the tests vary (the rest keep Stroke's defaults), and each kind's name for messages.
#pragma once

#include <string>

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

/// "grab", "inflate", ...: the name of the enumerator, for traces and test names.
inline std::string kind_name(Stroke::Kind kind) {
  switch (kind) {
    case Stroke::Kind::grab:
      return "grab";
    case Stroke::Kind::inflate:
      return "inflate";
    case Stroke::Kind::detail:
      return "detail";
    case Stroke::Kind::twist:
      return "twist";
    case Stroke::Kind::bend:
      return "bend";
    case Stroke::Kind::smooth:
      return "smooth";
    case Stroke::Kind::paint:
      return "paint";
  }
  return "?";
}

}  // namespace csculpt::test
