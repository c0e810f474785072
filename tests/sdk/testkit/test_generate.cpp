// The built-in test-mesh generators (csculpt/testkit/generate.h): make_sphere gives a valid closed,
// consistently oriented unit sphere with the documented counts, the face count closest to the
// one asked for; vertex_normals; each stroke kind does what it says and nothing outside its
// radius; scripted_strokes is deterministic for a seed, gives the count asked for and only the
// kinds asked for; bad arguments are refused rather than turned into NaN or a crash.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/hierarchy.h"
#include "csculpt/mesh.h"
#include "csculpt/testkit/generate.h"
#include "csculpt/vec3.h"
#include "test_meshes.h"
#include "test_strokes.h"

namespace csculpt {
namespace {

using test::stroke;

using test::first_difference;

std::uint32_t sphere_k(std::uint32_t faces) {
  return static_cast<std::uint32_t>(std::lround(std::sqrt(static_cast<double>(faces) / 20.0)));
}

/// Every directed edge exactly once and its reverse exactly once (closed, 2-manifold at the
/// edges, consistently oriented), no repeated triangle, positive signed volume (outward).
void expect_closed_oriented(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> half_edges;
  std::set<std::array<std::uint32_t, 3>> faces;
  double volume6 = 0;
  for (const Triangle& t : m.triangles) {
    for (int i = 0; i < 3; ++i) ++half_edges[{t[i], t[(i + 1) % 3]}];
    std::array<std::uint32_t, 3> sorted = t;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_TRUE(faces.insert(sorted).second) << "repeated triangle";
    volume6 += dot(m.positions[t[0]], cross(m.positions[t[1]], m.positions[t[2]]));
  }
  std::size_t bad = 0;
  for (const auto& [e, n] : half_edges) {
    const auto reverse = half_edges.find({e.second, e.first});
    if (n != 1 || reverse == half_edges.end() || reverse->second != 1) ++bad;
  }
  EXPECT_EQ(bad, 0u) << "half-edges used other than once, or without their twin";
  EXPECT_GT(volume6, 0) << "faces wound inwards";
  // a closed genus-0 surface: V - E + F = 2
  const auto edges = static_cast<long>(half_edges.size() / 2);
  EXPECT_EQ(static_cast<long>(m.vertex_count()) - edges + static_cast<long>(m.face_count()), 2);
}

float distance(Vec3f a, Vec3f b) {
  return std::sqrt(dot(sub(a, b), sub(a, b)));
}

// ---- make_sphere ---------------------------------------------------------------------------

TEST(GenerateSphere, IsAValidClosedOrientedUnitSphereWithTheDocumentedCounts) {
  for (std::uint32_t target : {20u, 80u, 500u, 1280u, 5000u, 20000u}) {
    SCOPED_TRACE("target " + std::to_string(target));
    const Mesh m = make_sphere(target);
    const std::uint32_t k = sphere_k(target);
    EXPECT_EQ(m.face_count(), 20u * k * k);
    EXPECT_EQ(m.vertex_count(), 10u * k * k + 2);
    EXPECT_TRUE(m.channels.empty());
    EXPECT_NO_THROW(validate(m, "sphere"));
    for (const Vec3f& p : m.positions) ASSERT_NEAR(std::sqrt(dot(p, p)), 1.f, 1e-6f);
    expect_closed_oriented(m);
    // no two vertices in one place (shared edge points are shared, not duplicated)
    std::set<std::array<float, 3>> places;
    for (const Vec3f& p : m.positions) places.insert({p.x, p.y, p.z});
    EXPECT_EQ(places.size(), m.vertex_count());
  }
}

TEST(GenerateSphere, ExactCountsAreHitAndTheSmallestIsTheIcosahedron) {
  for (std::uint32_t k = 1; k <= 12; ++k)
    EXPECT_EQ(make_sphere(20 * k * k).face_count(), 20 * k * k);
  for (std::uint32_t tiny : {0u, 1u, 19u, 21u}) {
    const Mesh m = make_sphere(tiny);
    EXPECT_EQ(m.face_count(), 20u) << tiny;
    EXPECT_EQ(m.vertex_count(), 12u) << tiny;
  }
}

TEST(GenerateSphere, TheFaceCountIsTheClosestToTheTarget) {
  // "k chosen so the face count is closest to target_faces": no other k is strictly closer
  std::vector<std::uint32_t> wrong;
  for (std::uint32_t target = 0; target <= 1000; ++target) {
    const auto faces = static_cast<long>(make_sphere(target).face_count());
    const auto k = static_cast<long>(std::lround(std::sqrt(static_cast<double>(faces) / 20.0)));
    const long t = target;
    for (long other : {k - 1, k + 1}) {
      if (other >= 1 && std::labs(20 * other * other - t) < std::labs(faces - t)) {
        wrong.push_back(target);
        break;
      }
    }
  }
  EXPECT_TRUE(wrong.empty()) << wrong.size() << " targets get a farther face count, the first "
                             << (wrong.empty() ? 0 : wrong[0]) << " gets "
                             << (wrong.empty() ? 0 : make_sphere(wrong[0]).face_count())
                             << " faces (k rounded in sqrt space, not by face count)";
}

TEST(GenerateSphere, IsDeterministicAndMaterialsAreTheBuiltInChannels) {
  const Mesh a = make_sphere(2000);
  EXPECT_EQ(first_difference(a, make_sphere(2000)), "");
  const Mesh m = make_sphere(2000, true);
  EXPECT_EQ(m.positions, a.positions);
  EXPECT_EQ(m.triangles, a.triangles);
  const std::vector<ChannelDesc> expected = material_channels();
  ASSERT_EQ(m.channels.size(), expected.size());
  for (std::size_t c = 0; c < expected.size(); ++c) {
    const Channel& ch = m.channels[c];
    EXPECT_EQ(ch.desc, expected[c]);
    ASSERT_EQ(ch.values.size(), m.vertex_count() * ch.desc.width);
    const float fill = ch.desc.name == "metallic"    ? default_metallic
                       : ch.desc.name == "roughness" ? default_roughness
                                                     : default_albedo;  // grey rough dielectric
    for (float v : ch.values) ASSERT_EQ(v, fill) << ch.desc.name;
  }
  EXPECT_NO_THROW(validate(m, "sphere with materials"));
}

// ---- vertex_normals ------------------------------------------------------------------------

TEST(GenerateNormals, AreUnitAndOutwardOnTheSphereAndZeroOffTheSurface) {
  Mesh m = make_sphere(1280);
  const std::vector<Vec3f> n = vertex_normals(m);
  ASSERT_EQ(n.size(), m.vertex_count());
  for (std::size_t v = 0; v < n.size(); ++v) {
    ASSERT_NEAR(std::sqrt(dot(n[v], n[v])), 1.f, 1e-5f) << v;
    ASSERT_GT(dot(n[v], m.positions[v]), 0.99f) << v;  // the sphere's normal is the position
  }
  // vertices only on a degenerate (collinear) face, and a vertex on no face: zero normals
  const auto first = static_cast<std::uint32_t>(m.vertex_count());
  for (float x : {5.f, 6.f, 7.f, 9.f}) m.positions.push_back({x, x, x});
  m.triangles.push_back({first, first + 1, first + 2});
  const std::vector<Vec3f> with_extra = vertex_normals(m);
  for (std::uint32_t v = first; v < first + 4; ++v) EXPECT_EQ(with_extra[v], (Vec3f{0, 0, 0})) << v;
  for (std::uint32_t v = 0; v < first; ++v) ASSERT_EQ(with_extra[v], n[v]);
}

// ---- apply_stroke --------------------------------------------------------------------------

TEST(GenerateStroke, GrabMovesAlongTheAxisWithTheFalloffAndNothingOutsideTheRadius) {
  const Mesh base = make_sphere(5000);
  const Vec3f center = base.positions[0];
  Mesh m = base;
  Stroke s = stroke(Stroke::Kind::grab, center, 0.5f, 0.2f);
  s.axis = {0, 0, 2};  // normalised by the stroke
  apply_stroke(m, s);
  std::size_t moved = 0;
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const float d = distance(base.positions[v], center);
    const Vec3f delta = sub(m.positions[v], base.positions[v]);
    if (d >= s.radius) {
      ASSERT_EQ(m.positions[v], base.positions[v]) << "outside the radius: " << v;
      continue;
    }
    const float t = 1.f - (d / s.radius) * (d / s.radius);
    EXPECT_EQ(delta.x, 0.f);
    EXPECT_EQ(delta.y, 0.f);
    EXPECT_NEAR(delta.z, s.strength * s.radius * t * t, 1e-6f) << v;
    moved += delta.z > 0 ? 1 : 0;
  }
  EXPECT_GT(moved, 10u);
  EXPECT_NEAR(m.positions[0].z - base.positions[0].z, s.strength * s.radius, 1e-6f)
      << "full strength at the centre";
}

TEST(GenerateStroke, InflateMovesAlongTheNormalAndTwistKeepsDistancesToTheAxisPoint) {
  const Mesh base = make_sphere(5000);
  const Vec3f center = base.positions[3];
  Mesh inflated = base;
  apply_stroke(inflated, stroke(Stroke::Kind::inflate, center, 0.4f, 0.1f));
  Mesh twisted = base;
  Stroke twist = stroke(Stroke::Kind::twist, center, 0.6f, 0.7f);
  twist.axis = center;
  apply_stroke(twisted, twist);
  std::size_t grown = 0, turned = 0;
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    const Vec3f& p = base.positions[v];
    const float r = std::sqrt(dot(inflated.positions[v], inflated.positions[v]));
    EXPECT_GE(r, 1.f - 1e-6f) << "inflate moves outwards on a sphere";
    grown += r > 1.f + 1e-4f ? 1 : 0;
    EXPECT_NEAR(distance(twisted.positions[v], center), distance(p, center), 1e-5f)
        << "a rotation about a line through the centre";
    turned += twisted.positions[v] == p ? 0 : 1;
    if (distance(p, center) >= 0.6f) {
      EXPECT_EQ(twisted.positions[v], p);
      EXPECT_EQ(inflated.positions[v], p);
    }
  }
  EXPECT_GT(grown, 10u);
  EXPECT_GT(turned, 10u);
}

TEST(GenerateStroke, PaintAddsTheMaterialChannelsAndBlendsOnlyInsideTheRadius) {
  const Mesh base = make_sphere(2000);
  Mesh m = base;
  Stroke paint = stroke(Stroke::Kind::paint, base.positions[0], 0.5f, 1.f);
  apply_stroke(m, paint);
  EXPECT_EQ(m.positions, base.positions) << "paint leaves the shape";
  ASSERT_EQ(m.channels.size(), material_channels().size());
  EXPECT_NO_THROW(validate(m, "painted"));
  const Mesh grey = make_sphere(2000, true);
  const float* albedo =
      m.channels[static_cast<std::size_t>(m.find_channel("albedo"))].values.data();
  const float* metal =
      m.channels[static_cast<std::size_t>(m.find_channel("metallic"))].values.data();
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    if (distance(base.positions[v], paint.center) >= paint.radius) {
      ASSERT_EQ(albedo[3 * v], 0.5f) << "outside the radius: the default grey";
      ASSERT_EQ(metal[v], 0.f);
    }
  }
  EXPECT_FLOAT_EQ(albedo[0], paint.albedo[0]) << "full strength at the centre";
  EXPECT_FLOAT_EQ(metal[0], paint.metallic);
  // a second paint on a mesh that has the channels keeps them (no duplicates)
  Mesh again = grey;
  apply_stroke(again, paint);
  EXPECT_EQ(again.channels.size(), grey.channels.size());
  EXPECT_EQ(first_difference(again, m), "");
}

TEST(GenerateStroke, SmoothNeedsTheTopologyAndFlattensTowardsTheNeighbours) {
  Mesh base = make_sphere(2000);
  Mesh noisy = base;
  apply_stroke(noisy, stroke(Stroke::Kind::detail, base.positions[0], 0.5f, 0.08f));
  Mesh untouched = noisy;
  apply_stroke(untouched, stroke(Stroke::Kind::smooth, base.positions[0], 0.5f, 1.f));
  EXPECT_EQ(first_difference(untouched, noisy), "") << "no topology: no smoothing";
  const Topology topo =
      Topology::build(static_cast<std::uint32_t>(noisy.vertex_count()), noisy.triangles);
  Mesh smoothed = noisy;
  apply_stroke(smoothed, stroke(Stroke::Kind::smooth, base.positions[0], 0.5f, 1.f), &topo);
  // the umbrella Laplacian (a vertex to its neighbours' mean) shrinks in the brush's core;
  // outside the brush nothing moves
  auto core_laplacian = [&](const Mesh& m) {
    double sum = 0;
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      if (distance(base.positions[v], base.positions[0]) >= 0.3f) continue;
      const auto row = topo.vertex_vertices.row(v);
      Vec3f mean{0, 0, 0};
      for (std::uint32_t u : row) mean = add(mean, m.positions[u]);
      mean = scale(mean, 1.f / static_cast<float>(row.size()));
      sum += dot(sub(m.positions[v], mean), sub(m.positions[v], mean));
    }
    return sum;
  };
  EXPECT_LT(core_laplacian(smoothed), core_laplacian(noisy));
  for (std::size_t v = 0; v < base.vertex_count(); ++v) {
    if (distance(noisy.positions[v], base.positions[0]) >= 0.5f) {
      ASSERT_EQ(smoothed.positions[v], noisy.positions[v]) << v;
    }
  }
}

TEST(GenerateStroke, ADegenerateRadiusIsRefusedOrHarmless) {
  // radius 0 (or negative) is a bad argument: apply_stroke must either refuse it with
  // InvalidInput or leave a valid mesh; it must not write NaN
  const Mesh base = make_sphere(500, true);
  for (auto kind : {Stroke::Kind::grab, Stroke::Kind::inflate, Stroke::Kind::detail,
                    Stroke::Kind::twist, Stroke::Kind::bend, Stroke::Kind::paint}) {
    for (float radius : {0.f, -0.5f}) {
      SCOPED_TRACE(test::kind_name(kind) + " of radius " + std::to_string(radius));
      Mesh m = base;
      try {
        apply_stroke(m, stroke(kind, base.positions[0], radius, 0.5f));
      } catch (const InvalidInput&) {
        continue;
      }
      EXPECT_NO_THROW(validate(m, "after the stroke"));
    }
  }
}

// ---- scripted_strokes ----------------------------------------------------------------------

bool same_strokes(const std::vector<Stroke>& a, const std::vector<Stroke>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Stroke &x = a[i], &y = b[i];
    const bool same = x.kind == y.kind && x.center == y.center && x.radius == y.radius &&
                      x.strength == y.strength && x.axis == y.axis && x.direction == y.direction &&
                      x.frequency == y.frequency && x.albedo == y.albedo &&
                      x.roughness == y.roughness && x.metallic == y.metallic;
    if (!same) return false;
  }
  return true;
}

TEST(GenerateScript, IsDeterministicForASeedAndDiffersBetweenSeeds) {
  const Mesh base = make_sphere(2000);
  for (std::uint64_t seed : {0ull, 1ull, 42ull, 0xffffffffffffffffull}) {
    const auto a = scripted_strokes(base, seed, 30);
    EXPECT_TRUE(same_strokes(a, scripted_strokes(base, seed, 30))) << seed;
    EXPECT_FALSE(same_strokes(a, scripted_strokes(base, seed + 1, 30))) << seed;
    // a longer script starts with the shorter one
    const auto longer = scripted_strokes(base, seed, 40);
    EXPECT_TRUE(same_strokes(a, {longer.begin(), longer.begin() + 30})) << seed;
  }
}

TEST(GenerateScript, GivesTheCountAndKindsAskedForAroundTheSurface) {
  const Mesh base = make_sphere(2000);
  const float diag = bbox_diagonal(base.positions);
  for (std::uint32_t count : {0u, 1u, 7u, 200u}) {
    EXPECT_EQ(scripted_strokes(base, 5, count).size(), count);
  }
  std::set<Stroke::Kind> kinds;
  for (const Stroke& s : scripted_strokes(base, 5, 200)) {
    kinds.insert(s.kind);
    bool on_vertex = false;
    for (const Vec3f& p : base.positions) on_vertex = on_vertex || p == s.center;
    EXPECT_TRUE(on_vertex) << "centred on a vertex of the mesh";
    EXPECT_GT(s.radius, 0.f);
    EXPECT_LE(s.radius, 0.3f * diag) << "at most half the model";
    EXPECT_NEAR(std::sqrt(dot(s.axis, s.axis)), 1.f, 1e-5f);
  }
  EXPECT_EQ(kinds,
            (std::set<Stroke::Kind>{Stroke::Kind::grab, Stroke::Kind::inflate, Stroke::Kind::detail,
                                    Stroke::Kind::twist, Stroke::Kind::paint}));
  for (const Stroke& s : scripted_strokes(base, 5, 200, false))
    EXPECT_NE(s.kind, Stroke::Kind::paint) << "paint = false";
  // the script sculpts a valid mesh
  Mesh m = make_sphere(2000, true);
  for (const Stroke& s : scripted_strokes(m, 5, 60)) apply_stroke(m, s);
  EXPECT_NO_THROW(validate(m, "sculpted"));
  EXPECT_NE(m.positions, base.positions);
}

TEST(GenerateScriptDeathTest, AnEmptyMeshIsRefusedNotACrash) {
  // strokes are anchored at vertices: with none there is nothing to anchor to; the call must
  // throw InvalidInput (it must not divide by zero or read past the positions)
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_TRUE(scripted_strokes(Mesh{}, 1, 0).empty()) << "no strokes asked: none given";
  EXPECT_EXIT(
      {
        try {
          scripted_strokes(Mesh{}, 1, 3);
        } catch (const InvalidInput&) {
          std::_Exit(0);
        }
        std::_Exit(1);
      },
      ::testing::ExitedWithCode(0), "");
}

}  // namespace
}  // namespace csculpt
