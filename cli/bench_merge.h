#pragma once
#include <cstdint>
#include <string>

namespace csculpt::cli {

struct BenchMergeOptions {
  std::uint32_t faces = 320000;
  std::uint32_t users = 2;
  std::string method = "full";
  std::uint32_t k = 7;
  std::uint32_t repeat = 21;
  double edited_fraction = 0.15;
  bool paint = false;
  std::uint64_t seed = 1;
};

/// Prints one JSON object (one line) with the medians; returns the process exit code.
int bench_merge(const BenchMergeOptions& options);

}  // namespace csculpt::cli
