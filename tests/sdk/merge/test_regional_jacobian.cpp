// The carriers' regional Jacobians (sdk/src/regional_jacobian.h): what the hedge of `full`
// reads a coarse edit's action off the surface from.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "csculpt/testkit/generate.h"
#include "regional_jacobian.h"
#include "worker_pool.h"

namespace csculpt::detail {
namespace {

struct Fitted {
  Mat3d a;
  double vouched = 0;
};

/// Fits u(p) = (J - I) p + t over every vertex of `mesh` as samples (radius r) and reads the
/// Jacobian back at position `at`.
template <class Field>
Fitted fit_and_read(const Mesh& mesh, const Field& u, double r, const Vec3d& at,
                    const Vec3d& normal_everywhere = {}) {
  std::vector<std::uint32_t> samples(mesh.positions.size());
  for (std::uint32_t v = 0; v < samples.size(); ++v) samples[v] = v;
  const std::vector<Vec3f> normals = vertex_normals(mesh);
  RegionalJacobians jacobians;
  jacobians.prepare(mesh.positions, {samples, r}, 1);
  jacobians.need(at);
  WorkerPool pool(2);
  jacobians.plan(
      [&](std::uint32_t v) {
        return length(normal_everywhere) > 0 ? normal_everywhere : widen(unit(normals[v]));
      },
      pool);
  jacobians.fit(
      0, [&](std::uint32_t v) { return u(widen(mesh.positions[v])); }, pool);
  RegionalJacobians::Reading reading;
  jacobians.gather(at, reading);
  Fitted f;
  f.vouched = jacobians.at(reading, 0, f.a);
  return f;
}

double max_difference(const Mat3d& a, const Mat3d& b) {
  double m = 0;
  for (int k = 0; k < 9; ++k) m = std::max(m, std::fabs(a.m[k] - b.m[k]));
  return m;
}

// On a curved surface the samples spread in three dimensions, so an affine displacement's
// whole Jacobian is recovered, its normal column included (what a taper's side or a Cast does
// to a detail standing on the surface).
TEST(RegionalJacobian, RecoversAnAffineDeformationOnACurvedSurface) {
  const Mesh sphere = make_sphere(8000);
  Mat3d j;
  j.m = {1.2, 0.1, -0.3, 0.05, 0.8, 0.2, -0.1, 0.25, 1.1};
  const auto u = [&](const Vec3d& p) { return add(sub(apply(j, p), p), Vec3d{0.3, -0.2, 0.1}); };
  const Fitted f = fit_and_read(sphere, u, 0.4, Vec3d{0.6, 0.0, 0.8});
  EXPECT_NEAR(f.vouched, 1.0, 1e-12);
  // The ridge that fixes a flat region's normal column pulls a gently curved one's a little
  // toward the even scaling: 0.021 here, a patch of radius 0.4 on the unit sphere.
  EXPECT_LT(max_difference(f.a, j), 0.03);
}

// A plane shows no normal column: the fit takes the region's even scaling along its normal
// (the geometric mean of its tangent stretches), as a taper scales its side, and leaves the
// tangent columns as measured.
TEST(RegionalJacobian, AFlatRegionScalesItsThicknessAsItsSurface) {
  Mesh plane;
  for (int y = 0; y <= 20; ++y)
    for (int x = 0; x <= 20; ++x)
      plane.positions.push_back(
          {static_cast<float>(x) / 10 - 1, static_cast<float>(y) / 10 - 1, 0});
  for (std::uint32_t y = 0; y < 20; ++y)
    for (std::uint32_t x = 0; x < 20; ++x) {
      const std::uint32_t a = y * 21 + x;
      plane.triangles.push_back({a, a + 1, a + 22});
      plane.triangles.push_back({a, a + 22, a + 21});
    }
  const auto u = [](const Vec3d& p) { return Vec3d{-0.36 * p.x, -0.19 * p.y, 0.0}; };
  const Fitted f = fit_and_read(plane, u, 0.5, Vec3d{0, 0, 0}, Vec3d{0, 0, 1});
  EXPECT_NEAR(f.a.m[0], 0.64, 1e-9);
  EXPECT_NEAR(f.a.m[4], 0.81, 1e-9);
  EXPECT_NEAR(f.a.m[8], std::sqrt(0.64 * 0.81), 1e-3);  // 0.72
}

// Samples far away vouch for nothing: the hedge fades out where no fit reaches.
TEST(RegionalJacobian, NoSamplesNearMeansNoReading) {
  const Mesh sphere = make_sphere(2000);
  const auto u = [](const Vec3d& p) { return scale(p, 0.1); };
  const Fitted f = fit_and_read(sphere, u, 0.3, Vec3d{5, 5, 5});
  EXPECT_EQ(f.vouched, 0.0);
  EXPECT_EQ(max_difference(f.a, kIdentity3), 0.0);
}

}  // namespace
}  // namespace csculpt::detail
