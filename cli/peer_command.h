// `csculpt peer`: one simulated artist in a serverless session, as its own process. It prints
// one JSON object per line on stdout (invite, session events, state changes, a final summary)
// so a script can drive several of them and check convergence (tests/session).
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace csculpt::cli {

struct PeerCommandOptions {
  std::string join;  ///< invite; empty: create a session
  std::uint32_t faces = 20000;
  std::uint64_t id = 0;  ///< 0: random
  std::string name;
  std::string bind = "tcp://127.0.0.1:*";
  std::uint32_t sync_ms = 250;
  std::uint32_t heartbeat_ms = 200;
  std::uint32_t evasive_ms = 600;
  std::uint32_t expired_ms = 1200;
  std::uint32_t join_timeout_ms = 30000;
  double seconds = 10;
  double strokes_per_second = 4;
  std::uint64_t seed = 1;
  double linger = 5;
  bool ignore_stdin = false;
  bool markers = false;           ///< a marker with each stroke (markers.h)
  std::int64_t marker_slot = -1;  ///< -1: the peer id's
  std::uint32_t marker_first = 0;
  std::uint32_t marker_limit = 0xffffffffu;
  std::string out;
  std::string journal;  ///< journal directory (create or join)
  std::string resume;   ///< journal directory to resume from
  std::uint64_t journal_max_log_versions = 1024;
};

CLI::App* add_peer_command(CLI::App& app, PeerCommandOptions& options);
int run_peer(const PeerCommandOptions& options);

}  // namespace csculpt::cli
