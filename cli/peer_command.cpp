#include "peer_command.h"

#include <cstdio>

namespace csculpt::cli {

CLI::App* add_peer_command(CLI::App& app, PeerCommandOptions& o) {
  CLI::App* peer = app.add_subcommand("peer", "one simulated artist in a session (in progress)");
  peer->add_option("--join", o.join, "invite of the session to join");
  return peer;
}

int run_peer(const PeerCommandOptions&) {
  std::fprintf(stderr, "csculpt peer: not built yet\n");
  return 2;
}

}  // namespace csculpt::cli
