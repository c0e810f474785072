// A grab recognised in a diff (sdk/src/radial_grab.h): where the hedge of `full` reads a
// grab's action off the surface exactly instead of fitting it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "csculpt/testkit/generate.h"
#include "radial_grab.h"

namespace csculpt::detail {
namespace {

/// A Warp-like grab: translation t scaled by a smoothstep of the distance from c, zero from r.
Vec3d warp(const Vec3d& p, const Vec3d& c, const Vec3d& t, double r) {
  const double x = std::max(0.0, 1 - length(sub(p, c)) / r);
  return scale(t, x * x * (3 - 2 * x));
}

struct Moved {
  std::vector<std::uint32_t> vertices;
  std::vector<Vec3d> by;  ///< per vertex of the mesh
};

template <class Field>
Moved moved_by(const Mesh& mesh, const Field& u) {
  Moved m;
  m.by.resize(mesh.positions.size());
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
    m.by[v] = u(v, widen(mesh.positions[v]));
    if (length(m.by[v]) > 0) m.vertices.push_back(v);
  }
  return m;
}

bool fit(RadialGrab& grab, const Mesh& mesh, const Moved& m) {
  return grab.fit(mesh.positions, m.vertices, [&](std::uint32_t v) { return m.by[v]; });
}

/// The sphere stretched into an ellipsoid (semi-axes 1, 0.8, 1.3): no sphere about any axis.
Mesh ellipsoid() {
  Mesh m = make_sphere(8000);
  for (Vec3f& p : m.positions) p = {p.x, 0.8f * p.y, 1.3f * p.z};
  return m;
}

const Vec3d kCentre{0.2, 0.1, 1.45}, kPull{0.05, 0.15, 0.05};
constexpr double kRadius = 0.6;

// A grab whose centre lies off the surface (in front of it, as a Warp's empty may): the fit
// finds the falloff from the moved vertices alone, and a detail standing on the surface is
// carried as the grab moves the space there, to a hundredth of the detail (the centre is found
// to 0.003, the falloff to a polynomial's accuracy).
TEST(RadialGrab, ReadsAGrabWithItsCentreOffTheSurface) {
  const Mesh mesh = ellipsoid();
  const Moved m = moved_by(
      mesh, [&](std::uint32_t, const Vec3d& p) { return warp(p, kCentre, kPull, kRadius); });
  RadialGrab grab;
  ASSERT_TRUE(fit(grab, mesh, m));
  double worst = 0;
  for (const std::uint32_t v : m.vertices) {
    const Vec3d p = widen(mesh.positions[v]);
    const Vec3d d = scale(p, 0.03 / length(p));  // a detail 0.03 high, about the normal
    const Vec3d stacked =
        add(d, sub(warp(add(p, d), kCentre, kPull, kRadius), warp(p, kCentre, kPull, kRadius)));
    worst = std::max(worst, length(sub(grab.carry(p, d), stacked)));
  }
  EXPECT_LT(worst, 0.01 * 0.03);
}

// On a sphere the same grab shows no centre: every point of the axis through the sphere's
// centre and the grab's explains the displacements exactly, each with its own falloff and its
// own action off the surface. The grab is refused (the merge falls back to the regional fit).
TEST(RadialGrab, ASphereAboutTheGrabHidesItsCentre) {
  const Mesh sphere = make_sphere(8000);
  const Moved m = moved_by(sphere, [&](std::uint32_t, const Vec3d& p) {
    return warp(p, {0.2, 0.1, 1.15}, kPull, kRadius);
  });
  RadialGrab grab;
  EXPECT_FALSE(fit(grab, sphere, m));
}

// Not grabs: displacements that are not parallel (a twist), and parallel ones whose lengths
// are no function of one distance (a Hook's per-vertex weights, here a pseudo-random weight
// per vertex) or two grabs in one diff.
TEST(RadialGrab, RefusesWhatIsNoGrab) {
  const Mesh sphere = ellipsoid();
  RadialGrab grab;
  const Moved twist = moved_by(sphere, [](std::uint32_t, const Vec3d& p) {
    const double a = 0.5 * p.z;
    return Vec3d{std::cos(a) * p.x - std::sin(a) * p.y - p.x,
                 std::sin(a) * p.x + std::cos(a) * p.y - p.y, 0};
  });
  EXPECT_FALSE(fit(grab, sphere, twist));
  const Moved hook = moved_by(sphere, [](std::uint32_t v, const Vec3d& p) {
    const double w = p.z > 0.5 ? static_cast<double>((v * 2654435761u) % 1000u) / 1000.0 : 0.0;
    return scale(Vec3d{0, 0.1, 0}, w);
  });
  EXPECT_FALSE(fit(grab, sphere, hook));
  const Vec3d t{0, 0, 0.1};
  const Moved two = moved_by(sphere, [&](std::uint32_t, const Vec3d& p) {
    return add(warp(p, {0.6, 0, 0.8}, t, 0.4), warp(p, {-0.6, 0, 0.8}, scale(t, 0.5), 0.4));
  });
  EXPECT_FALSE(fit(grab, sphere, two));
  EXPECT_FALSE(grab.valid());
}

// Few moved vertices are a detail, not a grab.
TEST(RadialGrab, AFewVerticesAreNoGrab) {
  const Mesh sphere = ellipsoid();
  RadialGrab grab;
  const Moved tiny = moved_by(sphere, [&](std::uint32_t, const Vec3d& p) {
    return warp(p, {0, 0, 1}, {0, 0.01, 0}, 0.05);
  });
  ASSERT_LT(tiny.vertices.size(), 32u);
  EXPECT_FALSE(fit(grab, sphere, tiny));
}

}  // namespace
}  // namespace csculpt::detail
