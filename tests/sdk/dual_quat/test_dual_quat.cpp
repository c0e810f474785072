// DualQuat math (dual_quat.h) against an independent implementation: GLM's dual quaternions
// (glm/gtx/dual_quaternion.hpp, in double precision), and against plain rotation matrices.
//
// GLM conventions, checked by transforming points below: glm::qua<T>(w, x, y, z) (constructor
// argument order, whatever the storage order), glm::tdualquat(real, dual), (a * b) applies b
// first, dq * vec3 applies the motion, and tdualquat(rotation, t) gives dual = 1/2 (0, t) r —
// the same encoding as csculpt::DualQuat.
#define GLM_ENABLE_EXPERIMENTAL
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtx/dual_quaternion.hpp>
#include <numbers>
#include <vector>

#include "csculpt/dual_quat.h"
#include "csculpt/testkit/random.h"
#include "test_support.h"

namespace csculpt {
namespace {

using csculpt::test::max_diff;

using GQuat = glm::qua<double, glm::defaultp>;
using GDual = glm::tdualquat<double, glm::defaultp>;
using GVec = glm::dvec3;

struct Rng : csculpt::SplitMix64 {
  explicit Rng(std::uint64_t seed) { state = seed; }
  /// Uniformly distributed unit quaternion (Shoemake), sign random.
  Quat rotation() {
    const double u1 = uniform(), u2 = range(0, 2 * std::numbers::pi),
                 u3 = range(0, 2 * std::numbers::pi);
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    return {static_cast<float>(a * std::sin(u2)), static_cast<float>(a * std::cos(u2)),
            static_cast<float>(b * std::sin(u3)), static_cast<float>(b * std::cos(u3))};
  }
  Vec3f point(double extent) {
    return {static_cast<float>(range(-extent, extent)), static_cast<float>(range(-extent, extent)),
            static_cast<float>(range(-extent, extent))};
  }
  DualQuat motion(double extent = 3.0) {
    return DualQuat::from_rotation_translation(rotation(), point(extent));
  }
};

GQuat to_glm(const Quat& q) {
  return GQuat(q.w, q.x, q.y, q.z);
}  // (w, x, y, z) order
GDual to_glm(const DualQuat& q) {
  return GDual(to_glm(q.real), to_glm(q.dual));
}
GVec to_glm(const Vec3f& v) {
  return GVec(v.x, v.y, v.z);
}

double dist(const Vec3f& a, const GVec& b) {
  return glm::length(GVec(a.x, a.y, a.z) - b);
}
double dist(const Vec3f& a, const Vec3f& b) {
  return dist(a, GVec(b.x, b.y, b.z));
}

double max_diff(const DualQuat& a, const GDual& b) {
  const double av[8] = {a.real.w, a.real.x, a.real.y, a.real.z,
                        a.dual.w, a.dual.x, a.dual.y, a.dual.z};
  const double bv[8] = {b.real.w, b.real.x, b.real.y, b.real.z,
                        b.dual.w, b.dual.x, b.dual.y, b.dual.z};
  double m = 0;
  for (int i = 0; i < 8; ++i) m = std::max(m, std::abs(av[i] - bv[i]));
  return m;
}
/// The same motion: equal up to the global sign of all 8 components.
double motion_diff(const DualQuat& a, const DualQuat& b) {
  const DualQuat nb{-1.f * b.real, -1.f * b.dual};
  return std::min(max_diff(a, b), max_diff(a, nb));
}

double real_norm(const DualQuat& q) {
  return std::sqrt(double(dot(q.real, q.real)));
}
double real_dot_dual(const DualQuat& q) {
  return double(dot(q.real, q.dual));
}
/// real . dual relative to the size of the dual part (float rounding scales with it).
double relative_real_dot_dual(const DualQuat& q) {
  return real_dot_dual(q) / (1.0 + std::sqrt(double(dot(q.dual, q.dual))));
}

constexpr int kTrials = 2000;

TEST(DualQuatGlm, ConventionsAgreeOnPoints) {
  // Pins GLM's conventions down before using it as the reference.
  Rng rng{1};
  for (int i = 0; i < 200; ++i) {
    const Quat r = rng.rotation();
    const Vec3f t = rng.point(2);
    const Vec3f p = rng.point(2);
    // GLM's (rotation, translation) constructor builds the same 8 numbers as ours.
    const DualQuat ours = DualQuat::from_rotation_translation(r, t);
    const GDual theirs(to_glm(r), to_glm(t));
    EXPECT_LT(max_diff(ours, theirs), 1e-6) << "trial " << i;
    // glm::quat * vec3 rotates like our rotate(), and the motion is R p + t.
    const GVec rp = glm::mat3_cast(to_glm(r)) * to_glm(p);
    EXPECT_LT(dist(rotate(r, p), to_glm(r) * to_glm(p)), 1e-5);
    EXPECT_LT(dist(rotate(r, p), rp), 1e-5);
    EXPECT_LT(dist(ours.apply(p), theirs * to_glm(p)), 1e-5);
    EXPECT_LT(dist(ours.apply(p), rp + to_glm(t)), 1e-5);
  }
}

TEST(DualQuatGlm, QuaternionProductMatchesGlm) {
  Rng rng{2};
  for (int i = 0; i < kTrials; ++i) {
    const Quat a = rng.rotation(), b = rng.rotation();
    const Quat ab = a * b;
    const GQuat g = to_glm(a) * to_glm(b);
    EXPECT_NEAR(ab.w, g.w, 1e-6);
    EXPECT_NEAR(ab.x, g.x, 1e-6);
    EXPECT_NEAR(ab.y, g.y, 1e-6);
    EXPECT_NEAR(ab.z, g.z, 1e-6);
  }
}

TEST(DualQuatGlm, CompositionMatchesGlmAndAppliesRightFirst) {
  Rng rng{3};
  double worst_q = 0, worst_p = 0;
  for (int i = 0; i < kTrials; ++i) {
    const DualQuat a = rng.motion(), b = rng.motion();
    const Vec3f p = rng.point(3);
    const DualQuat ab = a * b;
    const GDual g = to_glm(a) * to_glm(b);
    worst_q = std::max(worst_q, max_diff(ab, g));
    // (a * b) applies b first, then a — for us and for GLM.
    const Vec3f seq = a.apply(b.apply(p));
    worst_p = std::max(worst_p, dist(ab.apply(p), seq));
    worst_p = std::max(worst_p, dist(seq, g * to_glm(p)));
    worst_p = std::max(worst_p, dist(ab.apply(p), (to_glm(a) * (to_glm(b) * to_glm(p)))));
  }
  EXPECT_LT(worst_q, 1e-5);
  EXPECT_LT(worst_p, 1e-5);
}

TEST(DualQuatGlm, ApplyMatchesMatrixAndGlm) {
  Rng rng{4};
  double worst = 0;
  for (int i = 0; i < kTrials; ++i) {
    const Quat r = rng.rotation();
    const Vec3f t = rng.point(5);
    const DualQuat q = DualQuat::from_rotation_translation(r, t);
    // an independent rotation matrix, from the axis-angle of r
    const double w = std::clamp(double(r.w), -1.0, 1.0);
    const double angle = 2 * std::acos(w);
    GVec axis(r.x, r.y, r.z);
    const double s = glm::length(axis);
    glm::dmat3 m(1.0);
    if (s > 1e-12) m = glm::dmat3(glm::rotate(glm::dmat4(1.0), angle, axis / s));
    for (int k = 0; k < 4; ++k) {
      const Vec3f p = rng.point(4);
      const GVec expected = m * to_glm(p) + to_glm(t);
      worst = std::max(worst, dist(q.apply(p), expected));
      worst = std::max(worst, dist(q.apply(p), to_glm(q) * to_glm(p)));
    }
  }
  EXPECT_LT(worst, 2e-5);
}

TEST(DualQuatGlm, InverseMatchesGlmAndUndoesTheMotion) {
  Rng rng{5};
  double worst_id = 0, worst_glm = 0, worst_p = 0;
  for (int i = 0; i < kTrials; ++i) {
    const DualQuat q = rng.motion();
    const DualQuat qi = inverse(q);
    worst_id = std::max(worst_id, motion_diff(q * qi, DualQuat::identity()));
    worst_id = std::max(worst_id, motion_diff(qi * q, DualQuat::identity()));
    worst_glm = std::max(worst_glm, max_diff(qi, glm::inverse(to_glm(q))));
    const Vec3f p = rng.point(3);
    worst_p = std::max(worst_p, dist(qi.apply(q.apply(p)), p));
    worst_p = std::max(worst_p, dist(q.apply(qi.apply(p)), p));
  }
  EXPECT_LT(worst_id, 1e-6);
  EXPECT_LT(worst_glm, 1e-6);
  EXPECT_LT(worst_p, 2e-5);
}

TEST(DualQuatGlm, TranslationRecoversT) {
  Rng rng{6};
  double worst = 0;
  for (int i = 0; i < kTrials; ++i) {
    const Vec3f t = rng.point(10);
    const DualQuat q = DualQuat::from_rotation_translation(rng.rotation(), t);
    worst = std::max(worst, dist(q.translation(), t) / 10.0);
    // and GLM's motion of the origin is the translation too
    worst = std::max(worst, dist(q.translation(), to_glm(q) * GVec(0.0)) / 10.0);
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_EQ(DualQuat::identity().translation(), (Vec3f{0, 0, 0}));
}

TEST(DualQuatGlm, FromRotationAndPointsMapsFromOntoTo) {
  Rng rng{7};
  double worst = 0, worst_unit = 0;
  for (int i = 0; i < kTrials; ++i) {
    const Quat r = rng.rotation();
    const Vec3f from = rng.point(1), to = rng.point(1);
    const DualQuat q = DualQuat::from_rotation_and_points(r, from, to);
    worst = std::max(worst, dist(q.apply(from), to));
    worst = std::max(worst, glm::length(to_glm(q) * to_glm(from) - to_glm(to)));
    worst_unit = std::max(worst_unit, std::abs(real_dot_dual(q)));
    // the rotation is kept: other points move by R (p - from) + to
    const Vec3f p = rng.point(1);
    const Vec3f d{p.x - from.x, p.y - from.y, p.z - from.z};
    const Vec3f rd = rotate(r, d);
    worst = std::max(worst, dist(q.apply(p), Vec3f{rd.x + to.x, rd.y + to.y, rd.z + to.z}));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(worst_unit, 1e-6);
}

TEST(DualQuatGlm, NormalizedProjectsOntoUnitDualQuaternions) {
  Rng rng{8};
  double worst_norm = 0, worst_orth = 0, worst_motion = 0, worst_glm = 0;
  for (int i = 0; i < kTrials; ++i) {
    const DualQuat q = rng.motion();
    const float scale = static_cast<float>(rng.range(0.01, 50));
    // scaled, then perturbed away from real . dual = 0
    DualQuat s{scale * q.real, scale * q.dual};
    const DualQuat n0 = normalized(s);
    worst_norm = std::max(worst_norm, std::abs(real_norm(n0) - 1));
    worst_orth = std::max(worst_orth, std::abs(real_dot_dual(n0)));
    // a pure scale does not change the motion
    worst_motion = std::max(worst_motion, max_diff(n0, q));
    // against GLM's normalize on the same scaled dual quaternion
    const GDual gn = glm::normalize(to_glm(s));
    worst_glm = std::max(worst_glm, max_diff(n0, gn));

    const float eps = static_cast<float>(rng.range(-0.3, 0.3));
    s.dual = s.dual + eps * s.real;  // breaks orthogonality
    s.real = s.real + Quat{static_cast<float>(rng.range(-0.1, 0.1)), 0.05f, -0.02f, 0.f};
    const DualQuat n1 = normalized(s);
    worst_norm = std::max(worst_norm, std::abs(real_norm(n1) - 1));
    worst_orth = std::max(worst_orth, std::abs(real_dot_dual(n1)));
  }
  EXPECT_LT(worst_norm, 1e-6);
  EXPECT_LT(worst_orth, 1e-6);
  EXPECT_LT(worst_motion, 1e-5);
  EXPECT_LT(worst_glm, 1e-5);
  // a zero real part cannot be normalised: the identity
  const float zero[8] = {0, 0, 0, 0, 1, 2, 3, 4};
  EXPECT_EQ(normalized(zero), DualQuat::identity());
}

TEST(DualQuatGlm, CanonicalKeepsTheMotionWithPositiveRealW) {
  Rng rng{9};
  int flipped = 0;
  for (int i = 0; i < kTrials; ++i) {
    const DualQuat q = rng.motion();
    const DualQuat c = canonical(q);
    EXPECT_GE(c.real.w, 0.f);
    EXPECT_LT(motion_diff(c, q), 1e-7);
    if (q.real.w < 0) {
      ++flipped;
      EXPECT_EQ(c.real.w, -q.real.w);
      EXPECT_EQ(c.dual.x, -q.dual.x);
    } else {
      EXPECT_EQ(c, q);
    }
    const Vec3f p = rng.point(3);
    EXPECT_LT(dist(c.apply(p), q.apply(p)), 1e-5);
    // q and -q have the same canonical form
    const DualQuat neg{-1.f * q.real, -1.f * q.dual};
    if (q.real.w != 0) {
      EXPECT_EQ(canonical(neg), c);
    }
  }
  EXPECT_GT(flipped, kTrials / 4);  // the generator does produce negative w
}

TEST(DualQuatGlm, Magnitude) {
  EXPECT_EQ(magnitude(DualQuat::identity()), 0.f);
  Rng rng{10};
  for (int i = 0; i < kTrials; ++i) {
    const DualQuat q = rng.motion();
    const DualQuat neg{-1.f * q.real, -1.f * q.dual};
    EXPECT_FLOAT_EQ(magnitude(q), magnitude(neg));
    EXPECT_GT(magnitude(q), 0.f);
  }
  // closed forms: a pure translation t has magnitude |t|/2; a rotation by theta (< 180
  // degrees) has |(cos theta/2 - 1, sin theta/2 n)| = 2 sin(theta/4)
  for (int i = 0; i < 100; ++i) {
    const Vec3f t = rng.point(4);
    const double len = std::sqrt(double(t.x) * t.x + double(t.y) * t.y + double(t.z) * t.z);
    EXPECT_NEAR(magnitude(DualQuat::from_rotation_translation({}, t)), len / 2, 1e-6);
    const double theta = rng.range(0, 3.1);
    const Quat r{static_cast<float>(std::cos(theta / 2)), 0,
                 static_cast<float>(std::sin(theta / 2)), 0};
    EXPECT_NEAR(magnitude(DualQuat::from_rotation_translation(r, {})), 2 * std::sin(theta / 4),
                1e-6);
  }
}

DualQuat blend(float m0, const DualQuat& q0, float m1, const DualQuat& q1) {
  DualQuat sum{{0, 0, 0, 0}, {0, 0, 0, 0}};
  add_scaled(sum, m0, canonical(q0));
  add_scaled(sum, m1, canonical(q1));
  return normalized(sum);
}

TEST(DualQuatBlend, IdentityAndIdempotence) {
  Rng rng{11};
  double worst_identity = 0, worst_idem = 0, worst_sign = 0;
  for (int i = 0; i < kTrials; ++i) {
    const DualQuat q0 = rng.motion(), q1 = rng.motion();
    const float m0 = magnitude(q0);
    // identity: an absent (zero-weight) operand leaves the other unchanged
    worst_identity = std::max(worst_identity, max_diff(blend(m0, q0, 0.f, q1), canonical(q0)));
    worst_identity = std::max(worst_identity, max_diff(blend(0.f, q1, m0, q0), canonical(q0)));
    // idempotence: equal operands give themselves, whatever the weights and signs
    const float w = static_cast<float>(rng.range(0.1, 3));
    worst_idem = std::max(worst_idem, max_diff(blend(m0, q0, w, q0), canonical(q0)));
    const DualQuat neg{-1.f * q0.real, -1.f * q0.dual};
    worst_sign = std::max(worst_sign, max_diff(blend(m0, q0, m0, neg), canonical(q0)));
    // the blend is a unit dual quaternion and commutative
    const DualQuat b01 = blend(m0, q0, magnitude(q1), q1);
    const DualQuat b10 = blend(magnitude(q1), q1, m0, q0);
    EXPECT_EQ(b01, b10);
    EXPECT_NEAR(real_norm(b01), 1, 1e-6);
    EXPECT_NEAR(relative_real_dot_dual(b01), 0, 1e-6);
  }
  EXPECT_LT(worst_identity, 1e-6);
  EXPECT_LT(worst_idem, 1e-6);
  EXPECT_LT(worst_sign, 1e-6);
}

TEST(DualQuatBlend, PureTranslationsBlendLikeThePaperFormula) {
  // For pure translations the blend is the paper's magnitude-weighted average of translations.
  Rng rng{12};
  for (int i = 0; i < 200; ++i) {
    const Vec3f t0 = rng.point(0.5), t1 = rng.point(0.5);
    const DualQuat q0 = DualQuat::from_rotation_translation({}, t0);
    const DualQuat q1 = DualQuat::from_rotation_translation({}, t1);
    const double m0 = magnitude(q0), m1 = magnitude(q1);
    const Vec3f got = blend(float(m0), q0, float(m1), q1).translation();
    const double k0 = m0 / (m0 + m1), k1 = m1 / (m0 + m1);
    EXPECT_NEAR(got.x, k0 * t0.x + k1 * t1.x, 1e-6);
    EXPECT_NEAR(got.y, k0 * t0.y + k1 * t1.y, 1e-6);
    EXPECT_NEAR(got.z, k0 * t0.z + k1 * t1.z, 1e-6);
  }
}

TEST(DualQuatBlend, OffsetSumMatchesAdd) {
  Rng rng{13};
  for (int i = 0; i < 200; ++i) {
    const DualQuat q = canonical(rng.motion());
    const float w = static_cast<float>(rng.range(0, 2));
    DualQuat a{{0, 0, 0, 0}, {0, 0, 0, 0}}, b = a;
    add_scaled(a, w, q);
    add_scaled_offset(b, w, q);
    b.real.w += w;  // add_scaled_offset(w, q) = add_scaled(w, q) - w * identity
    const float av[8] = {a.real.w, a.real.x, a.real.y, a.real.z,
                         a.dual.w, a.dual.x, a.dual.y, a.dual.z};
    const float bv[8] = {b.real.w, b.real.x, b.real.y, b.real.z,
                         b.dual.w, b.dual.x, b.dual.y, b.dual.z};
    for (int k = 0; k < 8; ++k) EXPECT_NEAR(av[k], bv[k], 1e-6) << k;
  }
}

}  // namespace
}  // namespace csculpt
