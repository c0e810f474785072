// `csculpt demo`: the product's main job. A serverless session on this machine: N simulated
// artists, each a peer::Session with its own network thread and real (CURVE, loopback TCP)
// sockets, sculpt and paint a built-in sphere at the same time; the elected merger merges their
// edits every sync interval. One line per merge on stderr, a JSON summary as the last line on
// stdout, and the final mesh with materials and attribution colours (the paper's Fig. 1).
// With --replay, one peer plays every artist's script: the single-peer baseline of the same
// strokes, with the same summary (fold-overs included) to compare against.
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

namespace csculpt::cli {

struct DemoOptions {
  std::uint32_t peers = 2;
  double seconds = 20;  ///< editing time; syncing continues until converged
  std::uint32_t faces = 320000;
  std::uint32_t sync_ms = 250;
  std::string out = "merged.ply";
  std::uint64_t seed = 7;
  /// Per artist. Not a multiple of the sync rate: strokes land while a merge is in flight, so
  /// the rebase path runs as it would for a real artist.
  double strokes_per_second = 5;
  double converge_timeout_seconds = 15;
  /// One peer plays the scripts of all `peers` artists (the same scripts, seeds and rate a
  /// `peers`-peer session uses) in time order: the single-peer baseline of the same strokes.
  bool replay = false;
};

/// Runs the session; returns 0 when every peer converged with no lost edit, 1 otherwise
/// (the summary is printed and the mesh written in both cases).
int run_demo(const DemoOptions& options);

/// Registers `csculpt demo` and its options on `app`.
CLI::App* add_demo_command(CLI::App& app, DemoOptions& options);

}  // namespace csculpt::cli
