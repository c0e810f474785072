// `csculpt bench session`: end-to-end latency of a peer session.
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>

namespace csculpt::cli {

struct BenchSessionOptions {
  std::uint32_t faces = 320000;
};

CLI::App* add_bench_session_command(CLI::App& bench, BenchSessionOptions& options);
int bench_session(const BenchSessionOptions& options);

}  // namespace csculpt::cli
