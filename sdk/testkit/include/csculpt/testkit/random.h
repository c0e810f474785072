// splitmix64: a small, fast generator that gives the same numbers on every platform (unlike
// the std:: distributions), for scripted strokes, benchmarks and tests.
#pragma once

#include <cstdint>

namespace csculpt {

struct SplitMix64 {
  std::uint64_t state = 0;

  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// uniform in [0, 1) with 53 random bits
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double range(double a, double b) { return a + (b - a) * uniform(); }
  /// uniform in [0, 1) with 24 random bits
  float uniform_float() {
    return static_cast<float>(next() >> 40) / static_cast<float>(1ull << 24);
  }
  float range_float(float a, float b) { return a + (b - a) * uniform_float(); }
};

}  // namespace csculpt
