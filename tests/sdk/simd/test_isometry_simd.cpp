// The SSE2 face-rotation kernel (two faces per register) against the scalar kernel: every
// lane must give the scalar result bit for bit, whichever branch each lane takes (small and
// large rotations, trace of either sign, degenerate faces in either lane).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <numbers>

#include "csculpt/testkit/random.h"
#include "simd/vertex_isometry_kernel.h"

namespace csculpt {
namespace {

#if defined(__SSE2__)
bool same_bits(const Quat& a, const Quat& b) {
  return std::memcmp(&a, &b, sizeof(Quat)) == 0;
}

/// The kernels read their points in place, through pointers.
template <int N>
struct PointsOf {
  const Vec3f* p[N][6];
};
template <int N>
PointsOf<N> points_of(const Vec3f (&p)[N][6]) {
  PointsOf<N> out;
  for (int f = 0; f < N; ++f)
    for (int i = 0; i < 6; ++i) out.p[f][i] = &p[f][i];
  return out;
}

TEST(IsometryFaceRotationSimd, TwoLanesEqualTheScalarKernelBitForBit) {
  SplitMix64 rng;
  rng.state = 20261124;
  int both_small = 0, other = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    Vec3f p[2][6];
    for (int f = 0; f < 2; ++f) {
      const double extent = std::exp(rng.range(std::log(1e-3), std::log(1e3)));
      // rotation about a random axis by an angle that is small most of the time
      const double angle = (trial % 3 == 0 ? rng.range(0, std::numbers::pi) : rng.range(0, 0.3)) *
                           ((trial & 1) ? 1 : -1);
      double ax = rng.range(-1, 1), ay = rng.range(-1, 1), az = rng.range(-1, 1);
      const double n = std::sqrt(ax * ax + ay * ay + az * az) + 1e-12;
      ax /= n, ay /= n, az /= n;
      const double c = std::cos(angle), s = std::sin(angle);
      for (int i = 0; i < 3; ++i) {
        const double x = rng.range(-extent, extent), y = rng.range(-extent, extent),
                     z = rng.range(-extent, extent);
        p[f][i] = {float(x), float(y), float(z)};
        // Rodrigues, plus a little stretch and noise
        const double d = ax * x + ay * y + az * z;
        const double rx = x * c + (ay * z - az * y) * s + ax * d * (1 - c);
        const double ry = y * c + (az * x - ax * z) * s + ay * d * (1 - c);
        const double rz = z * c + (ax * y - ay * x) * s + az * d * (1 - c);
        const double k = rng.range(0.8, 1.2), e = 0.05 * extent;
        p[f][3 + i] = {float(k * rx + rng.range(-e, e)), float(k * ry + rng.range(-e, e)),
                       float(k * rz + rng.range(-e, e))};
      }
      if (trial % 17 == f) p[f][2] = p[f][1];  // degenerate before
      if (trial % 19 == f) p[f][5] = p[f][3];  // degenerate after
    }
    Quat q[2];
    bool ok[2];
    detail::face_rotation_kernel_x2(points_of(p).p, q, ok);
    for (int f = 0; f < 2; ++f) {
      Quat ref;
      const bool ref_ok =
          detail::face_rotation_kernel(p[f][0], p[f][1], p[f][2], p[f][3], p[f][4], p[f][5], ref);
      ASSERT_EQ(ok[f], ref_ok) << "trial " << trial << " face " << f;
      if (ref_ok) {
        ASSERT_TRUE(same_bits(q[f], ref)) << "trial " << trial << " face " << f;
      }
    }
    (ok[0] && ok[1] && q[0].w > 0.5f && q[1].w > 0.5f ? both_small : other)++;
  }
  EXPECT_GT(both_small, 1000);
  EXPECT_GT(other, 1000);
}

// The single-precision kernel against the double one (itself the SVD-closest rotation to
// rounding, see test_isometry.cpp) on faces of every shape: where it answers, within 1e-5
// per quaternion component; it declines thin triangles and large rotations.
TEST(IsometryFaceRotationSimd, SinglePrecisionMatchesTheDoubleKernelWhereItAnswers) {
  SplitMix64 rng;
  rng.state = 99;
  double worst = 0;
  int answered = 0, declined = 0, thin_answered = 0;
  for (int trial = 0; trial < 50000; ++trial) {
    Vec3f p[4][6];
    double sin_a[4];
    for (int f = 0; f < 4; ++f) {
      const double extent = std::exp(rng.range(std::log(1e-3), std::log(1e3)));
      const double cx = rng.range(-10, 10) * extent, cy = rng.range(-10, 10) * extent,
                   cz = rng.range(-10, 10) * extent;
      const double angle = (trial % 4 == 0 ? rng.range(0, std::numbers::pi) : rng.range(0, 0.5));
      double ax = rng.range(-1, 1), ay = rng.range(-1, 1), az = rng.range(-1, 1);
      const double n = std::sqrt(ax * ax + ay * ay + az * az) + 1e-12;
      ax /= n, ay /= n, az /= n;
      const double c = std::cos(angle), s = std::sin(angle);
      double v[3][3];
      for (int i = 0; i < 3; ++i)
        for (double& x : v[i]) x = rng.range(-extent, extent);
      // squash the third vertex towards the line of the first two: thin triangles too
      const double squash = std::exp(rng.range(std::log(1e-6), 0.0));
      for (int k = 0; k < 3; ++k)
        v[2][k] = 0.5 * (v[0][k] + v[1][k]) + squash * (v[2][k] - 0.5 * (v[0][k] + v[1][k]));
      sin_a[f] = squash;
      for (int i = 0; i < 3; ++i) {
        const double x = v[i][0], y = v[i][1], z = v[i][2];
        p[f][i] = {float(cx + x), float(cy + y), float(cz + z)};
        const double d = ax * x + ay * y + az * z;
        const double rx = x * c + (ay * z - az * y) * s + ax * d * (1 - c);
        const double ry = y * c + (az * x - ax * z) * s + ay * d * (1 - c);
        const double rz = z * c + (ax * y - ay * x) * s + az * d * (1 - c);
        const double k = rng.range(0.8, 1.2), e = 0.02 * extent;
        p[f][3 + i] = {float(cx + k * rx + rng.range(-e, e)), float(cy + k * ry + rng.range(-e, e)),
                       float(cz + k * rz + rng.range(-e, e))};
      }
    }
    Quat q[4];
    bool ok[4];
    detail::face_rotation_kernel_f4(points_of(p).p, q, ok);
    for (int f = 0; f < 4; ++f) {
      Quat q1;  // the scalar form: the same answer bit for bit, the same lanes declined
      const bool ok1 =
          detail::face_rotation_kernel_f1(p[f][0], p[f][1], p[f][2], p[f][3], p[f][4], p[f][5], q1);
      ASSERT_EQ(ok1, ok[f]) << "trial " << trial << " face " << f;
      if (ok1) {
        ASSERT_TRUE(same_bits(q1, q[f])) << "trial " << trial << " face " << f;
      }
      if (!ok[f]) {
        ++declined;
        continue;
      }
      Quat ref;
      ASSERT_TRUE(
          detail::face_rotation_kernel(p[f][0], p[f][1], p[f][2], p[f][3], p[f][4], p[f][5], ref));
      const double e =
          std::max({std::fabs(double(q[f].w) - ref.w), std::fabs(double(q[f].x) - ref.x),
                    std::fabs(double(q[f].y) - ref.y), std::fabs(double(q[f].z) - ref.z)});
      worst = std::max(worst, e);
      ++answered;
      thin_answered += sin_a[f] < 0.1;
    }
  }
  std::printf(
      "single precision: %d answered (%d squashed below 0.1), %d declined, worst |dq| %.3g\n",
      answered, thin_answered, declined, worst);
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(answered, 20000);
  EXPECT_GT(declined, 20000);
}
#endif

}  // namespace
}  // namespace csculpt
