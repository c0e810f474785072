#include "bench_session.h"

#include <cstdio>

namespace csculpt::cli {

CLI::App* add_bench_session_command(CLI::App& bench, BenchSessionOptions& o) {
  CLI::App* cmd = bench.add_subcommand("session", "session end-to-end latency (in progress)");
  cmd->add_option("--faces", o.faces, "approximate face count")->capture_default_str();
  return cmd;
}

int bench_session(const BenchSessionOptions&) {
  std::fprintf(stderr, "csculpt bench session: not built yet\n");
  return 2;
}

}  // namespace csculpt::cli
