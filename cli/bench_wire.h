#pragma once
#include <cstdint>

namespace csculpt::cli {

struct BenchWireOptions {
  std::uint32_t faces = 320000;
  std::uint32_t touched = 10000;  ///< vertices each benchmark stroke touches (about)
  std::uint32_t repeat = 51;
  double tolerance = 1e-5;  ///< position tolerance, fraction of the bounding-box diagonal
};

/// Prints one JSON object per stroke kind (and lossless) with bytes per touched vertex, the
/// largest decoded error and median encode/decode times; returns the process exit code.
int bench_wire(const BenchWireOptions& options);

}  // namespace csculpt::cli
