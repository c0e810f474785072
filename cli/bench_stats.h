// Timing and order statistics shared by the `csculpt bench` commands (medians, as the project
// quotes them).
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

namespace csculpt::cli {

using BenchClock = std::chrono::steady_clock;

inline double ms_between(BenchClock::time_point a, BenchClock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// The q-quantile (0 = min, 0.5 = median, 1 = max) of the samples; 0 for none.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

inline double median(std::vector<double> v) {
  return quantile(std::move(v), 0.5);
}

}  // namespace csculpt::cli
