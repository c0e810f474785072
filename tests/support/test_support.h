// Shared GoogleTest helpers.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "csculpt/dual_quat.h"
#include "csculpt/error.h"

namespace csculpt::test {

/// Runs fn, which must throw csculpt::InvalidInput, and returns the message (else a failure).
template <class Fn>
std::string invalid_input_message(Fn&& fn) {
  try {
    fn();
  } catch (const csculpt::InvalidInput& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InvalidInput";
  return {};
}

/// Largest absolute component difference of two dual quaternions (no sign handling).
inline double max_diff(const csculpt::DualQuat& a, const csculpt::DualQuat& b) {
  const float av[8] = {a.real.w, a.real.x, a.real.y, a.real.z,
                       a.dual.w, a.dual.x, a.dual.y, a.dual.z};
  const float bv[8] = {b.real.w, b.real.x, b.real.y, b.real.z,
                       b.dual.w, b.dual.x, b.dual.y, b.dual.z};
  double m = 0;
  for (int i = 0; i < 8; ++i) m = std::max(m, std::abs(double(av[i]) - double(bv[i])));
  return m;
}

}  // namespace csculpt::test
