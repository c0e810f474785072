// Internal: N dual quaternions at once in structure-of-arrays form (one register per
// component, one node per lane): N = 4 on SSE2 (__m128), N = 8 on AVX2 (__m256). Each lane
// performs exactly the scalar IEEE operations of csculpt/dual_quat.h and of merge.cpp's
// DqOps, in the same order; the branches of the scalar code become lane masks that select
// between values both computed. So every width gives bit-identical results, and the width
// is chosen at run time (merge.cpp) without changing a merge.
//
// The operations are written once, as templates over the register type, on the overloads
// below (v_add(__m128, __m128), v_add(__m256, __m256), ...).
#pragma once

#include "dq_simd.h"
#include "simd_isa.h"

#if defined(__SSE2__)

#if defined(__AVX__)
#include <immintrin.h>
#endif

// Register types as template arguments: GCC notes that it drops their may_alias attribute
// there, which changes nothing for values held in registers and arrays of them.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
namespace csculpt::detail {
CSCULPT_ISA_BEGIN

// ---- lane-wise operations, one overload per register width ----

inline __m128 v_add(__m128 a, __m128 b) {
  return _mm_add_ps(a, b);
}
inline __m128 v_sub(__m128 a, __m128 b) {
  return _mm_sub_ps(a, b);
}
inline __m128 v_mul(__m128 a, __m128 b) {
  return _mm_mul_ps(a, b);
}
inline __m128 v_div(__m128 a, __m128 b) {
  return _mm_div_ps(a, b);
}
inline __m128 v_sqrt(__m128 a) {
  return _mm_sqrt_ps(a);
}
inline __m128 v_max(__m128 a, __m128 b) {
  return _mm_max_ps(a, b);
}
inline __m128 v_and(__m128 a, __m128 b) {
  return _mm_and_ps(a, b);
}
inline __m128 v_andnot(__m128 a, __m128 b) {
  return _mm_andnot_ps(a, b);
}
inline __m128 v_or(__m128 a, __m128 b) {
  return _mm_or_ps(a, b);
}
inline __m128 v_xor(__m128 a, __m128 b) {
  return _mm_xor_ps(a, b);
}
inline __m128 v_gt(__m128 a, __m128 b) {
  return _mm_cmpgt_ps(a, b);
}
inline __m128 v_lt(__m128 a, __m128 b) {
  return _mm_cmplt_ps(a, b);
}
inline int v_bits(__m128 a) {
  return _mm_movemask_ps(a);
}

#if defined(__AVX__)
// _CMP_GT_OQ / _CMP_LT_OQ give the same lane results as SSE's cmpgt / cmplt (false on
// NaN); only the floating-point exception flag differs, which nothing reads.
inline __m256 v_add(__m256 a, __m256 b) {
  return _mm256_add_ps(a, b);
}
inline __m256 v_sub(__m256 a, __m256 b) {
  return _mm256_sub_ps(a, b);
}
inline __m256 v_mul(__m256 a, __m256 b) {
  return _mm256_mul_ps(a, b);
}
inline __m256 v_div(__m256 a, __m256 b) {
  return _mm256_div_ps(a, b);
}
inline __m256 v_sqrt(__m256 a) {
  return _mm256_sqrt_ps(a);
}
inline __m256 v_max(__m256 a, __m256 b) {
  return _mm256_max_ps(a, b);
}
inline __m256 v_and(__m256 a, __m256 b) {
  return _mm256_and_ps(a, b);
}
inline __m256 v_andnot(__m256 a, __m256 b) {
  return _mm256_andnot_ps(a, b);
}
inline __m256 v_or(__m256 a, __m256 b) {
  return _mm256_or_ps(a, b);
}
inline __m256 v_xor(__m256 a, __m256 b) {
  return _mm256_xor_ps(a, b);
}
inline __m256 v_gt(__m256 a, __m256 b) {
  return _mm256_cmp_ps(a, b, _CMP_GT_OQ);
}
inline __m256 v_lt(__m256 a, __m256 b) {
  return _mm256_cmp_ps(a, b, _CMP_LT_OQ);
}
inline int v_bits(__m256 a) {
  return _mm256_movemask_ps(a);
}
#endif

template <class V>
struct Lanes;
template <>
struct Lanes<__m128> {
  static constexpr int kCount = 4;
  static __m128 set1(float x) { return _mm_set1_ps(x); }
  static __m128 zero() { return _mm_setzero_ps(); }
  static __m128 load(const float* p) { return _mm_loadu_ps(p); }
  static void store(float* p, __m128 v) { _mm_storeu_ps(p, v); }
  /// From four values in registers (no round trip through memory, whose narrow stores a
  /// wide load cannot forward from).
  static __m128 set(const float (&x)[4]) { return _mm_set_ps(x[3], x[2], x[1], x[0]); }
  /// A mask with the lanes of `bits` set.
  static __m128 mask(unsigned bits) {
    return _mm_castsi128_ps(
        _mm_set_epi32(bits & 8 ? -1 : 0, bits & 4 ? -1 : 0, bits & 2 ? -1 : 0, bits & 1 ? -1 : 0));
  }
};
#if defined(__AVX__)
template <>
struct Lanes<__m256> {
  static constexpr int kCount = 8;
  static __m256 set1(float x) { return _mm256_set1_ps(x); }
  static __m256 zero() { return _mm256_setzero_ps(); }
  static __m256 load(const float* p) { return _mm256_loadu_ps(p); }
  static void store(float* p, __m256 v) { _mm256_storeu_ps(p, v); }
  static __m256 set(const float (&x)[8]) {
    return _mm256_set_ps(x[7], x[6], x[5], x[4], x[3], x[2], x[1], x[0]);
  }
  static __m256 mask(unsigned bits) {
    const __m256i lane_bit = _mm256_set_epi32(128, 64, 32, 16, 8, 4, 2, 1);
    const __m256i hit = _mm256_and_si256(_mm256_set1_epi32(static_cast<int>(bits)), lane_bit);
    return _mm256_castsi256_ps(_mm256_cmpeq_epi32(hit, lane_bit));
  }
};
#endif

template <class V>
constexpr int kAllLanes = (1 << Lanes<V>::kCount) - 1;

template <class V>
inline V sel(V mask, V a, V b) {  // mask ? a : b
  return v_or(v_and(mask, a), v_andnot(mask, b));
}
template <class V>
inline V neg(V a) {
  return v_xor(a, Lanes<V>::set1(-0.f));
}

/// Components rw, rx, ry, rz, dw, dx, dy, dz; lane i is node i.
template <class V>
struct DQN {
  V c[8];
};
using DQ4 = DQN<__m128>;

template <class V>
inline DQN<V> dqn_identity() {
  DQN<V> q;
  q.c[0] = Lanes<V>::set1(1.f);
#pragma GCC unroll 8
  for (int i = 1; i < 8; ++i) q.c[i] = Lanes<V>::zero();
  return q;
}
/// mask ? a : b per lane.
template <class V>
inline DQN<V> dqn_select(V mask, const DQN<V>& a, const DQN<V>& b) {
  const int bits = v_bits(mask);
  if (bits == kAllLanes<V>) return a;
  if (bits == 0) return b;
  DQN<V> q;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) q.c[i] = sel(mask, a.c[i], b.c[i]);
  return q;
}

/// Quaternion product (w, x, y, z) = a * b, term order as operator*(Quat, Quat).
template <class V>
inline void qn_mul(const V* a, const V* b, V* out) {
  const V aw = a[0], ax = a[1], ay = a[2], az = a[3];
  const V bw = b[0], bx = b[1], by = b[2], bz = b[3];
  out[0] = v_sub(v_sub(v_sub(v_mul(aw, bw), v_mul(ax, bx)), v_mul(ay, by)), v_mul(az, bz));
  out[1] = v_sub(v_add(v_add(v_mul(aw, bx), v_mul(ax, bw)), v_mul(ay, bz)), v_mul(az, by));
  out[2] = v_add(v_add(v_sub(v_mul(aw, by), v_mul(ax, bz)), v_mul(ay, bw)), v_mul(az, bx));
  out[3] = v_add(v_sub(v_add(v_mul(aw, bz), v_mul(ax, by)), v_mul(ay, bx)), v_mul(az, bw));
}
/// operator*(DualQuat, DualQuat): (ar br, ar bd + ad br)
template <class V>
inline DQN<V> dqn_mul(const DQN<V>& a, const DQN<V>& b) {
  DQN<V> o;
  qn_mul(a.c, b.c, o.c);
  V t1[4], t2[4];
  qn_mul(a.c, b.c + 4, t1);
  qn_mul(a.c + 4, b.c, t2);
#pragma GCC unroll 8
  for (int i = 0; i < 4; ++i) o.c[4 + i] = v_add(t1[i], t2[i]);
  return o;
}
/// inverse(a): the quaternion conjugate of both parts.
template <class V>
inline DQN<V> dqn_inverse(const DQN<V>& a) {
  DQN<V> o = a;
  o.c[1] = neg(a.c[1]), o.c[2] = neg(a.c[2]), o.c[3] = neg(a.c[3]);
  o.c[5] = neg(a.c[5]), o.c[6] = neg(a.c[6]), o.c[7] = neg(a.c[7]);
  return o;
}
/// canonical(): lanes with a negative real w negated (-1.f * x is a sign flip).
template <class V>
inline DQN<V> dqn_canonical(const DQN<V>& q) {
  const V negative = v_lt(q.c[0], Lanes<V>::zero());
  if (v_bits(negative) == 0) return q;  // the common case: nothing to flip
  const V flip = v_and(negative, Lanes<V>::set1(-0.f));
  DQN<V> o;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) o.c[i] = v_xor(q.c[i], flip);
  return o;
}
/// normalized(): identity where the real part's squared norm is not > 1e-30.
template <class V>
inline DQN<V> dqn_normalized(const DQN<V>& v) {
  const V n2 =
      v_add(v_add(v_add(v_mul(v.c[0], v.c[0]), v_mul(v.c[1], v.c[1])), v_mul(v.c[2], v.c[2])),
            v_mul(v.c[3], v.c[3]));
  const V ok = v_gt(n2, Lanes<V>::set1(1e-30f));
  const V inv = v_div(Lanes<V>::set1(1.f), v_sqrt(n2));
  DQN<V> o;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) o.c[i] = v_mul(v.c[i], inv);
  const V rd =
      v_add(v_add(v_add(v_mul(o.c[0], o.c[4]), v_mul(o.c[1], o.c[5])), v_mul(o.c[2], o.c[6])),
            v_mul(o.c[3], o.c[7]));
#pragma GCC unroll 8
  for (int i = 0; i < 4; ++i) o.c[4 + i] = v_sub(o.c[4 + i], v_mul(rd, o.c[i]));
  if (v_bits(ok) == kAllLanes<V>) return o;
  return dqn_select(ok, o, dqn_identity<V>());
}
/// magnitude() of values already canonical (canonical() is then the identity):
/// |q - 1| over the 8 components, summed in order.
template <class V>
inline V dqn_magnitude_of_canonical(const DQN<V>& c) {
  const V dw = v_sub(c.c[0], Lanes<V>::set1(1.f));
  V s = v_mul(dw, dw);
#pragma GCC unroll 8
  for (int i = 1; i < 8; ++i) s = v_add(s, v_mul(c.c[i], c.c[i]));
  return v_sqrt(s);
}
/// sqrt(dot(dr, dr) + dot(dd, dd)) with dr, dd the differences of the parts.
template <class V>
inline V dqn_distance(const DQN<V>& a, const DQN<V>& b) {
  V d[8];
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) d[i] = v_sub(a.c[i], b.c[i]);
  const V r = v_add(v_add(v_add(v_mul(d[0], d[0]), v_mul(d[1], d[1])), v_mul(d[2], d[2])),
                    v_mul(d[3], d[3]));
  const V u = v_add(v_add(v_add(v_mul(d[4], d[4]), v_mul(d[5], d[5])), v_mul(d[6], d[6])),
                    v_mul(d[7], d[7]));
  return v_sqrt(v_add(r, u));
}

// ---- one dual quaternion per lane, in array-of-structures form, and the transposes ----

/// SSE2: four nodes, each dual quaternion in two registers (DQv, dq_simd.h).
inline DQ4 dqn_from(const DQv (&q)[4]) {
  DQ4 out;
  __m128 r0 = q[0].r, r1 = q[1].r, r2 = q[2].r, r3 = q[3].r;
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out.c[0] = r0, out.c[1] = r1, out.c[2] = r2, out.c[3] = r3;
  __m128 d0 = q[0].d, d1 = q[1].d, d2 = q[2].d, d3 = q[3].d;
  _MM_TRANSPOSE4_PS(d0, d1, d2, d3);
  out.c[4] = d0, out.c[5] = d1, out.c[6] = d2, out.c[7] = d3;
  return out;
}
inline void dqn_to(const DQ4& q, DQv (&out)[4]) {
  __m128 r0 = q.c[0], r1 = q.c[1], r2 = q.c[2], r3 = q.c[3];
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  __m128 d0 = q.c[4], d1 = q.c[5], d2 = q.c[6], d3 = q.c[7];
  _MM_TRANSPOSE4_PS(d0, d1, d2, d3);
  out[0] = {r0, d0}, out[1] = {r1, d1}, out[2] = {r2, d2}, out[3] = {r3, d3};
}

#if defined(__AVX__)
/// AVX: one dual quaternion per register (rw rx ry rz dw dx dy dz).
struct DQy {
  __m256 v;
};
inline DQy dqy_load(const DualQuat& q) {
  return {_mm256_loadu_ps(&q.real.w)};
}
inline void dqy_store(DualQuat& q, const DQy& v) {
  _mm256_storeu_ps(&q.real.w, v.v);
}
inline DQy dqy_zero() {
  return {_mm256_setzero_ps()};
}
inline DQy dqy_identity() {
  return {_mm256_set_ps(0, 0, 0, 0, 0, 0, 0, 1.f)};
}
/// add_scaled_offset(): acc += w (q - 1); the other components subtract +0, which leaves
/// every value (-0 included) as it is, so each lane is dq_add_scaled_offset's.
inline void dqy_add_scaled_offset(DQy& acc, float w, const DQy& q) {
  acc.v =
      _mm256_add_ps(acc.v, _mm256_mul_ps(_mm256_set1_ps(w), _mm256_sub_ps(q.v, dqy_identity().v)));
}
/// The 8 x 8 transpose (its own inverse): register i's lane k <-> register k's lane i.
inline void transpose8(__m256 (&r)[8]) {
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
  const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
  const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
  const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
  r[0] = _mm256_permute2f128_ps(u0, u4, 0x20);
  r[1] = _mm256_permute2f128_ps(u1, u5, 0x20);
  r[2] = _mm256_permute2f128_ps(u2, u6, 0x20);
  r[3] = _mm256_permute2f128_ps(u3, u7, 0x20);
  r[4] = _mm256_permute2f128_ps(u0, u4, 0x31);
  r[5] = _mm256_permute2f128_ps(u1, u5, 0x31);
  r[6] = _mm256_permute2f128_ps(u2, u6, 0x31);
  r[7] = _mm256_permute2f128_ps(u3, u7, 0x31);
}
inline DQN<__m256> dqn_from(const DQy (&q)[8]) {
  DQN<__m256> out;
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) out.c[i] = q[i].v;
  transpose8(out.c);
  return out;
}
inline void dqn_to(const DQN<__m256>& q, DQy (&out)[8]) {
  __m256 r[8];
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) r[i] = q.c[i];
  transpose8(r);
#pragma GCC unroll 8
  for (int i = 0; i < 8; ++i) out[i].v = r[i];
}
#endif

CSCULPT_ISA_END
}  // namespace csculpt::detail

#pragma GCC diagnostic pop

#endif  // __SSE2__
