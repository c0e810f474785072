// The SSE2 face-rotation kernel (two faces per register) against the scalar kernel: every
// lane must give the scalar result bit for bit, whichever branch each lane takes (small and
// large rotations, trace of either sign, degenerate faces in either lane).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>

#include "csculpt/random.h"
#include "vertex_isometry_kernel.h"

namespace csculpt {
namespace {

#if defined(__SSE2__)
bool same_bits(const Quat& a, const Quat& b) { return std::memcmp(&a, &b, sizeof(Quat)) == 0; }

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
    detail::face_rotation_kernel_x2(p, q, ok);
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
#endif

}  // namespace
}  // namespace csculpt
