// `csculpt peer`: one simulated artist in a serverless session, as its own process.
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace csculpt::cli {

struct PeerCommandOptions {
  std::string join;  ///< invite; empty: create a session
};

CLI::App* add_peer_command(CLI::App& app, PeerCommandOptions& options);
int run_peer(const PeerCommandOptions& options);

}  // namespace csculpt::cli
