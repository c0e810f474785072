// `csculpt bench session`: end-to-end latency of a peer session on loopback (one thread per
// peer host plus each session's own network thread, real CURVE sockets): from a submitted
// local edit to every peer holding the merged version that contains it.
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <vector>

namespace csculpt::cli {

struct BenchSessionOptions {
  std::uint32_t faces = 320000;
  std::vector<std::uint32_t> peers{2, 4, 8};
  std::uint32_t sync_ms = 10;  // the session's default (SessionOptions::sync)
  std::uint32_t samples = 40;
  std::uint64_t seed = 11;
  /// Hosts submit the whole mesh instead of the vertices their strokes changed.
  bool full_submit = false;
};

CLI::App* add_bench_session_command(CLI::App& bench, BenchSessionOptions& options);
/// Prints one JSON object per peer count (medians and tails of the samples); returns the
/// process exit code (1 if a configuration could not be measured).
int bench_session(const BenchSessionOptions& options);

}  // namespace csculpt::cli
