// Merge fidelity properties of `full` (docs/merge-quality.md): disjoint edits exact and the
// result continuous as one edit's support slides into the other's; split seams that the
// artists moved together stay closed; a detail rides a coarse rotation at its own height.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/folds.h"
#include "csculpt/hierarchy.h"
#include "csculpt/merge.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/vec3.h"

namespace csculpt {
namespace {

using Deform = std::function<Vec3f(const Vec3f&)>;

Mesh deformed(const Mesh& base, const Deform& f) {
  Mesh m = base;
  for (Vec3f& p : m.positions) p = f(p);
  return m;
}

double distance(const Vec3f& a, const Vec3f& b) {
  const Vec3d d = sub(widen(a), widen(b));
  return std::sqrt(dot(d, d));
}

double max_change(const Mesh& a, const Mesh& b) {
  double m = 0;
  for (std::size_t v = 0; v < a.positions.size(); ++v)
    m = std::max(m, distance(a.positions[v], b.positions[v]));
  return m;
}

/// A smooth radial bump of height h and radius r around the unit direction c (on a sphere
/// centred at the origin: along the normal), a function of position only.
Deform bump(Vec3f c, float h, float r) {
  return [=](const Vec3f& p) {
    const Vec3f n = unit(p);
    const float dx = n.x - c.x, dy = n.y - c.y, dz = n.z - c.z;
    const float d2 = (dx * dx + dy * dy + dz * dz) / (r * r);
    const float k = d2 < 1 ? h * (1 - d2) * (1 - d2) * (1 - d2) : 0.f;
    return Vec3f{p.x + k * n.x, p.y + k * n.y, p.z + k * n.z};
  };
}

/// A smooth grab: translation t with a compact falloff of radius r around the point c.
Deform grab(Vec3f c, Vec3f t, float r) {
  return [=](const Vec3f& p) {
    const float dx = p.x - c.x, dy = p.y - c.y, dz = p.z - c.z;
    const float d2 = (dx * dx + dy * dy + dz * dz) / (r * r);
    const float k = d2 < 1 ? (1 - d2) * (1 - d2) : 0.f;
    return Vec3f{p.x + k * t.x, p.y + k * t.y, p.z + k * t.z};
  };
}

/// A rotation about the z axis by an angle growing with height (a twist of the top half).
Deform twist(float radians) {
  return [=](const Vec3f& p) {
    const float a = p.z > 0 ? radians * p.z : 0.f;
    const float c = std::cos(a), s = std::sin(a);
    return Vec3f{c * p.x - s * p.y, s * p.x + c * p.y, p.z};
  };
}

Mesh merged(const Mesh& base, const Hierarchy& h, const std::vector<Mesh>& edits,
            MergeMethod m = MergeMethod::full) {
  std::vector<Diff> diffs;
  for (const Mesh& e : edits) diffs.push_back(capture_diff(base, e));
  Merger merger(h);
  Mesh out = base;
  apply_diff(merger.merge(base, diffs, m), out);
  return out;
}

/// RMS of |result - expected| over the vertices `edit` moved, relative to its RMS size.
double rel_error(const Mesh& base, const Mesh& edit, const Mesh& result, const Mesh& expected) {
  double err = 0, size = 0;
  for (std::size_t v = 0; v < base.positions.size(); ++v) {
    const double d = distance(edit.positions[v], base.positions[v]);
    if (d == 0) continue;
    size += d * d;
    const double e = distance(result.positions[v], expected.positions[v]);
    err += e * e;
  }
  return size > 0 ? std::sqrt(err / size) : 0;
}

TEST(MergeFidelity, DisjointExactAndContinuousAsOneEditSlidesIntoTheOther) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const Mesh a = deformed(base, grab({1, 0, 0}, {0.15f, 0.05f, 0}, 0.5f));
  Mesh previous;
  Mesh previous_b;
  int disjoint_steps = 0;
  for (int step = 0; step <= 24; ++step) {
    // the bump's centre walks from the far side (120 degrees away) onto the grab
    const float angle = 2.1f * (1 - static_cast<float>(step) / 24.f);
    const Vec3f c{std::cos(angle), std::sin(angle), 0};
    const Mesh b = deformed(base, bump(c, 0.04f, 0.35f));
    const Mesh result = merged(base, h, {a, b});
    // the edits' supports are disjoint while the bump's rim (0.35 on the unit sphere's
    // directions) stays clear of the grab's (0.5 around (1, 0, 0)) by more than a ring
    const double gap = distance(Vec3f{1, 0, 0}, c) - 0.35 - 0.5;
    if (gap > 0.05) {
      ++disjoint_steps;
      Mesh expected = base;
      for (std::size_t v = 0; v < base.positions.size(); ++v) {
        const Vec3f& p = base.positions[v];
        expected.positions[v] = {p.x + (a.positions[v].x - p.x) + (b.positions[v].x - p.x),
                                 p.y + (a.positions[v].y - p.y) + (b.positions[v].y - p.y),
                                 p.z + (a.positions[v].z - p.z) + (b.positions[v].z - p.z)};
      }
      EXPECT_LT(rel_error(base, b, result, expected), 1e-5) << "step " << step;
      EXPECT_LT(rel_error(base, a, result, expected), 1e-5) << "step " << step;
    }
    if (step > 0) {
      // the result may move no more than a few times what the inputs moved in this step
      const double input_step = max_change(b, previous_b);
      const double output_step = max_change(result, previous);
      EXPECT_LT(output_step, 3.0 * input_step + 1e-6)
          << "step " << step << ": the bump moved " << input_step << ", the result " << output_step;
    }
    previous = result;
    previous_b = b;
  }
  EXPECT_GE(disjoint_steps, 5);
}

TEST(MergeFidelity, ADetailRidesACoarseTwistAtItsOwnHeight) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const Deform tw = twist(1.2f);
  const Deform bu = bump(unit({0.6f, 0, 0.8f}), 0.05f, 0.3f);
  const Mesh coarse = deformed(base, tw), fine = deformed(base, bu);
  // the detail's height re-applied along the twisted surface's normals (shared/eval's
  // ideal_frame): a detail keeps its height and follows the surface
  Mesh ideal = coarse;
  const std::vector<Vec3f> normals = vertex_normals(coarse);
  for (std::size_t v = 0; v < base.positions.size(); ++v) {
    const float k = static_cast<float>(distance(fine.positions[v], base.positions[v]));
    const Vec3f n = unit(normals[v]);
    ideal.positions[v] = {coarse.positions[v].x + k * n.x, coarse.positions[v].y + k * n.y,
                          coarse.positions[v].z + k * n.z};
  }
  const Mesh full = merged(base, h, {coarse, fine});
  const Mesh sum = merged(base, h, {coarse, fine}, MergeMethod::sum);
  const double e_full = rel_error(base, fine, full, ideal);
  const double e_sum = rel_error(base, fine, sum, ideal);
  RecordProperty("full", std::to_string(e_full));
  RecordProperty("sum", std::to_string(e_sum));
  EXPECT_LT(e_full, 0.1);
  EXPECT_LT(e_full, 0.25 * e_sum);
}

/// A swirl: a rotation about the axis through the origin and the unit direction c, by an angle
/// that falls off smoothly from `radians` at c to 0 at direction distance r (it spins the
/// sphere's surface about its normal there).
Deform swirl(Vec3f c, float radians, float r) {
  return [=](const Vec3f& p) {
    const Vec3f n = unit(p);
    const float dx = n.x - c.x, dy = n.y - c.y, dz = n.z - c.z;
    const float d2 = (dx * dx + dy * dy + dz * dz) / (r * r);
    const float a = d2 < 1 ? radians * (1 - d2) * (1 - d2) : 0.f;
    // Rodrigues about c
    const float co = std::cos(a), si = std::sin(a), k = dot(c, p) * (1 - co);
    const Vec3f x = cross(c, p);
    return Vec3f{co * p.x + si * x.x + k * c.x, co * p.y + si * x.y + k * c.y,
                 co * p.z + si * x.z + k * c.z};
  };
}

/// The shortest rotation taking unit a to unit b, applied to v.
Vec3f turn(Vec3f a, Vec3f b, Vec3f v) {
  const Vec3f axis = cross(a, b);
  const float c = dot(a, b);
  if (c <= -0.999f) return v;
  const Vec3f av = cross(axis, v), aav = cross(axis, av);
  const float k = 1.f / (1.f + c);
  return {v.x + av.x + k * aav.x, v.y + av.y + k * aav.y, v.z + av.z + k * aav.z};
}

/// The frame ideal of a detail given by its displacement vectors (a sideways one): the coarse
/// edit, then each detail displacement turned by the turn of the surface's normal.
Mesh turned_detail_ideal(const Mesh& base, const Mesh& coarse, const Mesh& fine) {
  const std::vector<Vec3f> n0 = vertex_normals(base), n1 = vertex_normals(coarse);
  Mesh ideal = coarse;
  for (std::size_t v = 0; v < base.positions.size(); ++v) {
    const Vec3f d = sub(fine.positions[v], base.positions[v]);
    ideal.positions[v] = add(coarse.positions[v], turn(unit(n0[v]), unit(n1[v]), d));
  }
  return ideal;
}

struct FullAndSum {
  double full, sum;
};

/// rel_err of `method` (in .full) and of `sum` against turned_detail_ideal (printed).
FullAndSum turned_detail_errors(const Mesh& base, const Hierarchy& h, const Mesh& coarse,
                                const Mesh& fine, MergeMethod method = MergeMethod::full) {
  const Mesh ideal = turned_detail_ideal(base, coarse, fine);
  const FullAndSum e{
      rel_error(base, fine, merged(base, h, {coarse, fine}, method), ideal),
      rel_error(base, fine, merged(base, h, {coarse, fine}, MergeMethod::sum), ideal)};
  std::printf("rel_err against the frame ideal: %s %.4f, sum %.4f\n",
              std::string(to_string(method)).c_str(), e.full, e.sum);
  return e;
}

// A sideways detail (a tiny grab) inside another artist's broad swirl: the frame ideal turns
// its displacement by the turn of the surface's normal, not by the surface's spin about it
// (turned by the spin too: 0.50 rel_err). Also: the grab moves the same way as the swirl
// there, and must not be taken for a partial copy of it (as it was: 0.069).
TEST(MergeFidelity, ASidewaysDetailRidesTheTurnOfTheSurfaceNotItsSpin) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const Vec3f c = unit({0.3f, 0.2f, 0.93f});
  const Mesh coarse = deformed(base, swirl(c, 0.8f, 1.2f));
  const Mesh fine = deformed(base, grab(unit(add(c, Vec3f{0.4f, 0, 0})), {0, 0.02f, 0}, 0.15f));
  const FullAndSum e = turned_detail_errors(base, h, coarse, fine);
  EXPECT_LT(e.full, 0.05);
  EXPECT_LT(e.full, 0.5 * e.sum);
}

/// A pinch: points within r of the surface point c drawn toward it by `amount` of the way at
/// c, with a smooth falloff (a sideways squeeze: the surface hardly turns).
Deform pinch(Vec3f c, float amount, float r) {
  return [=](const Vec3f& p) {
    const Vec3f d = sub(c, p);
    const float d2 = dot(d, d) / (r * r);
    const float k = d2 < 1 ? amount * (1 - d2) * (1 - d2) : 0.f;
    return Vec3f{p.x + k * d.x, p.y + k * d.y, p.z + k * d.z};
  };
}

// A broad lift along the normals (a Wave's crest, an inflate) grows every ring of a curved
// surface by height / radius, here up to 13 %, without being any finer. Read as a fine edit's
// squeeze, it made the swirl under it the carrier, and the swirl turned the lift sideways
// (0.045 against the frame ideal where `sum` is 0.033; the figure's head under a Wave in
// docs/merge-quality.md: 0.139 against 0.006). The lift carries the swirl: 0.009.
TEST(MergeFidelity, ABroadLiftCarriesASwirlInsideIt) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const Vec3f c = unit({0.2f, -0.3f, 0.93f});
  const Mesh coarse = deformed(base, bump(c, 0.13f, 1.4f));
  const Mesh fine = deformed(base, swirl(c, 0.9f, 1.4f));
  const FullAndSum e = turned_detail_errors(base, h, coarse, fine);
  EXPECT_LT(e.full, 0.5 * e.sum);
}

// The other side of the same rule: a pinch squeezes its ring evenly too, but it moves the
// surface sideways and hardly turns it, so that squeeze is what tells it is the finer edit
// under a twist. Riding the frames alone it follows the twist to 0.0003 of its size where
// `sum` misses by 0.37; with the even squeeze not counted for it, 0.0037. `full` hedges it
// toward how the twist's Jacobian, which shears the space along its axis, would move it:
// 0.0057.
TEST(MergeFidelity, APinchUnderATwistRidesIt) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const Mesh coarse = deformed(base, twist(1.2f));
  const Mesh fine = deformed(base, pinch(unit({0.5f, -0.3f, 0.8f}), 0.3f, 0.4f));
  const FullAndSum riding =
      turned_detail_errors(base, h, coarse, fine, MergeMethod::frame_transport);
  EXPECT_LT(riding.full, 0.005 * riding.sum);
  const FullAndSum e = turned_detail_errors(base, h, coarse, fine);
  EXPECT_LT(e.full, 0.03 * e.sum);
}

/// A taper: x and y scaled by 1 - k z (Blender's Simple Deform taper about the z axis), a
/// deformer of the space, not of the surface.
Deform taper(float k) {
  return [=](const Vec3f& p) {
    const float s = 1 - k * p.z;
    return Vec3f{s * p.x, s * p.y, p.z};
  };
}

struct BothIdeals {
  double stack_full, stack_riding, stack_sum, frame_full, frame_sum;
};

/// A detail under a coarse edit (two artists), merged by `full`, `frame-transport` (riding)
/// and `sum`, scored against Blender's stack (the coarse edit applied to the detailed
/// surface) and against the frame ideal (printed).
BothIdeals against_both_ideals(const Mesh& base, const Hierarchy& h, const Deform& detail,
                               const Deform& coarse_edit) {
  const Mesh fine = deformed(base, detail), coarse = deformed(base, coarse_edit);
  Mesh stack = base;
  for (Vec3f& p : stack.positions) p = coarse_edit(detail(p));
  const Mesh frame = turned_detail_ideal(base, coarse, fine);
  const Mesh full = merged(base, h, {coarse, fine});
  const Mesh riding = merged(base, h, {coarse, fine}, MergeMethod::frame_transport);
  const Mesh sum = merged(base, h, {coarse, fine}, MergeMethod::sum);
  const BothIdeals e{rel_error(base, fine, full, stack), rel_error(base, fine, riding, stack),
                     rel_error(base, fine, sum, stack), rel_error(base, fine, full, frame),
                     rel_error(base, fine, sum, frame)};
  std::printf(
      "against the stack full %.4f, frame-transport %.4f, sum %.4f; against the frame "
      "ideal full %.4f, sum %.4f\n",
      e.stack_full, e.stack_riding, e.stack_sum, e.frame_full, e.frame_sum);
  return e;
}

// A volumetric deformer over a detail (docs/merge-quality.md, "The hedge"): Blender's stack
// puts the detail first and deforms it with the space, so on a taper's side, where the
// surface tilts by 31 degrees but does not shrink, the stacked detail keeps its direction;
// the frame ideal tilts it with the surface. Riding the frames alone (frame-transport) lands
// 1.8x addition's distance from the stack (the stacked ideal's rule allows 1.5x); hedged by
// the taper's Jacobian, fitted from the taper's own displacement, `full` is nearer the stack
// than addition and still nearer the frame ideal than addition.
TEST(MergeFidelity, AVolumetricTaperOverADetailIsHedgedTowardItsStack) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const BothIdeals e =
      against_both_ideals(base, h, bump(unit({1, 0, 0.05f}), 0.06f, 0.35f), taper(0.6f));
  EXPECT_GT(e.stack_riding, 1.5 * e.stack_sum) << "not a case the two ideals disagree on";
  EXPECT_LE(e.stack_full, 1.5 * e.stack_sum);
  EXPECT_LT(e.frame_full, e.frame_sum);
}

// A grab whose falloff is steep across the regional fit's radius, over a detail on its slope:
// the affine fit reads the grab's action off the surface wrong (on a shipped duck, a detail
// stretched by 40 % where Blender's stack stretched it by 8 %). Here it left `full` 0.057 from
// the stack, 4.4x addition's distance. The grab is recognised as one (sdk/src/radial_grab.h)
// and its stacked reading is exact: 0.009, and still nearer the frame ideal than addition.
// On an ellipsoid: on a sphere a grab's centre is not determined.
TEST(MergeFidelity, ASteepGrabOverADetailIsReadAsAGrab) {
  Mesh base = make_sphere(20000);
  for (Vec3f& p : base.positions) p = {p.x, 0.8f * p.y, 1.3f * p.z};
  const Hierarchy h = Hierarchy::build(base);
  const BothIdeals e = against_both_ideals(base, h, bump(unit({0.35f, 0.1f, 0.85f}), 0.05f, 0.15f),
                                           grab({0.2f, 0.1f, 1.25f}, {0.1f, 0.2f, 0.25f}, 0.25f));
  EXPECT_LE(e.stack_full, 1.5 * e.stack_sum);
  EXPECT_LT(e.frame_full, e.frame_sum);
}

/// A rough detail: each vertex within r of the unit direction c lifted along its normal by a
/// height in [-h, h] drawn from its index (a crumpling brush), fading to nothing at r.
Mesh crumpled(const Mesh& base, Vec3f c, float h, float r) {
  Mesh m = base;
  for (std::uint32_t v = 0; v < m.positions.size(); ++v) {
    Vec3f& p = m.positions[v];
    const Vec3f n = unit(p);
    const float dx = n.x - c.x, dy = n.y - c.y, dz = n.z - c.z;
    const float d2 = (dx * dx + dy * dy + dz * dz) / (r * r);
    std::uint32_t x = v * 2654435761u;
    x ^= x >> 15;
    const float noise = static_cast<float>(x % 2001u) / 1000.f - 1.f;
    const float k = d2 < 1 ? h * noise * (1 - d2) * (1 - d2) : 0.f;
    p = Vec3f{p.x + k * n.x, p.y + k * n.y, p.z + k * n.z};
  }
  return m;
}

// A crumpling detail where a twist turns the surface by some 50 degrees: faces the detail
// tilts by 40-60 degrees turn past 90 from the base with the twist, although neither artist
// folded them and the detail rides its frame as it should (the frame ideal folds 26 faces),
// so the fold repair must open them (addition folds none). Pulling every face it touched
// toward addition until the last one opened, then smoothing every face that had ever folded,
// spent most of the detail: 0.36 against the frame ideal here, 0.43x addition's error (on a
// crumpled Wuson twisted 120 degrees, 0.73 against addition's 0.76). Each face pulling only
// as hard as it needs and each phase working on the folds left: 0.28 (0.33x). Nudged open by
// the least move of their vertices first (the twist carried the detail there): 0.19 (0.22x).
TEST(MergeFidelity, ACrumpledDetailUnderATwistIsRepairedOnlyWhereItFolds) {
  const Mesh base = make_sphere(20000);
  const Hierarchy h = Hierarchy::build(base);
  const Mesh coarse = deformed(base, twist(2.0f));
  const Mesh fine = crumpled(base, unit({0.6f, 0, 0.8f}), 0.03f, 0.3f);
  const Mesh ideal = turned_detail_ideal(base, coarse, fine);
  const Mesh full = merged(base, h, {coarse, fine}),
             sum = merged(base, h, {coarse, fine}, MergeMethod::sum);
  const Diff c = capture_diff(base, coarse), f = capture_diff(base, fine);
  const Diff* diffs[] = {&c, &f};
  const std::uint32_t folds_full =
      count_new_folds(base, std::span(diffs), capture_diff(base, full));
  const std::uint32_t folds_sum = count_new_folds(base, std::span(diffs), capture_diff(base, sum));
  const std::uint32_t folds_ideal =
      count_new_folds(base, std::span(diffs), capture_diff(base, ideal));
  const double e_full = rel_error(base, fine, full, ideal),
               e_sum = rel_error(base, fine, sum, ideal);
  std::printf("against the frame ideal full %.4f, sum %.4f; new folds full %u, sum %u, ideal %u\n",
              e_full, e_sum, folds_full, folds_sum, folds_ideal);
  EXPECT_GT(folds_ideal, 2 * folds_sum) << "the detail does not fold where the twist turns it";
  EXPECT_LE(folds_full, folds_sum);
  EXPECT_LT(e_full, 0.26 * e_sum);
}

/// The sphere cut along the plane y = 0 for x > 0: the faces on the y < 0 side get their own
/// copies of the vertices on the cut, so the mesh has a split seam of coincident vertices.
Mesh split_seam(const Mesh& m, std::vector<std::pair<std::uint32_t, std::uint32_t>>& twins) {
  Mesh out = m;
  std::map<std::uint32_t, std::uint32_t> copy;
  auto on_cut = [&](std::uint32_t v) {
    const Vec3f& p = m.positions[v];
    return std::fabs(p.y) < 1e-6f && p.x > 0.05f;
  };
  for (Triangle& t : out.triangles) {
    const float cy = m.positions[t[0]].y + m.positions[t[1]].y + m.positions[t[2]].y;
    if (cy >= 0) continue;
    for (std::uint32_t& v : t) {
      if (!on_cut(v)) continue;
      auto [it, fresh] = copy.try_emplace(v, static_cast<std::uint32_t>(out.positions.size()));
      if (fresh) {
        out.positions.push_back(m.positions[v]);
        twins.emplace_back(v, it->second);
      }
      v = it->second;
    }
  }
  return out;
}

TEST(MergeFidelity, SplitSeamsMovedTogetherStayClosed) {
  const Mesh sphere = make_sphere(20000);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> twins;
  const Mesh base = split_seam(sphere, twins);
  ASSERT_GT(twins.size(), 10u) << "the test mesh has no seam";
  const Hierarchy h = Hierarchy::build(base);
  // a twist through the seam and a bump on it: both functions of position, so each artist
  // moves the two copies of a seam vertex together
  const Mesh coarse = deformed(base, twist(1.0f));
  const Mesh fine = deformed(base, bump(unit({0.8f, 0, 0.6f}), 0.05f, 0.4f));
  for (const auto& [v, w] : twins) {
    ASSERT_EQ(coarse.positions[v], coarse.positions[w]);
    ASSERT_EQ(fine.positions[v], fine.positions[w]);
  }
  const Mesh result = merged(base, h, {coarse, fine});
  std::size_t moved = 0;
  for (const auto& [v, w] : twins) {
    EXPECT_EQ(result.positions[v], result.positions[w]) << "seam vertex " << v << " / " << w;
    moved += !(result.positions[v] == base.positions[v]);
  }
  EXPECT_GT(moved, 10u);
}

/// A session in lockstep, as the peers play it: each tick every artist submits its local
/// mesh, makes its next `run` strokes, and rebases them onto the version merged from the
/// submits. Returns the last version, once every stroke is merged.
Mesh lockstep_session(const Mesh& base, const Hierarchy& h,
                      const std::vector<std::vector<Stroke>>& scripts, MergeMethod method,
                      std::size_t run = 1) {
  const std::size_t ticks = scripts.front().size() / run;
  Mesh version = base;
  std::vector<Mesh> local(scripts.size(), base);
  for (std::size_t t = 0; t <= ticks; ++t) {
    const std::vector<Mesh> sent = local;
    if (t < ticks)
      for (std::size_t k = 0; k < local.size(); ++k)
        for (std::size_t r = 0; r < run; ++r)
          apply_stroke(local[k], scripts[k][t * run + r], &h.topology());
    version = merged(version, h, sent, method);
    for (std::size_t k = 0; k < local.size(); ++k)
      local[k] = t < ticks ? merged(sent[k], h, {version, local[k]}, method) : version;
  }
  return version;
}

/// Opposed face pairs at the end of lockstep sessions of three artists on a 320K-face sphere
/// (one per seed) under `full` and under plain addition, printed.
std::pair<std::uint32_t, std::uint32_t> lockstep_creases(std::span<const std::uint64_t> seeds,
                                                         std::uint64_t prime, std::uint32_t strokes,
                                                         std::size_t run) {
  const std::uint32_t faces = 320000, artists = 3;
  const Mesh base = make_sphere(faces);
  const Hierarchy h = Hierarchy::build(base);
  std::uint32_t full = 0, sum = 0;
  for (std::uint64_t seed : seeds) {
    std::vector<std::vector<Stroke>> scripts;
    for (std::uint32_t k = 0; k < artists; ++k)
      scripts.push_back(scripted_strokes(base, seed * prime + k, strokes, /*paint=*/false));
    const std::uint32_t f =
        count_opposed_face_pairs(lockstep_session(base, h, scripts, MergeMethod::full, run));
    const std::uint32_t s =
        count_opposed_face_pairs(lockstep_session(base, h, scripts, MergeMethod::sum, run));
    std::printf("runs of %zu, seed %llu: opposed face pairs full %u, sum %u\n", run,
                static_cast<unsigned long long>(seed), f, s);
    full += f;
    sum += s;
  }
  return {full, sum};
}

// A session merges and rebases short runs of strokes of one scale every sync: a grab beside a
// twist, an inflate across a crease. Neither is the other's frame, and two artists pushing the
// same way by similar amounts are two intents, not one. Carried halfway through each other's
// steep rotations, or counted partly as one where their ratio changed, such strokes crease
// the surface where they meet: `full` ends the session with no more creases than the same
// session merging and rebasing by plain addition (10 % slack; the counts are printed).
TEST(MergeFidelity, EditsOfOneScaleAddInsteadOfCreasingEachOther) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  // Smaller sessions crease nowhere under either method, so nothing would be compared; the
  // release phase runs it (the merges themselves are covered under the sanitizers above).
  GTEST_SKIP() << "minutes under the sanitizers at the size where creases appear";
#endif
  for (std::uint64_t seed : {1u, 3u}) {
    const std::uint64_t one[1] = {seed};
    const auto [full, sum] = lockstep_creases(one, 104729, 100, 1);
    EXPECT_LE(full, sum + sum / 10 + 4) << "seed " << seed;
  }
}

// Each rebase holds a run of strokes at mixed scales (a fine detail beside a broad inflate,
// as a peer that submits every few strokes rebases them): a diff is coarse in one place and
// fine in another. A broad stroke carried, vertex by vertex, through the rough rotations of a
// detail beside it was sheared into creases, and so was a groove wherever two inflates along
// one normal were within a tenth of each other: over these eight sessions `full` ended with 5x
// addition's creases (20,055 against 4,019). With the carrying rotation read at the scale of
// the displacement it carries and sameness kept to float rounding, 2.1x; the fold repair then
// pulled whole regions toward one artist's edit where strokes met and creased the pull's edge,
// and smoothing the displacement there instead brought it to 0.84x (3,390; on seeds 9-16
// 0.92x). Carrying only where a vertex's faces agree on the carrier's turn (a fold is no
// frame) moved it to 0.98x (3,959; seeds 9-16 0.94x): these counts swing by a sixth with any
// change to the merge, as the sessions diverge. The test holds `full` within addition's count
// plus a tenth.
TEST(MergeFidelity, RunsOfStrokesAtMixedScalesRebaseWithoutCreasing) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "minutes under the sanitizers at the size where creases appear";
#endif
  const std::uint64_t seeds[] = {1, 2, 3, 4, 5, 6, 7, 8};
  const auto [full, sum] = lockstep_creases(seeds, 7919, 120, 4);
  std::printf("runs of 4, eight sessions: opposed face pairs full %u, sum %u\n", full, sum);
  EXPECT_LE(full, sum + sum / 10);
}

}  // namespace
}  // namespace csculpt
