// csculpt: command-line front end of the SDK (merge, hierarchy, diff, bench).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "bench_merge.h"
#include "bench_session.h"
#include "bench_wire.h"
#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/testkit/scenarios.h"
#include "demo.h"
#include "explain.h"
#include "peer_command.h"

namespace {

using namespace csculpt;

/// "full, paper-blend, ...": every method the SDK knows, so the help cannot fall behind.
std::string method_names() {
  std::string names;
  for (MergeMethod m : all_merge_methods())
    names += (names.empty() ? "" : ", ") + std::string(to_string(m));
  return names;
}

struct MergeCommand {
  std::string base, out, method = "full";
  std::vector<std::string> edits;
  std::uint32_t k = 7;
  bool explain = false;
  std::vector<std::string> ideals;
};

/// Hierarchy::build, with running out of memory reported as the README's error line naming the
/// file it was building for.
Hierarchy build_hierarchy_of(const Mesh& mesh, const HierarchyOptions& options,
                             const std::string& path) {
  try {
    return Hierarchy::build(mesh, options);
  } catch (const std::bad_alloc&) {
    throw OutOfMemory(path + ": out of memory building the hierarchy of its " +
                      std::to_string(mesh.vertex_count()) + " vertices");
  }
}

int run_merge(const MergeCommand& c) {
  const MergeMethod method = merge_method_from_string(c.method);
  const Mesh base = read_mesh(c.base);
  std::vector<Diff> diffs;
  for (const std::string& path : c.edits) {
    const Mesh edit = read_mesh(path);
    try {
      diffs.push_back(capture_diff(base, edit));
    } catch (const InvalidInput& e) {
      throw InvalidInput(path + ": " + e.what() + " (compared with " + c.base + ")");
    }
  }
  HierarchyOptions options;
  options.max_parents = c.k;
  const Hierarchy hierarchy = build_hierarchy_of(base, options, c.base);
  Merger merger(hierarchy);
  const auto t0 = std::chrono::steady_clock::now();
  const Diff merged = merger.merge(base, diffs, method);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  Mesh result = base;
  apply_diff(merged, result);
  // Before writing: a bad --ideal fails the command without leaving an output behind.
  const std::string explanation =
      c.explain ? csculpt::cli::explain_merge(
                      {base, c.edits, diffs, merged, result, hierarchy, method, c.ideals})
                : "";
  write_mesh(result, c.out);
  std::fprintf(stderr, "merged %zu edits of %zu vertices with %s in %.2f ms -> %s\n", diffs.size(),
               base.vertex_count(), std::string(to_string(method)).c_str(), ms, c.out.c_str());
  if (c.explain) std::printf("%s\n", explanation.c_str());
  return 0;
}

int run_hierarchy(const std::string& path, std::uint32_t k) {
  const Mesh mesh = read_mesh(path);
  HierarchyOptions options;
  options.max_parents = k;
  const auto t0 = std::chrono::steady_clock::now();
  const Hierarchy h = build_hierarchy_of(mesh, options, path);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::string json = to_json(h.stats());
  json.pop_back();
  std::printf("%s,\"k\":%u,\"build_ms\":%.3f,\"digest\":\"%016llx\"}\n", json.c_str(), k, ms,
              static_cast<unsigned long long>(h.digest()));
  return 0;
}

int run_diff(const std::string& base_path, const std::string& edited_path) {
  const Mesh base = read_mesh(base_path);
  const Mesh edited = read_mesh(edited_path);
  Diff d;
  try {
    d = capture_diff(base, edited);
  } catch (const InvalidInput& e) {
    throw InvalidInput(edited_path + ": " + e.what() + " (compared with " + base_path + ")");
  }
  std::printf("%s\n", to_json(diff_stats(d, base)).c_str());
  return 0;
}

int run_scenarios(std::uint32_t faces, bool json) {
  const std::vector<Scenario> scenarios = make_scenarios(faces);
  if (!json) {
    std::printf("| scenario |");
    for (MergeMethod m : all_merge_methods())
      std::printf(" %s |", std::string(to_string(m)).c_str());
    std::printf("\n|---|");
    for (std::size_t i = 0; i < all_merge_methods().size(); ++i) std::printf("---|");
    std::printf("\n");
  }
  for (const Scenario& sc : scenarios) {
    const Hierarchy hierarchy = Hierarchy::build(sc.base);
    Merger merger(hierarchy);
    std::vector<Diff> diffs;
    for (const Mesh& e : sc.edits) diffs.push_back(capture_diff(sc.base, e));
    if (!json) std::printf("| %s |", sc.name.c_str());
    for (MergeMethod m : all_merge_methods()) {
      Mesh merged = sc.base;
      apply_diff(merger.merge(sc.base, diffs, m), merged);
      const ScenarioScore s = score(sc, merged, hierarchy.topology());
      if (json) {
        std::printf(
            "{\"scenario\":\"%s\",\"method\":\"%s\",\"faces\":%zu,\"rel_err\":%.5f,"
            "\"roughness\":%.4f,\"channel_err\":%.5f}\n",
            sc.name.c_str(), std::string(to_string(m)).c_str(), sc.base.face_count(), s.rel_err,
            s.roughness, s.channel_err);
      } else if (sc.has_expected) {
        bool has_channels = false;
        for (const Mesh& e : sc.edits)
          for (std::size_t c = 0; c < e.channels.size(); ++c)
            if (e.channels[c].values != sc.base.channels[c].values) has_channels = true;
        const bool has_positions = s.rel_err > 0 || !has_channels;
        if (has_positions && has_channels)
          std::printf(" %.3f / %.3f |", s.rel_err, s.channel_err);
        else if (has_channels)
          std::printf(" %.4f |", s.channel_err);
        else
          std::printf(" %.3f |", s.rel_err);
      } else {
        std::printf(" r=%.2f |", s.roughness);
      }
    }
    if (!json) std::printf("\n");
  }
  return 0;
}

CLI::App* add_merge_command(CLI::App& app, MergeCommand& mc) {
  auto* merge = app.add_subcommand("merge", "N-way merge of edits of BASE into OUT");
  merge->add_option("base", mc.base, "the last agreed mesh")->required()->check(CLI::ExistingFile);
  merge->add_option("edits", mc.edits, "two or more edited meshes (same connectivity)")
      ->required()
      ->expected(2, -1)
      ->check(CLI::ExistingFile);
  merge->add_option("-o,--out", mc.out, "merged mesh to write (.ply or .obj)")->required();
  merge->add_option("--method", mc.method, method_names())->capture_default_str();
  merge->add_option("--k", mc.k, "blended parents per node (paper: 7)")
      ->capture_default_str()
      ->check(CLI::Range(1, 32));
  CLI::Option* explain = merge->add_flag(
      "--explain", mc.explain,
      "print a JSON diagnosis of the merge: each edit's support and size, new folds, and with "
      "--ideal the error per artist, per part of the mesh, per hierarchy level, worst vertices");
  merge
      ->add_option("--ideal", mc.ideals,
                   "a mesh the merge should have given (same vertices), scored as "
                   "shared/eval/score_merge.py does; repeatable")
      ->check(CLI::ExistingFile)
      ->needs(explain);
  return merge;
}

/// `hierarchy` and `diff`: statistics of one mesh or one edit.
struct InspectCommands {
  std::string mesh_path, base, edited;
  std::uint32_t k = 7;
  CLI::App* hierarchy = nullptr;
  CLI::App* diff = nullptr;

  void add(CLI::App& app) {
    hierarchy = app.add_subcommand("hierarchy", "hierarchy statistics of MESH (JSON)");
    hierarchy->add_option("mesh", mesh_path, "mesh file")->required()->check(CLI::ExistingFile);
    hierarchy->add_option("--k", k, "blended parents per node")
        ->capture_default_str()
        ->check(CLI::Range(1, 32));
    diff = app.add_subcommand("diff", "statistics of the edit from BASE to EDITED (JSON)");
    diff->add_option("base", base, "base mesh")->required()->check(CLI::ExistingFile);
    diff->add_option("edited", edited, "edited mesh")->required()->check(CLI::ExistingFile);
  }
};

struct ScenarioCommand {
  std::uint32_t faces = 40000;
  bool json = false;
};

CLI::App* add_scenarios_command(CLI::App& app, ScenarioCommand& sc) {
  auto* scenarios = app.add_subcommand(
      "scenarios",
      "error of every merge method on the built-in scenarios (Markdown table or JSON)");
  scenarios->add_option("--faces", sc.faces, "sphere resolution")
      ->capture_default_str()
      ->check(CLI::Range(500u, 5000000u));
  scenarios->add_flag("--json", sc.json, "one JSON object per scenario and method");
  return scenarios;
}

CLI::App* add_bench_merge_command(CLI::App& bench, csculpt::cli::BenchMergeOptions& bo) {
  auto* bench_merge = bench.add_subcommand("merge", "merge speed on a built-in sphere");
  bench_merge->add_option("--faces", bo.faces, "approximate face count")
      ->capture_default_str()
      ->check(CLI::Range(20u, 50000000u));
  bench_merge->add_option("--users", bo.users, "concurrent edits")
      ->capture_default_str()
      ->check(CLI::Range(std::uint32_t{1}, static_cast<std::uint32_t>(max_merge_diffs)));
  bench_merge->add_option("--method", bo.method, method_names())->capture_default_str();
  bench_merge->add_option("--k", bo.k, "blended parents per node")
      ->capture_default_str()
      ->check(CLI::Range(1u, 32u));
  bench_merge->add_option("--repeat", bo.repeat, "timed repetitions (median reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 10000u));
  bench_merge->add_option("--edited-fraction", bo.edited_fraction, "vertices each user touches")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  bench_merge->add_flag("--paint", bo.paint, "add material channels and paint strokes");
  bench_merge->add_option("--seed", bo.seed, "stroke seed")->capture_default_str();
  return bench_merge;
}

CLI::App* add_bench_wire_command(CLI::App& bench, csculpt::cli::BenchWireOptions& bw) {
  auto* bench_wire = bench.add_subcommand(
      "wire", "size and encode/decode time of one stroke's diff message, per stroke kind");
  bench_wire->add_option("--faces", bw.faces, "approximate face count")
      ->capture_default_str()
      ->check(CLI::Range(20u, 50000000u));
  bench_wire->add_option("--touched", bw.touched, "vertices the stroke touches (about)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 50000000u));
  bench_wire
      ->add_option("--tolerance", bw.tolerance,
                   "position tolerance, fraction of the bounding-box diagonal")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  bench_wire->add_option("--repeat", bw.repeat, "timed repetitions (median reported)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 10000u));
  return bench_wire;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"cSculpt: merge concurrent sculpting and painting edits of one mesh"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "csculpt " CSCULPT_VERSION_STRING);

  MergeCommand mc;
  CLI::App* merge = add_merge_command(app, mc);
  InspectCommands inspect;
  inspect.add(app);
  // Session commands register their own options (cli/demo.cpp, cli/peer_command.cpp,
  // cli/bench_session.cpp).
  csculpt::cli::DemoOptions demo_options;
  CLI::App* demo = csculpt::cli::add_demo_command(app, demo_options);
  csculpt::cli::PeerCommandOptions peer_options;
  CLI::App* peer = csculpt::cli::add_peer_command(app, peer_options);
  ScenarioCommand sc;
  CLI::App* scenarios = add_scenarios_command(app, sc);

  auto* bench = app.add_subcommand("bench", "benchmarks (one JSON object per result)");
  bench->require_subcommand(1);
  csculpt::cli::BenchMergeOptions bo;
  CLI::App* bench_merge = add_bench_merge_command(*bench, bo);
  csculpt::cli::BenchWireOptions bw;
  CLI::App* bench_wire = add_bench_wire_command(*bench, bw);
  csculpt::cli::BenchSessionOptions bench_session_options;
  CLI::App* bench_session = csculpt::cli::add_bench_session_command(*bench, bench_session_options);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version are "errors" that exit 0; every real one gets the README's
    // contract: one `csculpt: error:` line and exit 1, like a bad file found later.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "csculpt: error: %s (csculpt --help for usage)\n", e.what());
    return 1;
  }
  try {
    if (*merge) return run_merge(mc);
    if (*inspect.hierarchy) return run_hierarchy(inspect.mesh_path, inspect.k);
    if (*inspect.diff) return run_diff(inspect.base, inspect.edited);
    if (*demo) return csculpt::cli::run_demo(demo_options);
    if (*peer) return csculpt::cli::run_peer(peer_options);
    if (*bench_session) return csculpt::cli::bench_session(bench_session_options);
    if (*scenarios) return run_scenarios(sc.faces, sc.json);
    if (*bench_merge) return csculpt::cli::bench_merge(bo);
    if (*bench_wire) return csculpt::cli::bench_wire(bw);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "csculpt: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
