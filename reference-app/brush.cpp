#include "brush.h"

#include <algorithm>
#include <cmath>

float falloff_weight(Falloff falloff, float d) {
  const float x = std::clamp(1.f - d, 0.f, 1.f);
  switch (falloff) {
    case Falloff::smooth:
      return x * x * (3.f - 2.f * x);
    case Falloff::sphere:
      return std::sqrt(std::max(0.f, 1.f - d * d));
    case Falloff::linear:
      return x;
    case Falloff::sharp:
      return x * x;
    case Falloff::constant:
      return d <= 1.f ? 1.f : 0.f;
  }
  return x;
}
