// The Blender-authored merge cases (shared/eval/cases and the repository's tests/eval/cases,
// see shared/eval/README.md and tests/eval/CASES.md) checked in C++: each case's edits are
// merged with `full` through the SDK, scored exactly as shared/eval/score_merge.py scores the
// CLI's output (rel_rms against each ideal, the roughness ratio where there is none, the sum
// and weighted-translation baselines, new fold-overs), and the rules asserted on every
// case, as tests/eval/check_eval.py asserts them on the CLI:
//   - disjoint and identical edits: within 0.01 of every ideal, and so is every artist's support;
//   - a detail under a coarse edit: against the frame ideal below sum and weighted-translation;
//     against the stacked ideal within 1.5 x sum (where the stacked ideal is sum itself and the
//     frame ideal is not, no merge can meet both: there, no farther from it than the frame ideal);
//   - every artist keeps, on its own support, no less of its edit than sum does (against the
//     frame ideal, within the ideals' rounding at a support's rim);
//   - no more new fold-overs than sum; roughness at most 1.2 of the inputs' where there is no
//     ideal;
//   - every method merges every case to finite positions, whatever the order of the edits.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/folds.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;

using Point = std::array<double, 3>;
using Points = std::vector<Point>;

constexpr double kExactLimit = 0.01;     // disjoint and identical cases
constexpr double kStackFactor = 1.5;     // against the stacked ideal, times sum
constexpr double kArtistSlack = 0.005;   // the ideals' own rounding at the rim of a support
constexpr double kStackIsSum = 0.001;    // sum this close to the stacked ideal: it is sum
constexpr double kRoughnessLimit = 1.2;  // where there is no ideal

struct EvalCase {
  std::string name;
  std::string dir;  ///< the case's directory
  Mesh base;
  std::vector<Mesh> edits;      ///< a.ply, b.ply, ... in that order
  std::optional<Points> stack;  ///< ideal.ply: the edits stacked in Blender
  std::optional<Points> frame;  ///< ideal_frame.ply: the details carried in the surface's frame
  bool exact() const {
    return name.find("disjoint") != std::string::npos ||
           name.find("identical") != std::string::npos;
  }
};

Points points(const Mesh& m) {
  Points p(m.vertex_count());
  for (std::size_t v = 0; v < m.vertex_count(); ++v)
    p[v] = {double(m.positions[v].x), double(m.positions[v].y), double(m.positions[v].z)};
  return p;
}

double norm(const Point& a) {
  return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}
Point minus(const Point& a, const Point& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

std::optional<Points> read_ideal(const fs::path& path) {
  if (!fs::is_regular_file(path)) return std::nullopt;
  return points(read_mesh(path.string(), Faces::optional));
}

void read_cases_in(const fs::path& dir, std::vector<EvalCase>& out) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  std::vector<fs::path> dirs;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (fs::is_regular_file(e.path() / "base.ply")) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& d : dirs) {
    EvalCase c;
    c.name = d.filename().string();
    c.dir = d.string();
    c.base = read_mesh((d / "base.ply").string());
    for (char n = 'a'; n <= 'h'; ++n) {
      const fs::path p = d / (std::string(1, n) + ".ply");
      if (fs::is_regular_file(p)) c.edits.push_back(read_mesh(p.string()));
    }
    c.stack = read_ideal(d / "ideal.ply");
    c.frame = read_ideal(d / "ideal_frame.ply");
    out.push_back(std::move(c));
  }
}

/// Every case of both directories, read once (empty when neither is there).
const std::vector<EvalCase>& cases() {
  static const std::vector<EvalCase> all = [] {
    std::vector<EvalCase> out;
    read_cases_in(CSCULPT_EVAL_CASES, out);
    read_cases_in(CSCULPT_REPO_CASES, out);
    return out;
  }();
  return all;
}

#define SKIP_WITHOUT_CASES()                                                                      \
  if (cases().empty())                                                                            \
    GTEST_SKIP() << "no Blender cases at " << CSCULPT_EVAL_CASES << " or " << CSCULPT_REPO_CASES; \
  static_assert(true)

/// RMS distance to the ideal over the vertices `moved` moves (as score_merge.py counts them),
/// relative to their RMS displacement there.
double support_error(const Points& x, const Points& ideal, const std::vector<double>& moved) {
  const double cutoff =
      1e-6 * std::max(1e-12, *std::max_element(moved.begin(), moved.end())) + 1e-9;
  double err = 0, size = 0;
  for (std::size_t v = 0; v < x.size(); ++v) {
    if (!(moved[v] > cutoff)) continue;
    const double d = norm(minus(x[v], ideal[v]));
    err += d * d;
    size += moved[v] * moved[v];
  }
  return size > 0 ? std::sqrt(err / size) : 0.0;
}

/// Each edit's per-vertex displacement length.
std::vector<std::vector<double>> moved_by(const Points& base, const std::vector<Points>& edits) {
  std::vector<std::vector<double>> out;
  for (const Points& e : edits) {
    std::vector<double>& m = out.emplace_back(base.size());
    for (std::size_t v = 0; v < base.size(); ++v) m[v] = norm(minus(e[v], base[v]));
  }
  return out;
}

/// score_merge.py's rel_rms: the support error over the edit with the smallest RMS
/// displacement (over all vertices; the first of equals, like Python's min()).
double rel_rms(const Points& x, const Points& ideal,
               const std::vector<std::vector<double>>& moved) {
  std::size_t finest = 0;
  double finest_ms = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < moved.size(); ++k) {
    double ms = 0;
    for (double m : moved[k]) ms += m * m;
    if (ms < finest_ms) finest_ms = ms, finest = k;
  }
  return support_error(x, ideal, moved[finest]);
}

/// score_merge.py's roughness: over the 2000 most displaced vertices, the mean distance of
/// each displacement from the mean displacement of its 12 nearest base neighbours.
double roughness(const Points& disp, const Points& base) {
  const std::size_t n = base.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<double> mag(n);
  for (std::size_t v = 0; v < n; ++v) mag[v] = norm(disp[v]);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return mag[a] < mag[b]; });
  const std::size_t take = std::min<std::size_t>(2000, n);
  std::vector<std::pair<double, std::size_t>> d2(n);
  double total = 0;
  for (std::size_t k = n - take; k < n; ++k) {
    const std::size_t i = order[k];
    for (std::size_t v = 0; v < n; ++v) {
      const Point e = minus(base[v], base[i]);
      d2[v] = {e[0] * e[0] + e[1] * e[1] + e[2] * e[2], v};
    }
    const std::size_t nn = std::min<std::size_t>(13, n);
    std::partial_sort(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(nn), d2.end());
    Point mean{0, 0, 0};
    for (std::size_t j = 1; j < nn; ++j)
      for (std::size_t c = 0; c < 3; ++c) mean[c] += disp[d2[j].second][c];
    for (double& m : mean) m /= static_cast<double>(nn - 1);
    total += norm(minus(disp[i], mean));
  }
  return total / static_cast<double>(take);
}

/// One result's scores against one ideal.
struct Against {
  double full = 0, sum = 0, weighted = 0;       ///< rel_rms over the finest edit's support
  std::vector<double> artist_full, artist_sum;  ///< each artist's support error
};

struct Scored {
  std::optional<Against> stack, frame;
  double ideals_apart = 0;       ///< the frame ideal's rel_rms against the stacked one
  double full_roughness = 0;     ///< roughness ratio to the roughest edit, where no ideal
  std::uint32_t full_folds = 0;  ///< new fold-overs (csculpt/folds.h)
  std::uint32_t sum_folds = 0;
};

/// The scorer's own baselines: the edits' displacements added, and averaged weighted by
/// their lengths.
void baselines(const Points& base, const std::vector<Points>& edits, Points& sum,
               Points& weighted) {
  sum = base;
  weighted = base;
  for (std::size_t v = 0; v < base.size(); ++v) {
    Point total{0, 0, 0}, wsum{0, 0, 0};
    double w = 0;
    for (const Points& e : edits) {
      const Point d = minus(e[v], base[v]);
      const double m = norm(d);
      for (std::size_t k = 0; k < 3; ++k) total[k] += d[k], wsum[k] += m * d[k];
      w += m;
    }
    if (!(w > 0)) w = 1;
    for (std::size_t k = 0; k < 3; ++k) sum[v][k] += total[k], weighted[v][k] += wsum[k] / w;
  }
}

Diff diff_to(const Mesh& base, const Points& x) {
  Mesh m = base;
  for (std::size_t v = 0; v < x.size(); ++v)
    m.positions[v] = {float(x[v][0]), float(x[v][1]), float(x[v][2])};
  return capture_diff(base, m);
}

/// One result's scores against `ideal`: over the finest edit's support and each artist's.
Against score_against(const Points& ideal, const Points& full, const Points& sum,
                      const Points& weighted, const std::vector<std::vector<double>>& moved) {
  Against a{rel_rms(full, ideal, moved),
            rel_rms(sum, ideal, moved),
            rel_rms(weighted, ideal, moved),
            {},
            {}};
  for (const auto& m : moved) {
    a.artist_full.push_back(support_error(full, ideal, m));
    a.artist_sum.push_back(support_error(sum, ideal, m));
  }
  return a;
}

/// The merge's roughness over the roughest edit's (score_merge.py's ratio).
double roughness_ratio(const Points& full, const Points& base, const std::vector<Points>& edits) {
  auto displacement = [&](const Points& x) {
    Points d(x.size());
    for (std::size_t v = 0; v < x.size(); ++v) d[v] = minus(x[v], base[v]);
    return d;
  };
  double rough_in = 0;
  for (const Points& e : edits) rough_in = std::max(rough_in, roughness(displacement(e), base));
  return roughness(displacement(full), base) / rough_in;
}

Scored score_case(const EvalCase& c) {
  const Hierarchy hierarchy = Hierarchy::build(c.base);
  Merger merger(hierarchy);
  std::vector<Diff> diffs;
  for (const Mesh& e : c.edits) diffs.push_back(capture_diff(c.base, e));
  const Diff merged = merger.merge(c.base, diffs, MergeMethod::full);
  Mesh full_mesh = c.base;
  apply_diff(merged, full_mesh);

  const Points base = points(c.base), full = points(full_mesh);
  std::vector<Points> edits;
  for (const Mesh& e : c.edits) edits.push_back(points(e));
  Points sum, weighted;
  baselines(base, edits, sum, weighted);
  const auto moved = moved_by(base, edits);

  Scored s;
  if (c.stack) s.stack = score_against(*c.stack, full, sum, weighted, moved);
  if (c.frame) s.frame = score_against(*c.frame, full, sum, weighted, moved);
  if (c.stack && c.frame) s.ideals_apart = rel_rms(*c.frame, *c.stack, moved);
  if (!c.stack) s.full_roughness = roughness_ratio(full, base, edits);
  std::vector<const Diff*> inputs;
  for (const Diff& d : diffs) inputs.push_back(&d);
  s.full_folds = count_new_folds(c.base, inputs, merged);
  s.sum_folds = count_new_folds(c.base, inputs, diff_to(c.base, sum));
  std::printf(
      "[ eval     ] %-36s full %.4f / %.4f (stack / frame)  sum %.4f / %.4f  folds %u / %u\n",
      c.name.c_str(), s.stack ? s.stack->full : -1.0, s.frame ? s.frame->full : -1.0,
      s.stack ? s.stack->sum : -1.0, s.frame ? s.frame->sum : -1.0, s.full_folds, s.sum_folds);
  return s;
}

const Scored& scored(const EvalCase& c) {
  static std::map<std::string, Scored> cache;  // by directory: names may repeat across sets
  auto it = cache.find(c.dir);
  if (it == cache.end()) it = cache.emplace(c.dir, score_case(c)).first;
  return it->second;
}

/// Runs `check` on every case for which `applies` holds; skips, saying so, when none does
/// (the cases without an ideal are all in shared/eval/cases).
template <class Applies, class Check>
void for_cases(const char* kind, Applies applies, Check check) {
  int found = 0;
  for (const EvalCase& c : cases()) {
    if (!applies(c)) continue;
    ++found;
    SCOPED_TRACE(c.name);
    check(c, scored(c));
  }
  if (found == 0) GTEST_SKIP() << "no " << kind << " case among the cases read";
}

TEST(EvalCases, DisjointAndIdenticalEditsComeBackExact) {
  SKIP_WITHOUT_CASES();
  for_cases(
      "disjoint or identical", [](const EvalCase& c) { return c.exact(); },
      [](const EvalCase&, const Scored& s) {
        for (const auto& a : {s.stack, s.frame}) {
          if (!a) continue;
          EXPECT_LE(a->full, kExactLimit);
          for (double e : a->artist_full) EXPECT_LE(e, kExactLimit) << "an artist's support";
        }
      });
}

bool detail_under_coarse(const EvalCase& c) {
  return c.frame && !c.exact();
}

TEST(EvalCases, ADetailBeatsSumAndWeightedTranslationAgainstTheFrameIdeal) {
  SKIP_WITHOUT_CASES();
  for_cases("detail under a coarse edit", detail_under_coarse,
            [](const EvalCase&, const Scored& s) {
              EXPECT_LT(s.frame->full, s.frame->sum) << "full vs (sum)";
              EXPECT_LT(s.frame->full, s.frame->weighted) << "full vs (weighted-translation)";
            });
}

TEST(EvalCases, ADetailStaysWithinOneAndAHalfSumOfTheStackedIdeal) {
  SKIP_WITHOUT_CASES();
  for_cases(
      "detail under a coarse edit",
      [](const EvalCase& c) { return detail_under_coarse(c) && c.stack; },
      [](const EvalCase&, const Scored& s) {
        if (s.stack->sum <= kStackIsSum && s.ideals_apart > kExactLimit) {
          // The stacked ideal is sum while the frame ideal is not: the frame rule forbids what
          // this one asks. Still no farther from it than the frame ideal itself.
          EXPECT_LE(s.stack->full, s.ideals_apart) << "full vs the frame ideal's distance";
          return;
        }
        EXPECT_LE(s.stack->full, kStackFactor * s.stack->sum) << "full vs 1.5 x (sum)";
      });
}

TEST(EvalCases, EveryArtistKeepsNoLessThanSumKeeps) {
  SKIP_WITHOUT_CASES();
  for_cases("detail under a coarse edit", detail_under_coarse,
            [](const EvalCase&, const Scored& s) {
              const Against& a = *s.frame;
              for (std::size_t k = 0; k < a.artist_full.size(); ++k)
                EXPECT_LE(a.artist_full[k], a.artist_sum[k] + kArtistSlack) << "artist " << k;
            });
}

TEST(EvalCases, NoMoreNewFoldsThanSum) {
  SKIP_WITHOUT_CASES();
  for_cases(
      "any", [](const EvalCase&) { return true; },
      [](const EvalCase&, const Scored& s) { EXPECT_LE(s.full_folds, s.sum_folds); });
}

TEST(EvalCases, FullIsNotRougherThanTheInputsWhereThereIsNoIdeal) {
  SKIP_WITHOUT_CASES();
  for_cases(
      "without an ideal", [](const EvalCase& c) { return !c.stack; },
      [](const EvalCase&, const Scored& s) {
        EXPECT_TRUE(std::isfinite(s.full_roughness));
        EXPECT_LE(s.full_roughness, kRoughnessLimit) << "seams or spikes";
      });
}

TEST(EvalCases, EveryCaseMergesFiniteAndOrderIndependent) {
  SKIP_WITHOUT_CASES();
  for (const EvalCase& c : cases()) {
    SCOPED_TRACE(c.name);
    ASSERT_GE(c.edits.size(), 2u);
    const Hierarchy hierarchy = Hierarchy::build(c.base);
    Merger merger(hierarchy);
    std::vector<Diff> diffs;
    for (const Mesh& e : c.edits) diffs.push_back(capture_diff(c.base, e));
    std::vector<Diff> swapped(diffs.rbegin(), diffs.rend());
    for (MergeMethod m : all_merge_methods()) {
      const Diff forward = merger.merge(c.base, diffs, m);
      const Diff backward = merger.merge(c.base, swapped, m);
      EXPECT_TRUE(forward == backward) << to_string(m) << ": reversed order differs (digest "
                                       << digest(backward) << " vs " << digest(forward) << ")";
      for (float x : forward.positions.values) ASSERT_TRUE(std::isfinite(x)) << to_string(m);
    }
  }
}

}  // namespace
}  // namespace csculpt
