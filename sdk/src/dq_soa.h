// Internal: four dual quaternions at once in structure-of-arrays form (one SSE2 register per
// component, one node per lane). Each lane performs exactly the scalar IEEE operations of
// csculpt/dual_quat.h and of merge.cpp's DqOps, in the same order; the branches of the
// scalar code become lane masks that select between values both computed, so results are
// bit-identical to the scalar path.
#pragma once

#include "dq_simd.h"

#if defined(__SSE2__)

namespace csculpt::detail {

/// Components rw, rx, ry, rz, dw, dx, dy, dz; lane i is node i.
struct DQ4 {
  __m128 c[8];
};

inline __m128 sel(__m128 mask, __m128 a, __m128 b) {  // mask ? a : b
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}
inline __m128 neg(__m128 a) {
  return _mm_xor_ps(a, _mm_set1_ps(-0.f));
}

/// From four AoS dual quaternions (one per lane).
inline DQ4 dq4_from(const DQv& a, const DQv& b, const DQv& c, const DQv& d) {
  DQ4 out;
  __m128 r0 = a.r, r1 = b.r, r2 = c.r, r3 = d.r;
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out.c[0] = r0, out.c[1] = r1, out.c[2] = r2, out.c[3] = r3;
  __m128 d0 = a.d, d1 = b.d, d2 = c.d, d3 = d.d;
  _MM_TRANSPOSE4_PS(d0, d1, d2, d3);
  out.c[4] = d0, out.c[5] = d1, out.c[6] = d2, out.c[7] = d3;
  return out;
}
/// Back to four AoS dual quaternions.
inline void dq4_to(const DQ4& q, DQv (&out)[4]) {
  __m128 r0 = q.c[0], r1 = q.c[1], r2 = q.c[2], r3 = q.c[3];
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  __m128 d0 = q.c[4], d1 = q.c[5], d2 = q.c[6], d3 = q.c[7];
  _MM_TRANSPOSE4_PS(d0, d1, d2, d3);
  out[0] = {r0, d0}, out[1] = {r1, d1}, out[2] = {r2, d2}, out[3] = {r3, d3};
}

inline DQ4 dq4_identity() {
  DQ4 q;
  q.c[0] = _mm_set1_ps(1.f);
#pragma GCC unroll 8
  for (int i = 1; i < 8; ++i) q.c[i] = _mm_setzero_ps();
  return q;
}
/// mask ? a : b per lane; `bits` = the mask's movemask (0xf: all a, 0: all b).
inline DQ4 dq4_select(__m128 mask, const DQ4& a, const DQ4& b) {
  const int bits = _mm_movemask_ps(mask);
  if (bits == 0xf) return a;
  if (bits == 0) return b;
  DQ4 q;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) q.c[i] = sel(mask, a.c[i], b.c[i]);
  return q;
}

/// Quaternion product (w, x, y, z) = a * b, term order as operator*(Quat, Quat).
inline void q4_mul(const __m128* a, const __m128* b, __m128* out) {
  const __m128 aw = a[0], ax = a[1], ay = a[2], az = a[3];
  const __m128 bw = b[0], bx = b[1], by = b[2], bz = b[3];
  out[0] =
      _mm_sub_ps(_mm_sub_ps(_mm_sub_ps(_mm_mul_ps(aw, bw), _mm_mul_ps(ax, bx)), _mm_mul_ps(ay, by)),
                 _mm_mul_ps(az, bz));
  out[1] =
      _mm_sub_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(aw, bx), _mm_mul_ps(ax, bw)), _mm_mul_ps(ay, bz)),
                 _mm_mul_ps(az, by));
  out[2] =
      _mm_add_ps(_mm_add_ps(_mm_sub_ps(_mm_mul_ps(aw, by), _mm_mul_ps(ax, bz)), _mm_mul_ps(ay, bw)),
                 _mm_mul_ps(az, bx));
  out[3] =
      _mm_add_ps(_mm_sub_ps(_mm_add_ps(_mm_mul_ps(aw, bz), _mm_mul_ps(ax, by)), _mm_mul_ps(ay, bx)),
                 _mm_mul_ps(az, bw));
}
/// operator*(DualQuat, DualQuat): (ar br, ar bd + ad br)
inline DQ4 dq4_mul(const DQ4& a, const DQ4& b) {
  DQ4 o;
  q4_mul(a.c, b.c, o.c);
  __m128 t1[4], t2[4];
  q4_mul(a.c, b.c + 4, t1);
  q4_mul(a.c + 4, b.c, t2);
#pragma GCC unroll 8
  for (int i = 0; i < 4; ++i) o.c[4 + i] = _mm_add_ps(t1[i], t2[i]);
  return o;
}
/// inverse(a): the quaternion conjugate of both parts.
inline DQ4 dq4_inverse(const DQ4& a) {
  DQ4 o = a;
  o.c[1] = neg(a.c[1]), o.c[2] = neg(a.c[2]), o.c[3] = neg(a.c[3]);
  o.c[5] = neg(a.c[5]), o.c[6] = neg(a.c[6]), o.c[7] = neg(a.c[7]);
  return o;
}
/// canonical(): lanes with a negative real w negated (-1.f * x is a sign flip).
inline DQ4 dq4_canonical(const DQ4& q) {
  const __m128 negative = _mm_cmplt_ps(q.c[0], _mm_setzero_ps());
  if (_mm_movemask_ps(negative) == 0) return q;  // the common case: nothing to flip
  const __m128 flip = _mm_and_ps(negative, _mm_set1_ps(-0.f));
  DQ4 o;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) o.c[i] = _mm_xor_ps(q.c[i], flip);
  return o;
}
/// normalized(): identity where the real part's squared norm is not > 1e-30.
inline DQ4 dq4_normalized(const DQ4& v) {
  const __m128 n2 =
      _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(v.c[0], v.c[0]), _mm_mul_ps(v.c[1], v.c[1])),
                            _mm_mul_ps(v.c[2], v.c[2])),
                 _mm_mul_ps(v.c[3], v.c[3]));
  const __m128 ok = _mm_cmpgt_ps(n2, _mm_set1_ps(1e-30f));
  const __m128 inv = _mm_div_ps(_mm_set1_ps(1.f), _mm_sqrt_ps(n2));
  DQ4 o;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) o.c[i] = _mm_mul_ps(v.c[i], inv);
  const __m128 rd =
      _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(o.c[0], o.c[4]), _mm_mul_ps(o.c[1], o.c[5])),
                            _mm_mul_ps(o.c[2], o.c[6])),
                 _mm_mul_ps(o.c[3], o.c[7]));
#pragma GCC unroll 8
  for (int i = 0; i < 4; ++i) o.c[4 + i] = _mm_sub_ps(o.c[4 + i], _mm_mul_ps(rd, o.c[i]));
  if (_mm_movemask_ps(ok) == 0xf) return o;
  return dq4_select(ok, o, dq4_identity());
}
/// magnitude() of values already canonical (canonical() is then the identity):
/// |q - 1| over the 8 components, summed in order.
inline __m128 dq4_magnitude_of_canonical(const DQ4& c) {
  const __m128 dw = _mm_sub_ps(c.c[0], _mm_set1_ps(1.f));
  __m128 s = _mm_mul_ps(dw, dw);
#pragma GCC unroll 8
  for (int i = 1; i < 8; ++i) s = _mm_add_ps(s, _mm_mul_ps(c.c[i], c.c[i]));
  return _mm_sqrt_ps(s);
}
/// sqrt(dot(dr, dr) + dot(dd, dd)) with dr, dd the differences of the parts.
inline __m128 dq4_distance(const DQ4& a, const DQ4& b) {
  __m128 d[8];
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) d[i] = _mm_sub_ps(a.c[i], b.c[i]);
  const __m128 r = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(d[0], d[0]), _mm_mul_ps(d[1], d[1])),
                                         _mm_mul_ps(d[2], d[2])),
                              _mm_mul_ps(d[3], d[3]));
  const __m128 u = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(d[4], d[4]), _mm_mul_ps(d[5], d[5])),
                                         _mm_mul_ps(d[6], d[6])),
                              _mm_mul_ps(d[7], d[7]));
  return _mm_sqrt_ps(_mm_add_ps(r, u));
}

}  // namespace csculpt::detail

#endif  // __SSE2__
