// The Blender-authored merge cases (shared/eval/cases, see shared/eval/README.md) checked in
// C++: each case's edits are merged with `full` through the SDK and scored exactly as
// shared/eval/score_merge.py scores the CLI's output (rel_rms against ideal.ply, the
// roughness ratio where there is no ideal, the sum and weighted-translation baselines), and
// the README's "what good looks like" rules asserted, as tests/eval/check_eval.py does.
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
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"

namespace csculpt {
namespace {

namespace fs = std::filesystem;

using Points = std::vector<std::array<double, 3>>;

struct EvalCase {
  std::string name;
  Mesh base;
  std::vector<Mesh> edits;  ///< a.ply, b.ply, ... in that order
  bool has_ideal = false;
  Mesh ideal;
};

Points points(const Mesh& m) {
  Points p(m.vertex_count());
  for (std::size_t v = 0; v < m.vertex_count(); ++v)
    p[v] = {double(m.positions[v].x), double(m.positions[v].y), double(m.positions[v].z)};
  return p;
}

double norm(const std::array<double, 3>& a) {
  return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}
std::array<double, 3> minus(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

/// Every case directory, read once (empty when the cases are not there).
const std::vector<EvalCase>& cases() {
  static const std::vector<EvalCase> all = [] {
    std::vector<EvalCase> out;
    const fs::path dir = CSCULPT_EVAL_CASES;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) return out;
    std::vector<fs::path> dirs;
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (fs::is_regular_file(e.path() / "base.ply")) dirs.push_back(e.path());
    std::sort(dirs.begin(), dirs.end());
    for (const fs::path& d : dirs) {
      EvalCase c;
      c.name = d.filename().string();
      c.base = read_mesh((d / "base.ply").string());
      for (char n = 'a'; n <= 'h'; ++n) {
        const fs::path p = d / (std::string(1, n) + ".ply");
        if (fs::is_regular_file(p)) c.edits.push_back(read_mesh(p.string()));
      }
      if (fs::is_regular_file(d / "ideal.ply")) {
        c.has_ideal = true;
        c.ideal = read_mesh((d / "ideal.ply").string());
      }
      out.push_back(std::move(c));
    }
    return out;
  }();
  return all;
}

const EvalCase* find_case(const std::string& name) {
  for (const EvalCase& c : cases())
    if (c.name == name) return &c;
  return nullptr;
}

#define SKIP_WITHOUT_CASES()                                                         \
  if (cases().empty()) GTEST_SKIP() << "no Blender cases at " << CSCULPT_EVAL_CASES; \
  static_assert(true)

/// score_merge.py's rel_rms: RMS distance to the ideal over the support of the edit with the
/// smallest RMS displacement (over all vertices), relative to that edit's RMS size there.
double rel_rms(const Points& x, const Points& ideal, const Points& base,
               const std::vector<Points>& edits) {
  const std::size_t n = base.size();
  std::vector<double> small;
  double small_rms = std::numeric_limits<double>::infinity();
  for (const Points& e : edits) {
    std::vector<double> nrm(n);
    double sum2 = 0;
    for (std::size_t v = 0; v < n; ++v) {
      nrm[v] = norm(minus(e[v], base[v]));
      sum2 += nrm[v] * nrm[v];
    }
    const double rms = std::sqrt(sum2 / static_cast<double>(n));
    if (rms < small_rms) {  // first minimum, like Python's min()
      small_rms = rms;
      small = std::move(nrm);
    }
  }
  const double cutoff =
      1e-6 * std::max(1e-12, *std::max_element(small.begin(), small.end())) + 1e-9;
  double err = 0, size = 0;
  std::size_t count = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (!(small[v] > cutoff)) continue;
    const double d = norm(minus(x[v], ideal[v]));
    err += d * d;
    size += small[v] * small[v];
    ++count;
  }
  if (count == 0) return 0;
  return std::sqrt(err / static_cast<double>(count)) / std::sqrt(size / static_cast<double>(count));
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
      const auto e = minus(base[v], base[i]);
      d2[v] = {e[0] * e[0] + e[1] * e[1] + e[2] * e[2], v};
    }
    const std::size_t nn = std::min<std::size_t>(13, n);
    std::partial_sort(d2.begin(), d2.begin() + static_cast<std::ptrdiff_t>(nn), d2.end());
    std::array<double, 3> mean{0, 0, 0};
    for (std::size_t j = 1; j < nn; ++j)
      for (int c = 0; c < 3; ++c)
        mean[static_cast<std::size_t>(c)] += disp[d2[j].second][static_cast<std::size_t>(c)];
    for (double& m : mean) m /= static_cast<double>(nn - 1);
    total += norm(minus(disp[i], mean));
  }
  return total / static_cast<double>(take);
}

struct Scored {
  Mesh full;                                           ///< base with the merged diff applied
  Points sum, weighted;                                ///< the scorer's own baselines
  double full_err = 0, sum_err = 0, weighted_err = 0;  ///< rel_rms where there is an ideal
  double full_roughness = 0;                           ///< roughness ratio where there is none
};

Scored score_case(const EvalCase& c) {
  const Hierarchy hierarchy = Hierarchy::build(c.base);
  Merger merger(hierarchy);
  std::vector<Diff> diffs;
  for (const Mesh& e : c.edits) diffs.push_back(capture_diff(c.base, e));
  Scored s;
  s.full = c.base;
  apply_diff(merger.merge(c.base, diffs, MergeMethod::full), s.full);

  const Points base = points(c.base);
  std::vector<Points> edits;
  for (const Mesh& e : c.edits) edits.push_back(points(e));
  const std::size_t n = base.size();
  s.sum = base;
  s.weighted = base;
  for (std::size_t v = 0; v < n; ++v) {
    std::array<double, 3> total{0, 0, 0}, weighted{0, 0, 0};
    double w = 0;
    for (const Points& e : edits) {
      const auto d = minus(e[v], base[v]);
      const double m = norm(d);
      for (std::size_t k = 0; k < 3; ++k) {
        total[k] += d[k];
        weighted[k] += m * d[k];
      }
      w += m;
    }
    if (!(w > 0)) w = 1;
    for (std::size_t k = 0; k < 3; ++k) {
      s.sum[v][k] += total[k];
      s.weighted[v][k] += weighted[k] / w;
    }
  }
  const Points full = points(s.full);
  if (c.has_ideal) {
    const Points ideal = points(c.ideal);
    s.full_err = rel_rms(full, ideal, base, edits);
    s.sum_err = rel_rms(s.sum, ideal, base, edits);
    s.weighted_err = rel_rms(s.weighted, ideal, base, edits);
    std::printf("[ eval     ] %-28s rel_err full %.4f  (sum) %.4f  (weighted-translation) %.4f\n",
                c.name.c_str(), s.full_err, s.sum_err, s.weighted_err);
  } else {
    auto displacement = [&](const Points& x) {
      Points d(n);
      for (std::size_t v = 0; v < n; ++v) d[v] = minus(x[v], base[v]);
      return d;
    };
    double rough_in = 0;
    for (const Points& e : edits) rough_in = std::max(rough_in, roughness(displacement(e), base));
    s.full_roughness = roughness(displacement(full), base) / rough_in;
    std::printf("[ eval     ] %-28s roughness full %.3f\n", c.name.c_str(), s.full_roughness);
  }
  return s;
}

const Scored& scored(const EvalCase& c) {
  static std::map<std::string, Scored> cache;
  auto it = cache.find(c.name);
  if (it == cache.end()) it = cache.emplace(c.name, score_case(c)).first;
  return it->second;
}

TEST(EvalCases, FullKeepsDisjointAndIdenticalEditsWhole) {
  SKIP_WITHOUT_CASES();
  for (const std::string name : {"disjoint_sphere", "identical_capsule"}) {
    const EvalCase* c = find_case(name);
    ASSERT_NE(c, nullptr) << name << " is missing from " << CSCULPT_EVAL_CASES;
    ASSERT_TRUE(c->has_ideal) << name;
    const Scored& s = scored(*c);
    EXPECT_LT(s.full_err, 0.05) << name << ": full rel_err";
    RecordProperty(name, std::to_string(s.full_err));
  }
}

TEST(EvalCases, FullCarriesTheDetailThroughBendAndTwist) {
  SKIP_WITHOUT_CASES();
  int rotational = 0;
  for (const EvalCase& c : cases()) {
    if (c.name.find("bend") == std::string::npos && c.name.find("twist") == std::string::npos)
      continue;
    ++rotational;
    ASSERT_TRUE(c.has_ideal) << c.name;
    const Scored& s = scored(c);
    EXPECT_LT(s.full_err, s.sum_err) << c.name << ": full vs (sum)";
    EXPECT_LT(s.full_err, s.weighted_err) << c.name << ": full vs (weighted-translation)";
    RecordProperty(c.name, std::to_string(s.full_err) + " sum " + std::to_string(s.sum_err) +
                               " weighted " + std::to_string(s.weighted_err));
  }
  EXPECT_GT(rotational, 0) << "no bend or twist case";
}

TEST(EvalCases, FullIsNotRougherThanTheInputsOnGrabVsSmooth) {
  SKIP_WITHOUT_CASES();
  int found = 0;
  for (const EvalCase& c : cases()) {
    if (c.name.find("grab_vs_smooth") == std::string::npos) continue;
    ++found;
    const Scored& s = scored(c);
    EXPECT_TRUE(std::isfinite(s.full_roughness)) << c.name;
    EXPECT_LE(s.full_roughness, 1.0) << c.name << ": seams or spikes";
    RecordProperty(c.name, std::to_string(s.full_roughness));
  }
  EXPECT_GT(found, 0) << "no grab_vs_smooth case";
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
      EXPECT_TRUE(forward == backward) << to_string(m) << ": b,a differs from a,b (digest "
                                       << digest(backward) << " vs " << digest(forward) << ")";
      for (float x : forward.positions.values) ASSERT_TRUE(std::isfinite(x)) << to_string(m);
    }
  }
}

}  // namespace
}  // namespace csculpt
