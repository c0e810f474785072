// The merge of paper §3.1 against its stated properties (identity, idempotence,
// commutativity, continuity, generality), rotational invariance, the built-in scenarios,
// material channels and input validation, on the built-in sphere and on real meshes: the
// Blender cases' base meshes (icosphere, capsule, Suzanne) and assimp's Spider STL
// (18 components, irregular triangles).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/io.h"
#include "csculpt/merge.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/testkit/scenarios.h"
#include "csculpt/vec3.h"
#include "test_meshes.h"
#include "test_strokes.h"
#include "test_support.h"

namespace csculpt {
using csculpt::test::invalid_input_message;
using csculpt::test::kind_name;

namespace {

namespace fs = std::filesystem;
using Kind = Stroke::Kind;

constexpr std::array<Kind, 7> kKinds = {Kind::grab, Kind::inflate, Kind::detail, Kind::twist,
                                        Kind::bend, Kind::smooth,  Kind::paint};

std::string method_name(MergeMethod m) {
  return std::string(to_string(m));
}

// ---- measurements (double precision) ----------------------------------------------------

double dist(Vec3f a, Vec3f b) {
  const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}
bool finite(Vec3f p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

struct Box {
  Vec3f lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
           std::numeric_limits<float>::infinity()};
  Vec3f hi{-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
           -std::numeric_limits<float>::infinity()};
  void add(Vec3f p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  /// How far p lies outside the box (0 inside).
  double outside(Vec3f p) const {
    const double dx = std::max({0.0, double(lo.x) - p.x, double(p.x) - hi.x});
    const double dy = std::max({0.0, double(lo.y) - p.y, double(p.y) - hi.y});
    const double dz = std::max({0.0, double(lo.z) - p.z, double(p.z) - hi.z});
    return std::sqrt(dx * dx + dy * dy + dz * dz);
  }
  Vec3f centre() const { return csculpt::scale(csculpt::add(lo, hi), 0.5f); }
};
Box bbox(const std::vector<Vec3f>& ps) {
  Box b;
  for (const Vec3f& p : ps) b.add(p);
  return b;
}

// ---- the meshes the properties are checked on --------------------------------------------

struct Subject {
  std::string name;
  Mesh base;  ///< with the built-in material channels, non-constant
  Hierarchy hierarchy;
  double diag = 0;
  Vec3f centre{};
  Vec3f axis{};  ///< the bbox's longest axis
};

std::unique_ptr<Subject> make_subject(std::string name, Mesh mesh) {
  auto s = std::make_unique<Subject>();
  s->name = std::move(name);
  if (mesh.find_channel("albedo") < 0) {
    // test::add_material_channels expects a unit-sized mesh around the origin: fill the
    // channels from normalised positions so every value stays inside [0, 1]
    Mesh unit_mesh = mesh;
    const Box b = bbox(mesh.positions);
    const Vec3f c = b.centre();
    const float half = 0.5f * bbox_diagonal(mesh.positions);
    for (Vec3f& p : unit_mesh.positions) p = scale(sub(p, c), 1.f / half);
    test::add_material_channels(unit_mesh);
    mesh.channels = std::move(unit_mesh.channels);
  }
  s->base = std::move(mesh);
  s->hierarchy = Hierarchy::build(s->base);
  s->diag = bbox_diagonal(s->base.positions);
  const Box b = bbox(s->base.positions);
  s->centre = b.centre();
  const Vec3f ext = sub(b.hi, b.lo);
  s->axis = ext.x >= ext.y && ext.x >= ext.z ? Vec3f{1, 0, 0}
            : ext.y >= ext.z                 ? Vec3f{0, 1, 0}
                                             : Vec3f{0, 0, 1};
  return s;
}

/// The built-in sphere (20480 faces) and every distinct base.ply of the Blender cases.
const std::vector<std::unique_ptr<Subject>>& sphere_and_eval_subjects() {
  static const auto subjects = [] {
    std::vector<std::unique_ptr<Subject>> out;
    out.push_back(make_subject("sphere20k", make_sphere(20000)));
    const fs::path cases = CSCULPT_EVAL_CASES;
    std::error_code ec;
    if (fs::is_directory(cases, ec)) {
      std::vector<fs::path> dirs;
      for (const auto& e : fs::directory_iterator(cases, ec))
        if (fs::is_regular_file(e.path() / "base.ply")) dirs.push_back(e.path());
      std::sort(dirs.begin(), dirs.end());
      std::vector<Mesh> seen;
      for (const fs::path& d : dirs) {
        Mesh m = read_mesh((d / "base.ply").string());
        bool dup = false;
        for (const Mesh& o : seen)
          dup = dup || (o.positions == m.positions && o.triangles == m.triangles);
        if (dup) continue;
        seen.push_back(m);
        out.push_back(make_subject(d.filename().string() + "/base.ply", std::move(m)));
      }
    }
    return out;
  }();
  return subjects;
}

const Subject* spider() {
  static const std::unique_ptr<Subject> s = []() -> std::unique_ptr<Subject> {
    const std::string path = std::string(CSCULPT_TEST_MODELS) + "/STL/Spider_binary.stl";
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return nullptr;
    return make_subject("Spider_binary.stl", read_mesh(path));
  }();
  return s.get();
}

/// Every subject: the sphere, the Blender bases, the spider.
std::vector<const Subject*> all_subjects() {
  std::vector<const Subject*> out;
  for (const auto& s : sphere_and_eval_subjects()) out.push_back(s.get());
  if (const Subject* s = spider()) out.push_back(s);
  return out;
}
const Subject& sphere_subject() {
  return *sphere_and_eval_subjects().front();
}
/// The sphere, and the largest real mesh when there is one (Suzanne: 31658 vertices).
std::vector<const Subject*> sphere_and_one_real() {
  std::vector<const Subject*> out{&sphere_subject()};
  const Subject* big = nullptr;
  for (const auto& s : sphere_and_eval_subjects())
    if (s.get() != &sphere_subject() && (!big || s->base.vertex_count() > big->base.vertex_count()))
      big = s.get();
  if (big) out.push_back(big);
  return out;
}

/// The vertex furthest along `dir` from the centre.
Vec3f extreme(const Subject& s, Vec3f dir) {
  std::size_t best = 0;
  float best_d = -std::numeric_limits<float>::infinity();
  for (std::size_t v = 0; v < s.base.vertex_count(); ++v) {
    const float d = dot(sub(s.base.positions[v], s.centre), dir);
    if (d > best_d) {
      best_d = d;
      best = v;
    }
  }
  return s.base.positions[best];
}

Vec3f perpendicular(Vec3f dir) {
  const Vec3f helper = std::abs(dir.x) < 0.9f ? Vec3f{1, 0, 0} : Vec3f{0, 1, 0};
  return unit(cross(dir, helper));
}

/// A stroke of `kind` on the surface point furthest along `dir`, sized to the mesh.
Stroke stroke_at(Kind kind, const Subject& s, Vec3f dir, float size = 1.f) {
  dir = unit(dir);
  const auto d = static_cast<float>(s.diag);
  Stroke st;
  st.kind = kind;
  st.center = extreme(s, dir);
  switch (kind) {
    case Kind::grab:
      st.radius = 0.25f * d * size;
      st.strength = 0.25f;
      st.axis = unit(add(dir, perpendicular(dir)));
      break;
    case Kind::inflate:
      st.radius = 0.2f * d * size;
      st.strength = 0.15f;
      break;
    case Kind::detail:
      st.radius = 0.12f * d * size;
      st.strength = 0.08f;
      st.frequency = 10.f;
      break;
    case Kind::twist:
      st.radius = 0.3f * d * size;
      st.strength = 0.7f;
      st.axis = dir;
      break;
    case Kind::bend:
      st.center = s.centre;
      st.radius = 0.5f * d * size;
      st.strength = 0.6f;
      st.axis = perpendicular(dir);
      st.direction = dir;
      break;
    case Kind::smooth:
      st.radius = 0.25f * d * size;
      st.strength = 1.f;
      break;
    case Kind::paint:
      st.radius = 0.2f * d * size;
      st.strength = 1.f;
      st.albedo = {0.9f, 0.15f, 0.05f};
      st.roughness = 0.25f;
      st.metallic = 1.f;
      break;
  }
  return st;
}

Mesh edited(const Subject& s, std::initializer_list<Stroke> strokes) {
  Mesh m = s.base;
  for (const Stroke& st : strokes) {
    // one smoothing pass on a regular mesh barely moves it: smooth a few times
    const int passes = st.kind == Kind::smooth ? 8 : 1;
    for (int i = 0; i < passes; ++i) apply_stroke(m, st, &s.hierarchy.topology());
  }
  return m;
}

Mesh applied(const Mesh& base, const Diff& d) {
  Mesh m = base;
  apply_diff(d, m);
  return m;
}

double max_position_error(const Mesh& a, const Mesh& b) {
  double e = 0;
  for (std::size_t v = 0; v < a.vertex_count(); ++v)
    e = std::max(e, dist(a.positions[v], b.positions[v]));
  return e;
}

/// Largest channel difference in each channel's linear space.
double max_channel_error(const Mesh& a, const Mesh& b) {
  double e = 0;
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    const Linearisation lin = a.channels[c].desc.linearisation;
    for (std::size_t i = 0; i < a.channels[c].values.size(); ++i)
      e = std::max(e, std::abs(double(to_linear(lin, a.channels[c].values[i])) -
                               to_linear(lin, b.channels[c].values[i])));
  }
  return e;
}

/// The vertices whose position differs (bitwise) between base and edit.
std::vector<std::uint32_t> support(const Mesh& base, const Mesh& edit) {
  return capture_diff(base, edit).positions.indices;
}

/// RMS |merged - expected| over `where`, relative to the RMS size of edit - base there.
double rel_error(const Mesh& merged, const Mesh& expected, const Mesh& base, const Mesh& edit,
                 const std::vector<std::uint32_t>& where) {
  double err = 0, size = 0;
  for (std::uint32_t v : where) {
    err += std::pow(dist(merged.positions[v], expected.positions[v]), 2);
    size += std::pow(dist(edit.positions[v], base.positions[v]), 2);
  }
  return size > 0 ? std::sqrt(err / size) : (err > 0 ? std::numeric_limits<double>::infinity() : 0);
}

double max_displacement(const Mesh& base, const Mesh& edit) {
  double m = 0;
  for (std::size_t v = 0; v < base.vertex_count(); ++v)
    m = std::max(m, dist(base.positions[v], edit.positions[v]));
  return m;
}

/// Every index of every attribute of `d` lies in `allowed` (sorted).
std::string indices_outside(const Diff& d, const std::vector<std::uint32_t>& allowed) {
  auto check = [&](const AttributeDiff& a, const std::string& what) -> std::string {
    for (std::uint32_t v : a.indices)
      if (!std::binary_search(allowed.begin(), allowed.end(), v))
        return what + " lists vertex " + std::to_string(v) + " that no edit changed";
    return {};
  };
  std::string r = check(d.positions, "positions");
  for (const ChannelDiff& c : d.channels)
    if (r.empty()) r = check(c.change, "channel " + c.desc.name);
  return r;
}

/// Sorted union of the vertices any attribute of any diff changes.
std::vector<std::uint32_t> touched_union(const std::vector<Diff>& diffs) {
  std::vector<std::uint32_t> all;
  for (const Diff& d : diffs) {
    all.insert(all.end(), d.positions.indices.begin(), d.positions.indices.end());
    for (const ChannelDiff& c : d.channels)
      all.insert(all.end(), c.change.indices.begin(), c.change.indices.end());
  }
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  return all;
}

std::vector<Diff> diffs_of(const Mesh& base, const std::vector<Mesh>& edits) {
  std::vector<Diff> out;
  for (const Mesh& e : edits) out.push_back(capture_diff(base, e));
  return out;
}

bool all_finite(const Mesh& m) {
  for (const Vec3f& p : m.positions)
    if (!finite(p)) return false;
  for (const Channel& c : m.channels)
    for (float x : c.values)
      if (!std::isfinite(x)) return false;
  return true;
}

// ---- 1. single edit ----------------------------------------------------------------------

TEST(MergeSingleEdit, OneDiffReproducesTheEditForEveryMethodAndStroke) {
  for (const Subject* s : all_subjects()) {
    Merger merger(s->hierarchy);
    for (Kind kind : kKinds) {
      const Mesh edit = edited(*s, {stroke_at(kind, *s, {0.3f, 0.8f, 0.5f})});
      const Diff d = capture_diff(s->base, edit);
      ASSERT_GT(d.touched_vertices(), 0u)
          << s->name << " " << kind_name(kind) << " changes nothing";
      const std::vector<Diff> one{d};
      for (MergeMethod m : all_merge_methods()) {
        SCOPED_TRACE(s->name + " " + kind_name(kind) + " " + method_name(m));
        const Diff merged = merger.merge(s->base, one, m);
        EXPECT_EQ(indices_outside(merged, touched_union(one)), "");
        const Mesh result = applied(s->base, merged);
        EXPECT_LT(max_position_error(result, edit), 1e-5 * s->diag);
        EXPECT_LT(max_channel_error(result, edit), 1e-5);
      }
    }
  }
}

// A session merges as submits arrive: most of its merges hold one submit, which must come
// out as it went in, to the bit, with the channels in the base's order.
TEST(MergeSingleEdit, OneDiffMergesToItselfBitForBitForEveryMethod) {
  for (const Subject* s : all_subjects()) {
    Merger merger(s->hierarchy);
    const Mesh edit = edited(*s, {stroke_at(Kind::detail, *s, {0.3f, 0.8f, 0.5f})});
    const Diff d = capture_diff(s->base, edit);
    for (MergeMethod m : all_merge_methods()) {
      SCOPED_TRACE(s->name + " " + method_name(m));
      const Diff merged = merger.merge(s->base, std::vector<Diff>{d}, m);
      EXPECT_EQ(merged.positions, d.positions);
      ASSERT_EQ(merged.channels.size(), s->base.channels.size());
      for (std::size_t c = 0; c < merged.channels.size(); ++c)
        EXPECT_EQ(merged.channels[c].desc.name, s->base.channels[c].desc.name);
      const Mesh result = applied(s->base, merged);
      EXPECT_TRUE(result.positions == edit.positions);
      for (std::size_t c = 0; c < edit.channels.size(); ++c)
        EXPECT_TRUE(result.channels[c].values == edit.channels[c].values);
    }
  }
}

// ---- 2. identity: disjoint edits ---------------------------------------------------------

TEST(MergeIdentity, DisjointEditsEachKeepTheirRegion) {
  for (const Subject* s : all_subjects()) {
    const Mesh a = edited(*s, {stroke_at(Kind::grab, *s, s->axis, 0.8f)});
    const Mesh b = edited(*s, {stroke_at(Kind::detail, *s, scale(s->axis, -1.f))});
    const std::vector<std::uint32_t> sa = support(s->base, a), sb = support(s->base, b);
    std::vector<std::uint32_t> both;
    std::set_intersection(sa.begin(), sa.end(), sb.begin(), sb.end(), std::back_inserter(both));
    ASSERT_TRUE(both.empty()) << s->name << ": the test's edits overlap";
    ASSERT_FALSE(sa.empty());
    ASSERT_FALSE(sb.empty());
    const std::vector<Diff> diffs = diffs_of(s->base, {a, b});
    const std::vector<std::uint32_t> changed = touched_union(diffs);
    Merger merger(s->hierarchy);
    for (MergeMethod m : all_merge_methods()) {
      SCOPED_TRACE(s->name + " " + method_name(m));
      const Diff merged = merger.merge(s->base, diffs, m);
      // untouched vertices keep their base values bit for bit (every method)
      EXPECT_EQ(indices_outside(merged, changed), "");
      const Mesh result = applied(s->base, merged);
      const double ea = rel_error(result, a, s->base, a, sa);
      const double eb = rel_error(result, b, s->base, b, sb);
      RecordProperty(s->name + "/" + method_name(m), std::to_string(ea) + " " + std::to_string(eb));
      if (m == MergeMethod::full) {
        EXPECT_LT(ea, 0.05) << "grab region";
        EXPECT_LT(eb, 0.05) << "detail region";
      }
      if (m == MergeMethod::full || m == MergeMethod::sum ||
          m == MergeMethod::weighted_translation || m == MergeMethod::single_level_isometry) {
        // per-vertex methods: where only one edit acts, its value is taken as it is
        EXPECT_LT(ea, 1e-4) << "grab region";
        EXPECT_LT(eb, 1e-4) << "detail region";
      }
    }
  }
}

// ---- 3. idempotence ----------------------------------------------------------------------

TEST(MergeIdempotence, IdenticalEditsMergeToThatEdit) {
  for (const Subject* s : all_subjects()) {
    Mesh a = s->base;
    for (const Stroke& st : scripted_strokes(s->base, 7, 8, true))
      apply_stroke(a, st, &s->hierarchy.topology());
    apply_stroke(a, stroke_at(Kind::twist, *s, {0.2f, 0.9f, 0.3f}));
    const Diff d = capture_diff(s->base, a);
    Merger merger(s->hierarchy);
    for (MergeMethod m : all_merge_methods()) {
      if (m == MergeMethod::sum) continue;  // sum doubles by design (paper: breaks idempotence)
      SCOPED_TRACE(s->name + " " + method_name(m));
      for (std::size_t copies : {2u, 3u}) {
        const std::vector<Diff> same(copies, d);
        const Mesh result = applied(s->base, merger.merge(s->base, same, m));
        EXPECT_LT(max_position_error(result, a), 1e-5 * s->diag) << copies << " copies";
        EXPECT_LT(max_channel_error(result, a), 1e-5) << copies << " copies";
      }
    }
  }
}

// ---- 4. commutativity / associativity, workspace reuse -----------------------------------

TEST(MergeOrder, EveryPermutationGivesTheSameBits) {
  for (const Subject* s : sphere_and_one_real()) {
    const Vec3f dir{0.5f, 0.7f, 0.5f};
    const Vec3f near1 = add(dir, scale(perpendicular(dir), 0.15f));
    const Vec3f near2 = sub(dir, scale(perpendicular(dir), 0.1f));
    const std::vector<Mesh> three = {edited(*s, {stroke_at(Kind::bend, *s, dir)}),
                                     edited(*s, {stroke_at(Kind::inflate, *s, near1)}),
                                     edited(*s, {stroke_at(Kind::smooth, *s, near2)})};
    const std::vector<Mesh> four = {
        edited(*s, {stroke_at(Kind::grab, *s, dir)}),
        edited(*s, {stroke_at(Kind::detail, *s, near1)}),
        edited(*s, {stroke_at(Kind::twist, *s, near2)}),
        edited(*s, {stroke_at(Kind::paint, *s, dir), stroke_at(Kind::detail, *s, near2, 0.5f)})};
    for (const std::vector<Mesh>* edits : {&three, &four}) {
      const std::vector<Diff> diffs = diffs_of(s->base, *edits);
      for (std::size_t i = 0; i < diffs.size(); ++i)
        for (std::size_t j = i + 1; j < diffs.size(); ++j) ASSERT_FALSE(diffs[i] == diffs[j]);
      Merger merger(s->hierarchy);
      for (MergeMethod m : all_merge_methods()) {
        SCOPED_TRACE(s->name + " " + std::to_string(diffs.size()) + " edits " + method_name(m));
        const Diff reference = merger.merge(s->base, diffs, m);
        EXPECT_FALSE(reference.positions.empty());
        std::vector<std::size_t> perm(diffs.size());
        std::iota(perm.begin(), perm.end(), std::size_t{0});
        int count = 0;
        while (std::next_permutation(perm.begin(), perm.end())) {
          std::vector<Diff> shuffled;
          for (std::size_t p : perm) shuffled.push_back(diffs[p]);
          const Diff merged = merger.merge(s->base, shuffled, m);
          EXPECT_TRUE(merged == reference) << "permutation " << count << " differs, digest "
                                           << digest(merged) << " vs " << digest(reference);
          ++count;
        }
        EXPECT_EQ(count + 1, diffs.size() == 3 ? 6 : 24);
        // the same merger again (warm workspace) and a fresh one
        EXPECT_TRUE(merger.merge(s->base, diffs, m) == reference) << "same Merger, second time";
        Merger fresh(s->hierarchy);
        EXPECT_TRUE(fresh.merge(s->base, diffs, m) == reference) << "fresh Merger";
      }
      // a merge of other diffs in between must leave nothing behind in the workspace
      const Diff full_ref = merger.merge(s->base, diffs, MergeMethod::full);
      const std::vector<Diff> other{diffs[1]};
      (void)merger.merge(s->base, other, MergeMethod::multiscale_translation);
      (void)merger.merge(s->base, std::vector<Diff>{diffs[0], diffs[0], diffs[2]},
                         MergeMethod::full);
      EXPECT_TRUE(merger.merge(s->base, diffs, MergeMethod::full) == full_ref)
          << s->name << ": workspace reuse after other merges changed the result";
    }
  }
}

// ---- 5. continuity -----------------------------------------------------------------------

/// base + factor (edit - base), computed in double.
Mesh scaled_edit(const Mesh& base, const Mesh& edit, double factor) {
  Mesh m = edit;
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    const Vec3f& b = base.positions[v];
    const Vec3f& e = edit.positions[v];
    m.positions[v] = {static_cast<float>(b.x + factor * (double(e.x) - b.x)),
                      static_cast<float>(b.y + factor * (double(e.y) - b.y)),
                      static_cast<float>(b.z + factor * (double(e.z) - b.z))};
  }
  return m;
}

TEST(MergeContinuity, ScalingOneEditByOnePlusEpsMovesTheResultByOrderEps) {
  for (const Subject* s : sphere_and_one_real()) {
    const Vec3f dir{0.3f, 0.4f, 0.85f};
    const Mesh coarse =
        edited(*s, {stroke_at(Kind::twist, *s, dir, 1.5f), stroke_at(Kind::grab, *s, dir)});
    const Mesh fine =
        edited(*s, {stroke_at(Kind::detail, *s, add(dir, scale(perpendicular(dir), 0.1f)))});
    Merger merger(s->hierarchy);
    for (int which = 0; which < 2; ++which) {
      const Mesh& scaled_one = which == 0 ? fine : coarse;
      const Mesh& other = which == 0 ? coarse : fine;
      const double size = max_displacement(s->base, scaled_one);
      for (MergeMethod m : all_merge_methods()) {
        SCOPED_TRACE(s->name + (which == 0 ? " scaling the detail " : " scaling the twist+grab ") +
                     method_name(m));
        const Mesh reference =
            applied(s->base, merger.merge(s->base, diffs_of(s->base, {other, scaled_one}), m));
        double previous = std::numeric_limits<double>::infinity();
        std::ostringstream trace;
        for (double eps : {1e-2, 1e-3, 1e-4}) {
          const Mesh perturbed = scaled_edit(s->base, scaled_one, 1 + eps);
          const Mesh result =
              applied(s->base, merger.merge(s->base, diffs_of(s->base, {other, perturbed}), m));
          const double change = max_position_error(result, reference);
          const double ratio = change / (eps * size);
          trace << " eps=" << eps << ": change " << change << " ratio " << ratio << ";";
          // Lipschitz: the merged positions move by at most a few times the input's change
          EXPECT_LT(ratio, 5.0) << trace.str();
          EXPECT_LT(change, previous) << "the change must shrink with eps:" << trace.str();
          previous = change;
        }
        RecordProperty(s->name + "/" + std::to_string(which) + "/" + method_name(m), trace.str());
      }
    }
  }
}

/// Continuity where the set of edits acting on a vertex changes: a tiny extra displacement
/// (1e-5 x diag) added to the detail edit over the region only the coarse edit touched
/// makes those vertices "edited by both" instead of "edited by one". The result there must
/// move by about that much, not jump to another formula's value.
TEST(MergeContinuity, ATinyEditWhereOnlyAnotherActedMovesTheResultLittle) {
  for (const Subject* s : sphere_and_one_real()) {
    const Vec3f dir{0.3f, 0.4f, 0.85f};
    const Mesh coarse =
        edited(*s, {stroke_at(Kind::twist, *s, dir, 1.5f), stroke_at(Kind::grab, *s, dir)});
    const Mesh fine =
        edited(*s, {stroke_at(Kind::detail, *s, add(dir, scale(perpendicular(dir), 0.1f)))});
    const std::vector<std::uint32_t> sc = support(s->base, coarse), sf = support(s->base, fine);
    Merger merger(s->hierarchy);
    for (MergeMethod m : all_merge_methods()) {
      SCOPED_TRACE(s->name + " " + method_name(m));
      const Mesh before =
          applied(s->base, merger.merge(s->base, diffs_of(s->base, {coarse, fine}), m));
      std::ostringstream trace;
      double previous = std::numeric_limits<double>::infinity();
      for (double rel : {1e-3, 1e-4, 1e-5}) {
        const double delta = rel * s->diag;
        Mesh fine_plus = fine;
        std::size_t added = 0;
        for (std::uint32_t v : sc) {
          if (std::binary_search(sf.begin(), sf.end(), v)) continue;
          fine_plus.positions[v].x += static_cast<float>(delta);
          ++added;
        }
        ASSERT_GT(added, 100u);
        const Mesh after =
            applied(s->base, merger.merge(s->base, diffs_of(s->base, {coarse, fine_plus}), m));
        const double change = max_position_error(after, before);
        trace << " delta=" << rel << "xdiag: change " << change / s->diag << "xdiag, ratio "
              << change / delta << ";";
        // average: the mean over the edits halves by design. paper-blend: the paper's node
        // blend taken literally is only Hoelder-continuous on a mesh of many parts (the
        // 18-part spider: ratio 8, 14, 18 as delta shrinks), so only the decrease holds.
        if (m != MergeMethod::average) {
          if (m != MergeMethod::paper_blend) {
            EXPECT_LT(change / delta, 10.0) << trace.str();
          }
          EXPECT_LT(change, previous) << trace.str();
        }
        previous = change;
      }
      RecordProperty(s->name + "/" + method_name(m), trace.str());
    }
  }
}

// ---- 6. generality -----------------------------------------------------------------------

TEST(MergeGenerality, EveryStrokePairMergesToFiniteBoundedResults) {
  std::vector<const Subject*> subjects{&sphere_subject()};
  if (const Subject* s = spider()) subjects.push_back(s);
  for (const Subject* s : subjects) {
    Merger merger(s->hierarchy);
    for (std::size_t i = 0; i < kKinds.size(); ++i) {
      for (std::size_t j = i; j < kKinds.size(); ++j) {
        // overlapping: the second stroke sits a little beside the first, at its own scale
        const Mesh a = edited(*s, {stroke_at(kKinds[i], *s, {0.2f, 0.3f, 0.9f})});
        const Mesh b = edited(*s, {stroke_at(kKinds[j], *s, {0.35f, 0.2f, 0.9f}, 0.8f)});
        const std::vector<Diff> diffs = diffs_of(s->base, {a, b});
        Box inputs = bbox(s->base.positions);
        for (const Vec3f& p : a.positions) inputs.add(p);
        for (const Vec3f& p : b.positions) inputs.add(p);
        const double margin =
            max_displacement(s->base, a) + max_displacement(s->base, b) + 1e-4 * s->diag;
        for (MergeMethod m : all_merge_methods()) {
          SCOPED_TRACE(s->name + " " + kind_name(kKinds[i]) + "+" + kind_name(kKinds[j]) + " " +
                       method_name(m));
          Diff merged;
          ASSERT_NO_THROW(merged = merger.merge(s->base, diffs, m));
          const Mesh result = applied(s->base, merged);
          ASSERT_TRUE(all_finite(result));
          double worst = 0;
          for (const Vec3f& p : result.positions) worst = std::max(worst, inputs.outside(p));
          EXPECT_LE(worst, margin) << "outside the inputs' bounding box by " << worst;
          for (const Channel& c : result.channels)
            for (float x : c.values) {
              ASSERT_GE(x, c.desc.min_value) << c.desc.name;
              ASSERT_LE(x, c.desc.max_value) << c.desc.name;
            }
        }
      }
    }
  }
}

// ---- 7. rotational invariance ------------------------------------------------------------

TEST(MergeRotation, GlobalRotationCarriesAFineDetail) {
  for (const Subject* s : sphere_and_one_real()) {
    // a rigid rotation of the whole mesh: a twist whose falloff radius is huge
    Stroke rotation;
    rotation.kind = Kind::twist;
    rotation.center = s->centre;
    rotation.radius = 1000.f * static_cast<float>(s->diag);
    rotation.strength = 0.5f;
    rotation.axis = unit({0.3f, 1.f, 0.2f});
    const Stroke detail = stroke_at(Kind::detail, *s, {0.8f, 0.2f, 0.55f});
    const Mesh a = edited(*s, {rotation});
    const Mesh b = edited(*s, {detail});
    const Mesh expected = edited(*s, {detail, rotation});  // detail first, then the rotation
    const std::vector<std::uint32_t> sb = support(s->base, b);
    ASSERT_FALSE(sb.empty());
    const std::vector<Diff> diffs = diffs_of(s->base, {a, b});
    Merger merger(s->hierarchy);
    auto err = [&](MergeMethod m) {
      return rel_error(applied(s->base, merger.merge(s->base, diffs, m)), expected, s->base, b, sb);
    };
    const double full = err(MergeMethod::full);
    const double weighted = err(MergeMethod::weighted_translation);
    const double sum = err(MergeMethod::sum);
    RecordProperty(s->name, "full " + std::to_string(full) + " weighted-translation " +
                                std::to_string(weighted) + " sum " + std::to_string(sum));
    SCOPED_TRACE(s->name + ": full " + std::to_string(full) + ", weighted-translation " +
                 std::to_string(weighted) + ", sum " + std::to_string(sum));
    EXPECT_LT(full, 0.02);
    EXPECT_GT(weighted, 10 * full);
    EXPECT_GT(sum, 10 * full);
    EXPECT_GT(weighted, 0.2);
    EXPECT_GT(sum, 0.2);
  }
}

// ---- 8. scenarios ------------------------------------------------------------------------

TEST(MergeScenarios, FullBeatsTheMethodsThePaperSaysItBeats) {
  const std::vector<Scenario> scenarios = make_scenarios(20000);
  ASSERT_GE(scenarios.size(), 8u);
  for (const Scenario& sc : scenarios) {
    const Hierarchy hierarchy = Hierarchy::build(sc.base);
    Merger merger(hierarchy);
    const std::vector<Diff> diffs = diffs_of(sc.base, sc.edits);
    std::vector<ScenarioScore> scores;
    for (MergeMethod m : all_merge_methods()) {
      SCOPED_TRACE(sc.name + " " + method_name(m));
      const Mesh merged = applied(sc.base, merger.merge(sc.base, diffs, m));
      EXPECT_TRUE(all_finite(merged));
      const ScenarioScore score_m = score(sc, merged, hierarchy.topology());
      EXPECT_TRUE(std::isfinite(score_m.rel_err) && std::isfinite(score_m.roughness) &&
                  std::isfinite(score_m.channel_err));
      scores.push_back(score_m);
    }
    auto score_of = [&](MergeMethod m) {
      const auto methods = all_merge_methods();
      const auto it = std::find(methods.begin(), methods.end(), m);
      return scores[static_cast<std::size_t>(it - methods.begin())];
    };
    const ScenarioScore full = score_of(MergeMethod::full);
    for (MergeMethod m : sc.full_beats) {
      const ScenarioScore other = score_of(m);
      EXPECT_LT(full.rel_err, other.rel_err) << sc.name << ": full " << full.rel_err << " vs "
                                             << method_name(m) << " " << other.rel_err;
    }
    if (sc.name == "disjoint" || sc.name == "identical") {
      EXPECT_LT(full.rel_err, 0.01) << sc.name;
    }
    if (!sc.has_expected) {
      EXPECT_LE(full.roughness, 1.5) << sc.name << ": seams or spikes";
    }
    std::ostringstream line;
    for (MergeMethod m : all_merge_methods())
      line << method_name(m) << "=" << score_of(m).rel_err << "/" << score_of(m).roughness << "/"
           << score_of(m).channel_err << " ";
    RecordProperty(sc.name, line.str());
  }
}

// ---- 9. materials ------------------------------------------------------------------------

Stroke paint_at(const Subject& s, Vec3f dir, std::array<float, 3> albedo, float roughness,
                float metallic, float size = 1.f) {
  Stroke st = stroke_at(Kind::paint, s, dir, size);
  st.albedo = albedo;
  st.roughness = roughness;
  st.metallic = metallic;
  return st;
}

/// Largest linear-space difference of the channels over the vertices `where`.
double channel_error_over(const Mesh& a, const Mesh& b, const std::vector<std::uint32_t>& where) {
  double e = 0;
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    const ChannelDesc& d = a.channels[c].desc;
    for (std::uint32_t v : where)
      for (std::uint32_t k = 0; k < d.width; ++k) {
        const std::size_t i = std::size_t{v} * d.width + k;
        e = std::max(e, std::abs(double(to_linear(d.linearisation, a.channels[c].values[i])) -
                                 to_linear(d.linearisation, b.channels[c].values[i])));
      }
  }
  return e;
}

std::vector<std::uint32_t> channel_support(const Mesh& base, const Mesh& edit) {
  std::vector<Diff> d{capture_diff(base, edit)};
  return touched_union(d);
}

TEST(MergeMaterials, DisjointPaintsExactIdenticalIdempotentOverlapsInRange) {
  for (const Subject* s : all_subjects()) {
    Merger merger(s->hierarchy);
    const Mesh red = edited(*s, {paint_at(*s, s->axis, {0.9f, 0.1f, 0.1f}, 0.2f, 1.f)});
    const Mesh blue =
        edited(*s, {paint_at(*s, scale(s->axis, -1.f), {0.1f, 0.2f, 0.9f}, 0.8f, 0.f)});
    const std::vector<std::uint32_t> sr = channel_support(s->base, red),
                                     sbl = channel_support(s->base, blue);
    ASSERT_FALSE(sr.empty());
    ASSERT_FALSE(sbl.empty());
    {
      std::vector<std::uint32_t> both;
      std::set_intersection(sr.begin(), sr.end(), sbl.begin(), sbl.end(), std::back_inserter(both));
      ASSERT_TRUE(both.empty()) << s->name << ": the test's paints overlap";
    }
    const std::vector<Diff> disjoint = diffs_of(s->base, {red, blue});
    for (MergeMethod m : all_merge_methods()) {
      SCOPED_TRACE(s->name + " " + method_name(m));
      const Diff merged_diff = merger.merge(s->base, disjoint, m);
      EXPECT_TRUE(merged_diff.positions.empty()) << "paint moved vertices";
      EXPECT_EQ(indices_outside(merged_diff, touched_union(disjoint)), "");
      const Mesh merged = applied(s->base, merged_diff);
      const double er = channel_error_over(merged, red, sr);
      const double eb = channel_error_over(merged, blue, sbl);
      RecordProperty("disjoint paint " + s->name + "/" + method_name(m),
                     std::to_string(er) + " " + std::to_string(eb));
      // Exact for `full` (merge.cpp: "a disjoint paint stays exact") and for the per-vertex
      // methods sum, weighted-translation and single-level-isometry; the others are recorded.
      if (m == MergeMethod::full || m == MergeMethod::weighted_translation ||
          m == MergeMethod::sum || m == MergeMethod::single_level_isometry) {
        EXPECT_LT(er, 1e-4) << "red spot";
        EXPECT_LT(eb, 1e-4) << "blue spot";
      }
    }
    // identical paints: idempotent (every method but sum)
    const Mesh twice =
        edited(*s, {paint_at(*s, {0.2f, 0.9f, 0.3f}, {0.3f, 0.7f, 0.2f}, 0.6f, 0.f),
                    paint_at(*s, {0.3f, 0.8f, 0.3f}, {0.9f, 0.9f, 0.1f}, 0.1f, 1.f, 0.5f)});
    const std::vector<Diff> same = diffs_of(s->base, {twice, twice});
    for (MergeMethod m : all_merge_methods()) {
      if (m == MergeMethod::sum) continue;
      SCOPED_TRACE(s->name + " identical paints " + method_name(m));
      EXPECT_LT(max_channel_error(applied(s->base, merger.merge(s->base, same, m)), twice), 1e-4);
    }
    // overlapping different colours (and a sculpt under one of them): within the channel range
    const Mesh a = edited(*s, {paint_at(*s, {0.6f, 0.6f, 0.5f}, {1.f, 1.f, 1.f}, 1.f, 1.f, 1.5f)});
    const Mesh b = edited(*s, {paint_at(*s, {0.5f, 0.6f, 0.6f}, {1.f, 0.95f, 1.f}, 0.9f, 1.f, 1.5f),
                               stroke_at(Kind::inflate, *s, {0.5f, 0.6f, 0.6f})});
    const Mesh c =
        edited(*s, {paint_at(*s, {0.6f, 0.5f, 0.6f}, {0.f, 0.f, 0.05f}, 0.f, 0.f, 1.5f)});
    const std::vector<Diff> overlapping = diffs_of(s->base, {a, b, c});
    for (MergeMethod m : all_merge_methods()) {
      SCOPED_TRACE(s->name + " overlapping paints " + method_name(m));
      const Mesh merged = applied(s->base, merger.merge(s->base, overlapping, m));
      for (const Channel& ch : merged.channels)
        for (float x : ch.values) {
          ASSERT_TRUE(std::isfinite(x)) << ch.desc.name;
          ASSERT_GE(x, ch.desc.min_value) << ch.desc.name;
          ASSERT_LE(x, ch.desc.max_value) << ch.desc.name;
        }
    }
  }
}

// ---- 10. bad input -----------------------------------------------------------------------

bool contains(const std::string& haystack, const std::string& needle) {
  std::string h = haystack, n = needle;
  for (char& ch : h) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (char& ch : n) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return h.find(n) != std::string::npos;
}

TEST(MergeBadInput, MalformedDiffsAreRejectedWithAMessage) {
  const Subject& s = sphere_subject();
  Merger merger(s.hierarchy);
  const Diff good = capture_diff(s.base, edited(s, {stroke_at(Kind::grab, s, {0, 0, 1})}));
  const Diff paint = capture_diff(s.base, edited(s, {stroke_at(Kind::paint, s, {0, 1, 0})}));
  ASSERT_GE(good.positions.size(), 3u);
  const auto n = static_cast<std::uint32_t>(s.base.vertex_count());

  auto merge_with = [&](const Diff& bad) {
    return invalid_input_message([&] {
      (void)merger.merge(s.base, std::vector<Diff>{good, bad}, MergeMethod::full);
    });
  };
  {
    Diff bad = good;
    bad.positions.indices.back() = n + 5;
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "out of range") && contains(msg, std::to_string(n + 5))) << msg;
  }
  {
    Diff bad = good;
    std::swap(bad.positions.indices[0], bad.positions.indices[1]);
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "increasing")) << msg;
  }
  {
    Diff bad = good;
    bad.positions.indices[1] = bad.positions.indices[0];  // repeated
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "increasing")) << msg;
  }
  {
    Diff bad = good;
    bad.positions.values[4] = std::numeric_limits<float>::quiet_NaN();
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "finite") && contains(msg, std::to_string(bad.positions.indices[1])))
        << msg;
  }
  {
    Diff bad = paint;
    bad.channels[0].change.values[0] = std::numeric_limits<float>::infinity();
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "finite") && contains(msg, bad.channels[0].desc.name)) << msg;
  }
  {
    Diff bad = good;
    bad.vertex_count = n + 1;
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, std::to_string(n + 1)) && contains(msg, "vertices")) << msg;
  }
  {
    Diff bad = good;
    bad.positions.values.pop_back();
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "values")) << msg;
  }
  {
    Diff bad = paint;
    bad.channels[1].desc.name = "emission";
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "emission")) << msg;
  }
  {
    Diff bad = paint;
    bad.channels[0].desc.width = 2;  // albedo is RGB
    const std::string msg = merge_with(bad);
    EXPECT_TRUE(contains(msg, "albedo") && contains(msg, "width")) << msg;
  }
  // a hierarchy built for another mesh
  {
    const Hierarchy other = Hierarchy::build(make_sphere(5000));
    Merger wrong(other);
    const std::string msg = invalid_input_message(
        [&] { (void)wrong.merge(s.base, std::vector<Diff>{good}, MergeMethod::full); });
    EXPECT_TRUE(contains(msg, "hierarchy")) << msg;
  }
  // 0 diffs: an empty diff with the base's channels
  for (MergeMethod m : all_merge_methods()) {
    const Diff empty = merger.merge(s.base, std::span<const Diff>{}, m);
    EXPECT_EQ(empty.vertex_count, n);
    EXPECT_TRUE(empty.positions.empty());
    EXPECT_EQ(empty.touched_vertices(), 0u);
    ASSERT_EQ(empty.channels.size(), s.base.channels.size());
    for (std::size_t c = 0; c < empty.channels.size(); ++c)
      EXPECT_EQ(empty.channels[c].desc, s.base.channels[c].desc);
  }
  // after all those rejections the merger still works
  EXPECT_TRUE(merger.merge(s.base, std::vector<Diff>{good}, MergeMethod::full) ==
              Merger(s.hierarchy).merge(s.base, std::vector<Diff>{good}, MergeMethod::full));
}

TEST(MergeBadInput, HierarchyOfAnotherMeshWithTheSameVertexCount) {
  // Same vertex count, different connectivity: the sphere with its vertices renumbered.
  const Subject& s = sphere_subject();
  Mesh renumbered = s.base;
  const auto n = static_cast<std::uint32_t>(s.base.vertex_count());
  for (Triangle& t : renumbered.triangles)
    for (std::uint32_t& v : t) v = (v + n / 2) % n;
  const Hierarchy other = Hierarchy::build(renumbered);
  Merger wrong(other);
  const Diff good = capture_diff(s.base, edited(s, {stroke_at(Kind::grab, s, {0, 0, 1})}));
  const std::string msg = invalid_input_message([&] {
    (void)wrong.merge(s.base, std::vector<Diff>{good, good}, MergeMethod::full);
  });
  EXPECT_TRUE(contains(msg, "hierarchy")) << msg;
}

}  // namespace
// SameChange::add (an artist's undo against everyone else's work): matching changes are a
// coincidence, not a copy, so they add like any two edits would, positions and channels.
TEST(MergeIdempotence, SameChangeAddAddsIdenticalEdits) {
  const Subject& s = *all_subjects().front();
  Mesh a = s.base;
  apply_stroke(a, stroke_at(Kind::inflate, s, s.axis));
  apply_stroke(a, paint_at(s, s.axis, {0.6f, 0.4f, 0.3f}, 0.5f, 0.5f));
  const Diff d = capture_diff(s.base, a);
  Mesh twice = s.base;  // the edit's change applied two times over
  for (std::size_t v = 0; v < twice.vertex_count(); ++v)
    twice.positions[v] = add(a.positions[v], sub(a.positions[v], s.base.positions[v]));
  for (std::size_t c = 0; c < twice.channels.size(); ++c) {
    const ChannelDesc& desc = twice.channels[c].desc;
    for (std::size_t i = 0; i < twice.channels[c].values.size(); ++i) {
      // twice the change in the channel's linear space, where channels merge
      const float b = to_linear(desc.linearisation, s.base.channels[c].values[i]);
      const float e = to_linear(desc.linearisation, a.channels[c].values[i]);
      twice.channels[c].values[i] =
          std::clamp(from_linear(desc.linearisation, e + (e - b)), desc.min_value, desc.max_value);
    }
  }
  Merger merger(s.hierarchy);
  const Diff* both[2] = {&d, &d};
  const MergeFrame frame = MergeFrame::fit(s.base.positions);
  const Mesh once = applied(s.base, merger.merge(s.base, both, MergeMethod::full, frame));
  const Mesh added =
      applied(s.base, merger.merge(s.base, both, MergeMethod::full, frame, SameChange::add));
  EXPECT_LT(max_position_error(once, a), 1e-5 * s.diag);
  EXPECT_GT(max_position_error(added, a), 0.5 * max_position_error(a, s.base));
  // Identical displacements carry each other by their own rotations: close to twice, not
  // exactly (the inflate turns the surface).
  EXPECT_LT(max_position_error(added, twice), 0.25 * max_position_error(a, s.base));
  EXPECT_LT(max_channel_error(added, twice), 1e-4);
}

}  // namespace csculpt
