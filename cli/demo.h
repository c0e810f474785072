#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace csculpt::cli {

struct DemoOptions {
  std::uint32_t artists = 2;
  std::uint32_t faces = 320000;
  std::uint32_t rounds = 12;
  std::uint32_t strokes_per_round = 2;
  std::string method = "full";
  std::string out = "merged.ply";
  std::uint64_t seed = 7;
};

/// In-process collaborative session: every round each artist sculpts and paints its own
/// copy of the agreed version with scripted strokes, then the edits are merged into the
/// next version. Prints a line per merge and a JSON summary; writes the final mesh.
int run_demo(const DemoOptions& options);

/// Registers `csculpt demo` and its options on `app`.
CLI::App* add_demo_command(CLI::App& app, DemoOptions& options);

}  // namespace csculpt::cli
