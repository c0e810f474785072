// `csculpt demo`: the merge in the loop of a collaborative session, on the built-in sphere.
// Until the ZeroMQ peer session lands, the artists run in this process and sync by rounds.
#include "demo.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/generate.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"

namespace csculpt::cli {

int run_demo(const DemoOptions& o) {
  const MergeMethod method = merge_method_from_string(o.method);
  Mesh version = make_sphere(o.faces, true);
  const std::size_t n = version.vertex_count();
  const auto t0 = std::chrono::steady_clock::now();
  const Hierarchy hierarchy = Hierarchy::build(version);
  const double hierarchy_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const MergeFrame frame = MergeFrame::fit(version.positions);  // once per session
  Merger merger(hierarchy);
  std::fprintf(
      stderr,
      "session: %u artists on a %zu-face sphere (%zu vertices), hierarchy %u levels in %.1f ms\n",
      o.artists, version.face_count(), n, hierarchy.stats().levels, hierarchy_ms);

  // Per artist: its scripted strokes, and how much it moved each vertex (attribution).
  std::vector<std::vector<Stroke>> scripts;
  for (std::uint32_t a = 0; a < o.artists; ++a)
    scripts.push_back(scripted_strokes(version, o.seed * 7919 + a, o.rounds * o.strokes_per_round));
  std::vector<std::vector<float>> contribution(o.artists, std::vector<float>(n, 0.f));

  std::uint32_t strokes = 0, conflicting = 0;
  double merge_sum = 0, merge_max = 0;
  std::size_t diff_vertices = 0;
  std::vector<std::uint32_t> owner_round(n, 0), owner_mask(n, 0);
  for (std::uint32_t round = 0; round < o.rounds; ++round) {
    std::vector<Diff> diffs;
    // which artists touched each vertex this round (for the conflict count)
    std::vector<std::vector<std::vector<std::uint32_t>>> stroke_sets(o.artists);
    for (std::uint32_t a = 0; a < o.artists; ++a) {
      Mesh local = version;
      for (std::uint32_t s = 0; s < o.strokes_per_round; ++s) {
        const Mesh before = local;
        apply_stroke(local, scripts[a][round * o.strokes_per_round + s], &hierarchy.topology());
        const Diff stroke = capture_diff(before, local);
        std::vector<std::uint32_t> touched = stroke.positions.indices;
        for (const ChannelDiff& c : stroke.channels)
          touched.insert(touched.end(), c.change.indices.begin(), c.change.indices.end());
        std::sort(touched.begin(), touched.end());
        touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
        for (std::uint32_t v : touched) {
          if (owner_round[v] != round + 1) {
            owner_round[v] = round + 1;
            owner_mask[v] = 0;
          }
          owner_mask[v] |= 1u << (a % 32);
        }
        stroke_sets[a].push_back(std::move(touched));
        ++strokes;
      }
      diffs.push_back(capture_diff(version, local));
      diff_vertices += diffs.back().touched_vertices();
      for (std::size_t i = 0; i < diffs.back().positions.indices.size(); ++i) {
        const std::uint32_t v = diffs.back().positions.indices[i];
        const float* p = diffs.back().positions.values.data() + 3 * i;
        const float dx = p[0] - version.positions[v].x, dy = p[1] - version.positions[v].y,
                    dz = p[2] - version.positions[v].z;
        contribution[a][v] += std::sqrt(dx * dx + dy * dy + dz * dz);
      }
    }
    // MeshHisto (paper §3.3) rejects an edit that touches a vertex another artist touched
    // in the same sync window.
    std::uint32_t round_conflicts = 0;
    for (std::uint32_t a = 0; a < o.artists; ++a)
      for (const auto& set : stroke_sets[a])
        for (std::uint32_t v : set)
          if (owner_mask[v] & ~(1u << (a % 32))) {
            ++round_conflicts;
            break;
          }
    conflicting += round_conflicts;

    const auto m0 = std::chrono::steady_clock::now();
    const Diff merged = merger.merge(version, diffs, method, frame);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m0).count();
    apply_diff(merged, version);
    merge_sum += ms;
    merge_max = std::max(merge_max, ms);
    std::fprintf(stderr,
                 "merge %2u: %u diffs, %zu vertices changed, %.2f ms, %u edits would conflict\n",
                 round + 1, o.artists, merged.touched_vertices(), ms, round_conflicts);
  }

  // Attribution colours (paper Fig. 1): green for artist A, blue for B, cyan for both,
  // further artists red/yellow/magenta; brightness by share of the total change.
  static const float palette[6][3] = {{0, 1, 0}, {0, 0, 1}, {1, 0, 0},
                                      {1, 1, 0}, {1, 0, 1}, {1, 0.5f, 0}};
  std::vector<float> colour(3 * n, 0.f);
  for (std::size_t v = 0; v < n; ++v) {
    float total = 0;
    for (std::uint32_t a = 0; a < o.artists; ++a) total += contribution[a][v];
    if (!(total > 0)) continue;
    for (std::uint32_t a = 0; a < o.artists; ++a)
      for (int c = 0; c < 3; ++c)
        colour[3 * v + static_cast<std::size_t>(c)] =
            std::min(1.f, colour[3 * v + static_cast<std::size_t>(c)] +
                              palette[a % 6][c] * std::min(1.f, 2.f * contribution[a][v] / total));
  }
  ChannelDesc attribution{"attribution", 3, Linearisation::identity, 0.f, 1.f};
  const int index = version.add_channel(attribution);
  version.channels[static_cast<std::size_t>(index)].values = colour;
  write_mesh(version, o.out);

  std::printf(
      "{\"artists\":%u,\"faces\":%zu,\"vertices\":%zu,\"method\":\"%s\",\"rounds\":%u,\"strokes\":%"
      "u,"
      "\"merges\":%u,\"merge_ms_mean\":%.3f,\"merge_ms_max\":%.3f,\"vertices_per_diff\":%.0f,"
      "\"conflicting_edits\":%u,\"conflicting_fraction\":%.3f,\"out\":\"%s\"}\n",
      o.artists, version.face_count(), n, std::string(to_string(method)).c_str(), o.rounds, strokes,
      o.rounds, merge_sum / std::max(1u, o.rounds), merge_max,
      static_cast<double>(diff_vertices) / std::max(1u, o.rounds * o.artists), conflicting,
      strokes ? static_cast<double>(conflicting) / strokes : 0.0, o.out.c_str());
  return 0;
}

CLI::App* add_demo_command(CLI::App& app, DemoOptions& o) {
  CLI::App* demo = app.add_subcommand(
      "demo", "a collaborative session in this process: artists sculpt and paint, edits merge");
  demo->add_option("--artists", o.artists, "simulated artists")
      ->capture_default_str()
      ->check(CLI::Range(1u, 32u));
  demo->add_option("--faces", o.faces, "faces of the built-in sphere")
      ->capture_default_str()
      ->check(CLI::Range(20u, 20000000u));
  demo->add_option("--rounds", o.rounds, "sync rounds (one merge each)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 100000u));
  demo->add_option("--strokes", o.strokes_per_round, "strokes per artist per round")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1000u));
  demo->add_option("--method", o.method, "merge method")->capture_default_str();
  demo->add_option("-o,--out", o.out, "final mesh (PLY with materials and attribution colours)")
      ->capture_default_str();
  demo->add_option("--seed", o.seed, "stroke seed")->capture_default_str();
  return demo;
}

}  // namespace csculpt::cli
