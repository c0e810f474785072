// Internal: single-precision face rotations for many faces, N per register (4 on SSE2, 8 on
// AVX2; the AVX2 build lives in blend_avx2.cpp and is chosen at run time). Every lane is
// face_rotation_kernel_f1 (vertex_isometry_kernel.h) bit for bit, so the width changes no
// result.
#pragma once

#include <cstddef>
#include <cstdint>

#include "csculpt/dual_quat.h"
#include "csculpt/mesh.h"

namespace csculpt::detail {

/// The faces of one diff as plain arrays (an aggregate: nothing of it is compiled per
/// instruction set).
struct FaceRotationArgs {
  const std::uint32_t* triangles = nullptr;  ///< 3 vertex indices per face of the mesh
  const Vec3f* base = nullptr;               ///< positions before, per vertex
  const Vec3f* edited = nullptr;             ///< positions after, per vertex
  const std::uint32_t* faces = nullptr;      ///< the faces to rotate
  std::size_t count = 0;
  Quat* offsets = nullptr;        ///< out, per listed face: its rotation - 1 where computed
  std::uint32_t* redo = nullptr;  ///< out (room for `count`): positions left to the double kernel
};

/// Computes the well-conditioned faces' rotations in single precision and lists the others
/// (thin, degenerate, large rotation, extreme coordinates) in `redo`, in increasing order;
/// returns how many it listed.
using FaceRotationsFn = std::size_t (*)(const FaceRotationArgs&);

/// The AVX2 build (blend_avx2.cpp); null where it is not built.
FaceRotationsFn face_rotations_avx2();
/// The build the merge uses: the AVX2 one where built and supported, as blend_chunk_kernel().
FaceRotationsFn face_rotations_kernel();

/// The last step of the per-vertex isometries, as plain arrays: for each listed vertex, its
/// rotation (the normalised sum of its faces' rotations, unchanged faces counting as the
/// identity) and the translation that lands it on its edited position, in the merge frame.
struct VertexFinishArgs {
  const std::uint32_t* vertices = nullptr;  ///< the touched vertices
  std::size_t count = 0;
  const std::uint32_t* face_offsets = nullptr;  ///< vertex_faces offsets: the degree
  const Quat* rotation_sum = nullptr;           ///< per vertex: sum of (q_face - 1)
  const Vec3f* base = nullptr;
  const Vec3f* edited = nullptr;
  Vec3f center{0, 0, 0};  ///< the frame: local = (p - center) * inv_scale
  float inv_scale = 1;
  DualQuat* out = nullptr;  ///< per listed vertex, in list order
};
using VertexFinishFn = void (*)(const VertexFinishArgs&);
VertexFinishFn vertex_finish_avx2();
VertexFinishFn vertex_finish_kernel();

}  // namespace csculpt::detail

#if defined(__SSE2__)

#include "dq_soa.h"
#include "simd_isa.h"

namespace csculpt::detail {
// Register types as template arguments: see dq_soa.h.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
CSCULPT_ISA_BEGIN

/// face_rotation_kernel_f1 on N faces at once: p[f][0..5] -> a0, a1, a2, b0, b1, b2 of face f.
/// ok[f] is set for the lanes computed; the others are left to the double kernel.
template <class V>
inline void face_rotation_kernel_lanes(const Vec3f* const (*p)[6], Quat* out, bool* ok) {
  using L = Lanes<V>;
  constexpr int N = L::kCount;
  struct F3 {
    V x, y, z;
  };
  auto load = [&](int i) -> F3 {
    float x[N], y[N], z[N];
    for (int f = 0; f < N; ++f) {
      x[f] = p[f][i]->x;
      y[f] = p[f][i]->y;
      z[f] = p[f][i]->z;
    }
    return {L::set(x), L::set(y), L::set(z)};
  };
  auto sub3 = [&](const F3& u, const F3& v) -> F3 {
    return {v_sub(u.x, v.x), v_sub(u.y, v.y), v_sub(u.z, v.z)};
  };
  auto cross = [&](const F3& u, const F3& v) -> F3 {
    return {v_sub(v_mul(u.y, v.z), v_mul(u.z, v.y)), v_sub(v_mul(u.z, v.x), v_mul(u.x, v.z)),
            v_sub(v_mul(u.x, v.y), v_mul(u.y, v.x))};
  };
  auto dot3 = [&](const F3& u, const F3& v) {
    return v_add(v_add(v_mul(u.x, v.x), v_mul(u.y, v.y)), v_mul(u.z, v.z));
  };
  auto scale = [&](const F3& u, V s) -> F3 {
    return {v_mul(u.x, s), v_mul(u.y, s), v_mul(u.z, s)};
  };
  const F3 a0 = load(0), a1 = load(1), a2 = load(2), b0 = load(3), b1 = load(4), b2 = load(5);
  const F3 e0a = sub3(a1, a0), e1a = sub3(a2, a0), e0b = sub3(b1, b0), e1b = sub3(b2, b0);
  const F3 ca = cross(e0a, e1a), cb = cross(e0b, e1b);
  const V la2 = dot3(e0a, e0a), lb2 = dot3(e0b, e0b);
  const V da2 = dot3(ca, ca), db2 = dot3(cb, cb);
  // sin^2 > 1e-2 both sides; |e0 x e1|^2 within [1e-24, 1e24] so that nothing below
  // (products of up to two such squares) leaves the normal float range
  const V tol = L::set1(1e-2f), lo = L::set1(1e-24f), hi = L::set1(1e24f);
  V good = v_and(v_gt(da2, v_mul(v_mul(tol, la2), dot3(e1a, e1a))),
                 v_gt(db2, v_mul(v_mul(tol, lb2), dot3(e1b, e1b))));
  good = v_and(good, v_and(v_gt(da2, lo), v_lt(da2, hi)));
  good = v_and(good, v_and(v_gt(db2, lo), v_lt(db2, hi)));
  int mask = v_bits(good);
  if (mask == 0) {
    for (int f = 0; f < N; ++f) ok[f] = false;
    return;
  }
  const V one = L::set1(1.f);
  const V inv_la = v_div(one, v_sqrt(la2)), inv_lb = v_div(one, v_sqrt(lb2));
  const V area_a = v_sqrt(da2), area_b = v_sqrt(db2);
  const F3 na = scale(ca, v_div(one, area_a)), nb = scale(cb, v_div(one, area_b));
  const F3 xa = scale(e0a, inv_la), xb = scale(e0b, inv_lb);
  const F3 ya = cross(na, xa), yb = cross(nb, xb);
  // cs, sn as in the double kernel but divided by la2 lb2 first (same angle), so their
  // squares stay in range: cs' = |ca| / la2 + |cb| / lb2 etc.
  const V inv_la2 = v_mul(inv_la, inv_la), inv_lb2 = v_mul(inv_lb, inv_lb);
  const V cs = v_add(v_mul(area_a, inv_la2), v_mul(area_b, inv_lb2));
  const V sn = v_sub(v_mul(dot3(e0a, e1a), inv_la2), v_mul(dot3(e0b, e1b), inv_lb2));
  const V inv_h = v_div(one, v_sqrt(v_add(v_mul(cs, cs), v_mul(sn, sn))));
  const V c = v_mul(cs, inv_h), s = v_mul(sn, inv_h);
  const F3 xr{v_add(v_mul(c, xb.x), v_mul(s, yb.x)), v_add(v_mul(c, xb.y), v_mul(s, yb.y)),
              v_add(v_mul(c, xb.z), v_mul(s, yb.z))};
  const F3 yr{v_sub(v_mul(c, yb.x), v_mul(s, xb.x)), v_sub(v_mul(c, yb.y), v_mul(s, xb.y)),
              v_sub(v_mul(c, yb.z), v_mul(s, xb.z))};
  auto entry = [&](V rx, V ry, V rn, V ax, V ay, V an) {
    return v_add(v_add(v_mul(rx, ax), v_mul(ry, ay)), v_mul(rn, an));
  };
  const V m0 = entry(xr.x, yr.x, nb.x, xa.x, ya.x, na.x);
  const V m1 = entry(xr.x, yr.x, nb.x, xa.y, ya.y, na.y);
  const V m2 = entry(xr.x, yr.x, nb.x, xa.z, ya.z, na.z);
  const V m3 = entry(xr.y, yr.y, nb.y, xa.x, ya.x, na.x);
  const V m4 = entry(xr.y, yr.y, nb.y, xa.y, ya.y, na.y);
  const V m5 = entry(xr.y, yr.y, nb.y, xa.z, ya.z, na.z);
  const V m6 = entry(xr.z, yr.z, nb.z, xa.x, ya.x, na.x);
  const V m7 = entry(xr.z, yr.z, nb.z, xa.y, ya.y, na.y);
  const V m8 = entry(xr.z, yr.z, nb.z, xa.z, ya.z, na.z);
  // Shepperd's first branch only: trace > 0 (w > 1/2)
  const V tr = v_add(v_add(m0, m4), m8);
  mask &= v_bits(v_gt(tr, L::zero()));
  for (int f = 0; f < N; ++f) ok[f] = (mask >> f & 1) != 0;
  if (mask == 0) return;
  const V sq = v_mul(v_sqrt(v_add(tr, one)), L::set1(2.f));
  const V inv = v_div(one, sq);
  alignas(32) float w[N], x[N], y[N], z[N];
  L::store(w, v_mul(L::set1(0.25f), sq));
  L::store(x, v_mul(v_sub(m7, m5), inv));
  L::store(y, v_mul(v_sub(m2, m6), inv));
  L::store(z, v_mul(v_sub(m3, m1), inv));
  for (int f = 0; f < N; ++f) out[f] = {w[f], x[f], y[f], z[f]};
}

/// FaceRotationsFn at width N: groups of N listed faces, the last one padded with copies of
/// its first face (whose results are not kept), so every face meets the same kernel
/// whatever its position and the width.
template <class V>
std::size_t face_rotations_lanes(const FaceRotationArgs& a) {
  constexpr std::size_t N = static_cast<std::size_t>(Lanes<V>::kCount);
  std::size_t redo = 0;
  for (std::size_t k = 0; k < a.count; k += N) {
    const std::size_t lanes = a.count - k < N ? a.count - k : N;
    const Vec3f* p[N][6];
    for (std::size_t f = 0; f < N; ++f) {
      const std::uint32_t* t = a.triangles + 3 * std::size_t{a.faces[k + (f < lanes ? f : 0)]};
      for (int i = 0; i < 3; ++i) {
        p[f][i] = a.base + t[i];
        p[f][3 + i] = a.edited + t[i];
      }
    }
    Quat q[N];
    bool ok[N];
    face_rotation_kernel_lanes<V>(p, q, ok);
    for (std::size_t f = 0; f < lanes; ++f) {
      if (ok[f])
        a.offsets[k + f] = Quat{q[f].w - 1.f, q[f].x, q[f].y, q[f].z};
      else
        a.redo[redo++] = static_cast<std::uint32_t>(k + f);
    }
  }
  return redo;
}

/// VertexFinishFn at width N, one vertex per lane, each lane the scalar sequence of
/// compute_vertex_isometries (vertex_isometry_kernel.h) operation for operation: the
/// products of q_mul (dq_simd.h) summed in its order, its sign flips as subtractions
/// (x + (-y) is x - y in IEEE arithmetic), the zero real parts of the points kept as
/// 0.5 * 0 so that signed zeros come out alike. The last group is padded with its first
/// vertex, whose extra results are not kept.
template <class V>
void vertex_finish_lanes(const VertexFinishArgs& a) {
  using L = Lanes<V>;
  constexpr std::size_t N = static_cast<std::size_t>(L::kCount);
  const V half = L::set1(0.5f), zero = L::zero(), one = L::set1(1.f);
  const V cx = L::set1(a.center.x), cy = L::set1(a.center.y), cz = L::set1(a.center.z);
  const V inv_scale = L::set1(a.inv_scale);
  for (std::size_t k = 0; k < a.count; k += N) {
    const std::size_t lanes = a.count - k < N ? a.count - k : N;
    float sw[N], sx[N], sy[N], sz[N], deg[N], fx[N], fy[N], fz[N], tx[N], ty[N], tz[N];
    for (std::size_t f = 0; f < N; ++f) {
      const std::uint32_t u = a.vertices[k + (f < lanes ? f : 0)];
      const Quat& q = a.rotation_sum[u];
      sw[f] = q.w, sx[f] = q.x, sy[f] = q.y, sz[f] = q.z;
      deg[f] = static_cast<float>(a.face_offsets[u + 1] - a.face_offsets[u]);
      fx[f] = a.base[u].x, fy[f] = a.base[u].y, fz[f] = a.base[u].z;
      tx[f] = a.edited[u].x, ty[f] = a.edited[u].y, tz[f] = a.edited[u].z;
    }
    // r = normalised (sum + degree), or the identity where its norm vanishes
    V rw = v_add(L::set(sw), L::set(deg)), rx = L::set(sx), ry = L::set(sy), rz = L::set(sz);
    const V n2 = v_add(v_add(v_add(v_mul(rw, rw), v_mul(rx, rx)), v_mul(ry, ry)), v_mul(rz, rz));
    const V ok = v_gt(n2, L::set1(1e-30f));
    const V inv = v_div(one, v_sqrt(n2));
    rw = sel(ok, v_mul(inv, rw), one);
    rx = sel(ok, v_mul(inv, rx), zero);
    ry = sel(ok, v_mul(inv, ry), zero);
    rz = sel(ok, v_mul(inv, rz), zero);
    // the points in the frame, as quaternions (0, p / 2)
    const V pa_w = v_mul(half, zero);
    const V pa_x = v_mul(half, v_mul(v_sub(L::set(fx), cx), inv_scale));
    const V pa_y = v_mul(half, v_mul(v_sub(L::set(fy), cy), inv_scale));
    const V pa_z = v_mul(half, v_mul(v_sub(L::set(fz), cz), inv_scale));
    const V pb_w = pa_w;
    const V pb_x = v_mul(half, v_mul(v_sub(L::set(tx), cx), inv_scale));
    const V pb_y = v_mul(half, v_mul(v_sub(L::set(ty), cy), inv_scale));
    const V pb_z = v_mul(half, v_mul(v_sub(L::set(tz), cz), inv_scale));
    // q_mul(a, b) of dq_simd.h, per component
    auto mul_w = [](V aw, V ax, V ay, V az, V bw, V bx, V by, V bz) {
      return v_sub(v_sub(v_sub(v_mul(aw, bw), v_mul(ax, bx)), v_mul(ay, by)), v_mul(az, bz));
    };
    auto mul_x = [](V aw, V ax, V ay, V az, V bw, V bx, V by, V bz) {
      return v_sub(v_add(v_add(v_mul(aw, bx), v_mul(ax, bw)), v_mul(ay, bz)), v_mul(az, by));
    };
    auto mul_y = [](V aw, V ax, V ay, V az, V bw, V bx, V by, V bz) {
      return v_add(v_add(v_sub(v_mul(aw, by), v_mul(ax, bz)), v_mul(ay, bw)), v_mul(az, bx));
    };
    auto mul_z = [](V aw, V ax, V ay, V az, V bw, V bx, V by, V bz) {
      return v_add(v_sub(v_add(v_mul(aw, bz), v_mul(ax, by)), v_mul(ay, bx)), v_mul(az, bw));
    };
    // dual = pb r - r pa
    V d[4] = {v_sub(mul_w(pb_w, pb_x, pb_y, pb_z, rw, rx, ry, rz),
                    mul_w(rw, rx, ry, rz, pa_w, pa_x, pa_y, pa_z)),
              v_sub(mul_x(pb_w, pb_x, pb_y, pb_z, rw, rx, ry, rz),
                    mul_x(rw, rx, ry, rz, pa_w, pa_x, pa_y, pa_z)),
              v_sub(mul_y(pb_w, pb_x, pb_y, pb_z, rw, rx, ry, rz),
                    mul_y(rw, rx, ry, rz, pa_w, pa_x, pa_y, pa_z)),
              v_sub(mul_z(pb_w, pb_x, pb_y, pb_z, rw, rx, ry, rz),
                    mul_z(rw, rx, ry, rz, pa_w, pa_x, pa_y, pa_z))};
    // canonical: both parts negated where the real w is negative
    const V flip = v_and(v_lt(rw, zero), L::set1(-0.f));
    alignas(32) float out[8][N];
    L::store(out[0], v_xor(rw, flip));
    L::store(out[1], v_xor(rx, flip));
    L::store(out[2], v_xor(ry, flip));
    L::store(out[3], v_xor(rz, flip));
    for (int i = 0; i < 4; ++i) L::store(out[4 + i], v_xor(d[i], flip));
    for (std::size_t f = 0; f < lanes; ++f)
      a.out[k + f] = DualQuat{{out[0][f], out[1][f], out[2][f], out[3][f]},
                              {out[4][f], out[5][f], out[6][f], out[7][f]}};
  }
}

CSCULPT_ISA_END
#pragma GCC diagnostic pop
}  // namespace csculpt::detail

#endif  // __SSE2__
