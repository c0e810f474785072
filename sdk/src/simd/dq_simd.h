// Internal: the dual-quaternion arithmetic of the merge's hot loops on SSE2 registers (the
// x86-64 baseline, so no dispatch). Every operation performs, lane by lane, exactly the IEEE
// operations of the scalar code in csculpt/dual_quat.h in the same order (x - y is x + (-y)
// bit for bit; horizontal sums are taken left to right), so the results are bit-identical
// to the scalar path, which stays as the fallback on other targets.
#pragma once

#include <cmath>

#include "csculpt/dual_quat.h"
#include "simd_isa.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace csculpt::detail {
CSCULPT_ISA_BEGIN

#if defined(__SSE2__)

/// A dual quaternion in two registers: (w, x, y, z) of the real and of the dual part.
struct DQv {
  __m128 r, d;
};

inline DQv dq_load(const DualQuat& q) {
  return {_mm_loadu_ps(&q.real.w), _mm_loadu_ps(&q.dual.w)};
}
inline void dq_store(DualQuat& q, const DQv& v) {
  _mm_storeu_ps(&q.real.w, v.r);
  _mm_storeu_ps(&q.dual.w, v.d);
}
inline DQv dq_zero() {
  return {_mm_setzero_ps(), _mm_setzero_ps()};
}
inline DQv dq_identity() {
  return {_mm_set_ss(1.f), _mm_setzero_ps()};
}

/// ((v0 + v1) + v2) + v3, as the scalar code sums.
inline float hsum_ordered(__m128 v) {
  __m128 s = _mm_add_ss(v, _mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 1, 1, 1)));
  s = _mm_add_ss(s, _mm_movehl_ps(v, v));
  s = _mm_add_ss(s, _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 3, 3, 3)));
  return _mm_cvtss_f32(s);
}
/// (((s + v0) + v1) + v2) + v3
inline float hsum_ordered(float s0, __m128 v) {
  __m128 s = _mm_add_ss(_mm_set_ss(s0), v);
  s = _mm_add_ss(s, _mm_shuffle_ps(v, v, _MM_SHUFFLE(1, 1, 1, 1)));
  s = _mm_add_ss(s, _mm_movehl_ps(v, v));
  s = _mm_add_ss(s, _mm_shuffle_ps(v, v, _MM_SHUFFLE(3, 3, 3, 3)));
  return _mm_cvtss_f32(s);
}

inline __m128 sign_mask(bool w, bool x, bool y, bool z) {
  return _mm_castsi128_ps(_mm_set_epi32(z ? int(0x80000000u) : 0, y ? int(0x80000000u) : 0,
                                        x ? int(0x80000000u) : 0, w ? int(0x80000000u) : 0));
}

/// Quaternion product a * b, term order and signs as operator*(Quat, Quat).
inline __m128 q_mul(__m128 a, __m128 b) {
  const __m128 aw = _mm_shuffle_ps(a, a, _MM_SHUFFLE(0, 0, 0, 0));
  const __m128 ax = _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 1, 1, 1));
  const __m128 ay = _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 2, 2, 2));
  const __m128 az = _mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 3, 3, 3));
  const __m128 b1 = _mm_shuffle_ps(b, b, _MM_SHUFFLE(2, 3, 0, 1));  // x w z y
  const __m128 b2 = _mm_shuffle_ps(b, b, _MM_SHUFFLE(1, 0, 3, 2));  // y z w x
  const __m128 b3 = _mm_shuffle_ps(b, b, _MM_SHUFFLE(0, 1, 2, 3));  // z y x w
  __m128 r = _mm_mul_ps(aw, b);
  r = _mm_add_ps(r, _mm_xor_ps(_mm_mul_ps(ax, b1), sign_mask(true, false, true, false)));
  r = _mm_add_ps(r, _mm_xor_ps(_mm_mul_ps(ay, b2), sign_mask(true, false, false, true)));
  r = _mm_add_ps(r, _mm_xor_ps(_mm_mul_ps(az, b3), sign_mask(true, true, false, false)));
  return r;
}
inline __m128 q_conjugate(__m128 a) {
  return _mm_xor_ps(a, sign_mask(false, true, true, true));
}

/// operator*(DualQuat, DualQuat)
inline DQv dq_mul(const DQv& a, const DQv& b) {
  return {q_mul(a.r, b.r), _mm_add_ps(q_mul(a.r, b.d), q_mul(a.d, b.r))};
}
/// inverse(a) * b
inline DQv dq_inverse_mul(const DQv& a, const DQv& b) {
  return dq_mul({q_conjugate(a.r), q_conjugate(a.d)}, b);
}
/// canonical(): negate both parts when the real w is negative.
inline DQv dq_canonical(const DQv& q) {
  const __m128 neg =
      _mm_cmplt_ps(_mm_shuffle_ps(q.r, q.r, _MM_SHUFFLE(0, 0, 0, 0)), _mm_setzero_ps());
  const __m128 flip = _mm_and_ps(neg, sign_mask(true, true, true, true));
  return {_mm_xor_ps(q.r, flip), _mm_xor_ps(q.d, flip)};
}
/// add_scaled(): acc += w q
inline void dq_add_scaled(DQv& acc, float w, const DQv& q) {
  const __m128 ww = _mm_set1_ps(w);
  acc.r = _mm_add_ps(acc.r, _mm_mul_ps(ww, q.r));
  acc.d = _mm_add_ps(acc.d, _mm_mul_ps(ww, q.d));
}
/// add_scaled_offset(): acc += w (q - 1)
inline void dq_add_scaled_offset(DQv& acc, float w, const DQv& q) {
  const __m128 ww = _mm_set1_ps(w);
  acc.r = _mm_add_ps(acc.r, _mm_mul_ps(ww, _mm_sub_ss(q.r, _mm_set_ss(1.f))));
  acc.d = _mm_add_ps(acc.d, _mm_mul_ps(ww, q.d));
}
/// real w += s (the other lanes untouched, so a -0 stays -0)
inline DQv dq_add_real_w(const DQv& q, float s) {
  return {_mm_add_ss(q.r, _mm_set_ss(s)), q.d};
}
/// normalized()
inline DQv dq_normalized(const DQv& v) {
  const float n2 = hsum_ordered(_mm_mul_ps(v.r, v.r));
  if (!(n2 > 1e-30f)) return dq_identity();
  const __m128 inv = _mm_set1_ps(1.f / std::sqrt(n2));
  const __m128 r = _mm_mul_ps(v.r, inv);
  __m128 d = _mm_mul_ps(v.d, inv);
  const float rd = hsum_ordered(_mm_mul_ps(r, d));
  d = _mm_sub_ps(d, _mm_mul_ps(_mm_set1_ps(rd), r));
  return {r, d};
}
/// magnitude(): |canonical(q) - 1| over the 8 components, summed in order.
inline float dq_magnitude(const DQv& q) {
  const DQv c = dq_canonical(q);
  const __m128 e = _mm_sub_ss(c.r, _mm_set_ss(1.f));
  return std::sqrt(hsum_ordered(hsum_ordered(_mm_mul_ps(e, e)), _mm_mul_ps(c.d, c.d)));
}
/// |a - b| as DqOps::distance: sqrt(dot(dr, dr) + dot(dd, dd)).
inline float dq_distance(const DQv& a, const DQv& b) {
  const __m128 dr = _mm_sub_ps(a.r, b.r), dd = _mm_sub_ps(a.d, b.d);
  return std::sqrt(hsum_ordered(_mm_mul_ps(dr, dr)) + hsum_ordered(_mm_mul_ps(dd, dd)));
}

#endif  // __SSE2__

CSCULPT_ISA_END
}  // namespace csculpt::detail
