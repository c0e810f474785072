// Shared GoogleTest helpers.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

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

/// The whole file as bytes ("" if it cannot be read).
inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

/// A fresh, empty directory for the running test under testing::TempDir(), named by `prefix`,
/// the process and the test (so parallel ctest runs never share one), removed with the object.
class TestDir {
 public:
  explicit TestDir(const std::string& prefix) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::path(::testing::TempDir()) /
            (prefix + "_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" +
             info->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TestDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TestDir(const TestDir&) = delete;
  TestDir& operator=(const TestDir&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace csculpt::test
