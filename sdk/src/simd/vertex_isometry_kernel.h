// Internal: the sparse per-vertex isometry kernel shared by the merge and
// vertex_isometries(). Works only on the faces around changed vertices.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/dual_quat.h"
#include "csculpt/hierarchy.h"
#include "csculpt/isometry.h"
#include "dq_simd.h"
#include "face_rotation_lanes.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace csculpt::detail {

/// Maps mesh coordinates into the merge's working frame (centred, unit diagonal), in which
/// the magnitude |q - 1| weighs rotation and translation alike whatever the model's units.
struct Frame {
  Vec3f center{0, 0, 0};
  float inv_scale = 1;
  Vec3f to_local(const Vec3f& p) const {
    return {(p.x - center.x) * inv_scale, (p.y - center.y) * inv_scale,
            (p.z - center.z) * inv_scale};
  }
};

/// Closed form of the paper's per-face rotation: the SVD-closest rotation to
/// A = (e0b, e1b, nb)(e0a, e1a, na)^-1. Both triangles have right-handed orthonormal frames
/// F = (x, y, n) with x along e0, so A = Fb diag(M, 1) Fa^T with M the 2x2 map of the edges
/// in those frames (det M > 0). The closest rotation is invariant under the orthogonal
/// factors, and that of a 2x2 map [[a, b], [c, d]] is the plane rotation by
/// atan2(c - b, a + d); hence R = Fb Rz(theta) Fa^T exactly, with no iteration.
inline bool face_rotation_kernel(const Vec3f& a0, const Vec3f& a1, const Vec3f& a2, const Vec3f& b0,
                                 const Vec3f& b1, const Vec3f& b2, Quat& out) {
  struct D3 {
    double x, y, z;
  };
  auto sub = [](const Vec3f& p, const Vec3f& q) -> D3 {
    return {double(p.x) - q.x, double(p.y) - q.y, double(p.z) - q.z};
  };
  auto cross = [](const D3& u, const D3& v) -> D3 {
    return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  };
  auto dot3 = [](const D3& u, const D3& v) { return u.x * v.x + u.y * v.y + u.z * v.z; };
  auto scale = [](const D3& u, double s) -> D3 { return {u.x * s, u.y * s, u.z * s}; };
  const D3 e0a = sub(a1, a0), e1a = sub(a2, a0), e0b = sub(b1, b0), e1b = sub(b2, b0);
  const D3 ca = cross(e0a, e1a), cb = cross(e0b, e1b);
  const double la2 = dot3(e0a, e0a), lb2 = dot3(e0b, e0b);
  const double da2 = dot3(ca, ca), db2 = dot3(cb, cb);
  // Degenerate before or after: no usable frame, no rotation from this face. A triangle
  // flattened in float arithmetic keeps a cross product of rounding noise (sin of its
  // angles ~1e-7), whose normal would be arbitrary, so the bound sits well above float
  // resolution: sin(angle between the edges) > 1e-5.
  const double tol = 1e-10;
  if (!(da2 > tol * la2 * dot3(e1a, e1a))) return false;
  if (!(db2 > tol * lb2 * dot3(e1b, e1b))) return false;
  // Frames: x along e0, n along e0 x e1, y = n x x (one reciprocal each).
  const double inv_la = 1.0 / std::sqrt(la2), inv_lb = 1.0 / std::sqrt(lb2);
  const double area_a = std::sqrt(da2), area_b = std::sqrt(db2);
  const D3 na = scale(ca, 1.0 / area_a), nb = scale(cb, 1.0 / area_b);
  const D3 xa = scale(e0a, inv_la), xb = scale(e0b, inv_lb);
  const D3 ya = cross(na, xa), yb = cross(nb, xb);
  // The 2x2 map of the edges in those frames is M = [[pb/pa, (ub - pb ua/pa)/va], [0, vb/va]]
  // with p = |e0|, u = e1.x, v = e1.y = |e0 x e1| / p; its polar angle comes from
  // (m00 + m11, m10 - m01), here multiplied by the positive pa^2 pb^2 va / (pa pb) to need
  // no further division: (pb^2 |ca| + pa^2 |cb|, pb^2 (e0a.e1a) - pa^2 (e0b.e1b)).
  const double cs = lb2 * area_a + la2 * area_b;
  const double sn = lb2 * dot3(e0a, e1a) - la2 * dot3(e0b, e1b);
  const double inv_h = 1.0 / std::sqrt(cs * cs + sn * sn);
  const double c = cs * inv_h, s = sn * inv_h;
  // x' = c xb + s yb, y' = -s xb + c yb; R = x' xa^T + y' ya^T + nb na^T
  const D3 xr{c * xb.x + s * yb.x, c * xb.y + s * yb.y, c * xb.z + s * yb.z};
  const D3 yr{c * yb.x - s * xb.x, c * yb.y - s * xb.y, c * yb.z - s * xb.z};
  const double r[9] = {
      xr.x * xa.x + yr.x * ya.x + nb.x * na.x, xr.x * xa.y + yr.x * ya.y + nb.x * na.y,
      xr.x * xa.z + yr.x * ya.z + nb.x * na.z, xr.y * xa.x + yr.y * ya.x + nb.y * na.x,
      xr.y * xa.y + yr.y * ya.y + nb.y * na.y, xr.y * xa.z + yr.y * ya.z + nb.y * na.z,
      xr.z * xa.x + yr.z * ya.x + nb.z * na.x, xr.z * xa.y + yr.z * ya.y + nb.z * na.y,
      xr.z * xa.z + yr.z * ya.z + nb.z * na.z};
  out = quat_from_rotation_matrix(r);
  return true;
}

/// One lane of face_rotation_kernel_f4 (the scalar reference it equals bit for bit, and the
/// path of builds without SSE2, so that every build merges alike): single-precision face
/// rotation of a well-conditioned face, false where it declines (see face_rotation_kernel_f4).
inline bool face_rotation_kernel_f1(const Vec3f& a0, const Vec3f& a1, const Vec3f& a2,
                                    const Vec3f& b0, const Vec3f& b1, const Vec3f& b2, Quat& out) {
  struct F3 {
    float x, y, z;
  };
  auto sub = [](const Vec3f& p, const Vec3f& q) -> F3 { return {p.x - q.x, p.y - q.y, p.z - q.z}; };
  auto cross = [](const F3& u, const F3& v) -> F3 {
    return {u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  };
  auto dot3 = [](const F3& u, const F3& v) { return u.x * v.x + u.y * v.y + u.z * v.z; };
  auto scale = [](const F3& u, float s) -> F3 { return {u.x * s, u.y * s, u.z * s}; };
  const F3 e0a = sub(a1, a0), e1a = sub(a2, a0), e0b = sub(b1, b0), e1b = sub(b2, b0);
  const F3 ca = cross(e0a, e1a), cb = cross(e0b, e1b);
  const float la2 = dot3(e0a, e0a), lb2 = dot3(e0b, e0b);
  const float da2 = dot3(ca, ca), db2 = dot3(cb, cb);
  const float tol = 1e-2f, lo = 1e-24f, hi = 1e24f;
  if (!(da2 > tol * la2 * dot3(e1a, e1a)) || !(db2 > tol * lb2 * dot3(e1b, e1b))) return false;
  if (!(da2 > lo && da2 < hi && db2 > lo && db2 < hi)) return false;
  const float inv_la = 1.f / std::sqrt(la2), inv_lb = 1.f / std::sqrt(lb2);
  const float area_a = std::sqrt(da2), area_b = std::sqrt(db2);
  const F3 na = scale(ca, 1.f / area_a), nb = scale(cb, 1.f / area_b);
  const F3 xa = scale(e0a, inv_la), xb = scale(e0b, inv_lb);
  const F3 ya = cross(na, xa), yb = cross(nb, xb);
  const float inv_la2 = inv_la * inv_la, inv_lb2 = inv_lb * inv_lb;
  const float cs = area_a * inv_la2 + area_b * inv_lb2;
  const float sn = dot3(e0a, e1a) * inv_la2 - dot3(e0b, e1b) * inv_lb2;
  const float inv_h = 1.f / std::sqrt(cs * cs + sn * sn);
  const float c = cs * inv_h, s = sn * inv_h;
  const F3 xr{c * xb.x + s * yb.x, c * xb.y + s * yb.y, c * xb.z + s * yb.z};
  const F3 yr{c * yb.x - s * xb.x, c * yb.y - s * xb.y, c * yb.z - s * xb.z};
  const float m0 = xr.x * xa.x + yr.x * ya.x + nb.x * na.x;
  const float m1 = xr.x * xa.y + yr.x * ya.y + nb.x * na.y;
  const float m2 = xr.x * xa.z + yr.x * ya.z + nb.x * na.z;
  const float m3 = xr.y * xa.x + yr.y * ya.x + nb.y * na.x;
  const float m5 = xr.y * xa.z + yr.y * ya.z + nb.y * na.z;
  const float m4 = xr.y * xa.y + yr.y * ya.y + nb.y * na.y;
  const float m6 = xr.z * xa.x + yr.z * ya.x + nb.z * na.x;
  const float m7 = xr.z * xa.y + yr.z * ya.y + nb.z * na.y;
  const float m8 = xr.z * xa.z + yr.z * ya.z + nb.z * na.z;
  const float tr = m0 + m4 + m8;
  if (!(tr > 0)) return false;
  const float sq = std::sqrt(tr + 1.f) * 2.f, inv = 1.f / sq;
  out = {0.25f * sq, (m7 - m5) * inv, (m2 - m6) * inv, (m3 - m1) * inv};
  return true;
}

#if defined(__SSE2__)
/// face_rotation_kernel for two faces at once, one per lane of SSE2 doubles: every lane
/// performs exactly the scalar kernel's IEEE operations in the same order (the degenerate
/// tests become masks), so results are bit-identical to two scalar calls. Vertices are given
/// as p[face][0..5] -> a0, a1, a2, b0, b1, b2 (read in place: no copy).
inline void face_rotation_kernel_x2(const Vec3f* const (&p)[2][6], Quat (&out)[2], bool (&ok)[2]) {
  struct D3 {
    __m128d x, y, z;
  };
  auto load = [&](int i) -> D3 {
    return {_mm_set_pd(double(p[1][i]->x), double(p[0][i]->x)),
            _mm_set_pd(double(p[1][i]->y), double(p[0][i]->y)),
            _mm_set_pd(double(p[1][i]->z), double(p[0][i]->z))};
  };
  auto sub = [](const D3& u, const D3& v) -> D3 {
    return {_mm_sub_pd(u.x, v.x), _mm_sub_pd(u.y, v.y), _mm_sub_pd(u.z, v.z)};
  };
  auto mul = [](__m128d a, __m128d b) { return _mm_mul_pd(a, b); };
  auto add = [](__m128d a, __m128d b) { return _mm_add_pd(a, b); };
  auto cross = [&](const D3& u, const D3& v) -> D3 {
    return {_mm_sub_pd(mul(u.y, v.z), mul(u.z, v.y)), _mm_sub_pd(mul(u.z, v.x), mul(u.x, v.z)),
            _mm_sub_pd(mul(u.x, v.y), mul(u.y, v.x))};
  };
  auto dot3 = [&](const D3& u, const D3& v) {
    return add(add(mul(u.x, v.x), mul(u.y, v.y)), mul(u.z, v.z));
  };
  auto scale = [&](const D3& u, __m128d s) -> D3 {
    return {mul(u.x, s), mul(u.y, s), mul(u.z, s)};
  };
  const D3 a0 = load(0), a1 = load(1), a2 = load(2), b0 = load(3), b1 = load(4), b2 = load(5);
  const D3 e0a = sub(a1, a0), e1a = sub(a2, a0), e0b = sub(b1, b0), e1b = sub(b2, b0);
  const D3 ca = cross(e0a, e1a), cb = cross(e0b, e1b);
  const __m128d la2 = dot3(e0a, e0a), lb2 = dot3(e0b, e0b);
  const __m128d da2 = dot3(ca, ca), db2 = dot3(cb, cb);
  const __m128d tol = _mm_set1_pd(1e-10);
  const __m128d valid = _mm_and_pd(_mm_cmpgt_pd(da2, mul(mul(tol, la2), dot3(e1a, e1a))),
                                   _mm_cmpgt_pd(db2, mul(mul(tol, lb2), dot3(e1b, e1b))));
  const int mask = _mm_movemask_pd(valid);
  ok[0] = (mask & 1) != 0;
  ok[1] = (mask & 2) != 0;
  if (mask == 0) return;
  const __m128d one = _mm_set1_pd(1.0);
  const __m128d inv_la = _mm_div_pd(one, _mm_sqrt_pd(la2)),
                inv_lb = _mm_div_pd(one, _mm_sqrt_pd(lb2));
  const __m128d area_a = _mm_sqrt_pd(da2), area_b = _mm_sqrt_pd(db2);
  const D3 na = scale(ca, _mm_div_pd(one, area_a)), nb = scale(cb, _mm_div_pd(one, area_b));
  const D3 xa = scale(e0a, inv_la), xb = scale(e0b, inv_lb);
  const D3 ya = cross(na, xa), yb = cross(nb, xb);
  const __m128d cs = add(mul(lb2, area_a), mul(la2, area_b));
  const __m128d sn = _mm_sub_pd(mul(lb2, dot3(e0a, e1a)), mul(la2, dot3(e0b, e1b)));
  const __m128d inv_h = _mm_div_pd(one, _mm_sqrt_pd(add(mul(cs, cs), mul(sn, sn))));
  const __m128d c = mul(cs, inv_h), s = mul(sn, inv_h);
  const D3 xr{add(mul(c, xb.x), mul(s, yb.x)), add(mul(c, xb.y), mul(s, yb.y)),
              add(mul(c, xb.z), mul(s, yb.z))};
  const D3 yr{_mm_sub_pd(mul(c, yb.x), mul(s, xb.x)), _mm_sub_pd(mul(c, yb.y), mul(s, xb.y)),
              _mm_sub_pd(mul(c, yb.z), mul(s, xb.z))};
  auto entry = [&](__m128d rx, __m128d ry, __m128d rn, const __m128d& ax, const __m128d& ay,
                   const __m128d& an) { return add(add(mul(rx, ax), mul(ry, ay)), mul(rn, an)); };
  const __m128d r[9] = {
      entry(xr.x, yr.x, nb.x, xa.x, ya.x, na.x), entry(xr.x, yr.x, nb.x, xa.y, ya.y, na.y),
      entry(xr.x, yr.x, nb.x, xa.z, ya.z, na.z), entry(xr.y, yr.y, nb.y, xa.x, ya.x, na.x),
      entry(xr.y, yr.y, nb.y, xa.y, ya.y, na.y), entry(xr.y, yr.y, nb.y, xa.z, ya.z, na.z),
      entry(xr.z, yr.z, nb.z, xa.x, ya.x, na.x), entry(xr.z, yr.z, nb.z, xa.y, ya.y, na.y),
      entry(xr.z, yr.z, nb.z, xa.z, ya.z, na.z)};
  // quat_from_rotation_matrix on both lanes when both take its first branch (trace > 0,
  // the common case: face rotations are mostly small): the same operations, so the same bits.
  // There w = s / 4 > 0, so its sign flip multiplies by 1.0 (exact) and is left out; the
  // narrowing to float rounds as the scalar cast does.
  const __m128d tr = add(add(r[0], r[4]), r[8]);
  if (mask == 3 && _mm_movemask_pd(_mm_cmpgt_pd(tr, _mm_setzero_pd())) == 3) {
    const __m128d sq = mul(_mm_sqrt_pd(add(tr, one)), _mm_set1_pd(2.0));
    const __m128d inv = _mm_div_pd(one, sq);
    const __m128 w = _mm_cvtpd_ps(mul(_mm_set1_pd(0.25), sq));
    const __m128 x = _mm_cvtpd_ps(mul(_mm_sub_pd(r[7], r[5]), inv));
    const __m128 y = _mm_cvtpd_ps(mul(_mm_sub_pd(r[2], r[6]), inv));
    const __m128 z = _mm_cvtpd_ps(mul(_mm_sub_pd(r[3], r[1]), inv));
    // (w0 w1 . .), (x0 x1 . .) ... -> (w0 x0 w1 x1), (y0 z0 y1 z1) -> per face (w x y z)
    const __m128 wx = _mm_unpacklo_ps(w, x), yz = _mm_unpacklo_ps(y, z);
    _mm_storeu_ps(&out[0].w, _mm_movelh_ps(wx, yz));
    _mm_storeu_ps(&out[1].w, _mm_movehl_ps(yz, wx));
    return;
  }
  alignas(16) double lanes[9][2];
  for (int i = 0; i < 9; ++i) _mm_store_pd(lanes[i], r[i]);
  for (int f = 0; f < 2; ++f) {
    if (!ok[f]) continue;
    const double m[9] = {lanes[0][f], lanes[1][f], lanes[2][f], lanes[3][f], lanes[4][f],
                         lanes[5][f], lanes[6][f], lanes[7][f], lanes[8][f]};
    out[f] = quat_from_rotation_matrix(m);
  }
}

/// Single-precision face rotations, four faces per register, for well-conditioned faces
/// only: both triangles' edge angles with sin > 0.1 (so the float cross products carry a
/// relative error of a few 1e-7 / 0.1) and a rotation whose matrix has a positive trace
/// (Shepperd's first branch, stable when w >= 1/2). `ok` is set for the lanes computed here;
/// every other lane (thin, degenerate, large rotation, huge or tiny coordinates) is left to
/// the double kernel. The same formulas as face_rotation_kernel, in float: deterministic
/// (IEEE single operations in a fixed order on every SSE2 CPU), not bit-identical to it;
/// each lane is bit-identical to face_rotation_kernel_f1, at any width
/// (face_rotation_lanes.h).
inline void face_rotation_kernel_f4(const Vec3f* const (&p)[4][6], Quat (&out)[4], bool (&ok)[4]) {
  face_rotation_kernel_lanes<__m128>(p, out, ok);
}
#endif

/// A set of indices as one bit each: 40 KB for the faces of a 320K-face mesh, so the
/// membership tests of the sparse loops hit L1/L2 instead of a 4-byte stamp per element.
/// Cleared word by word from the list of what was inserted.
struct BitSet {
  std::vector<std::uint64_t> words;
  void resize(std::size_t n) {
    if (words.size() < (n + 63) / 64) words.resize((n + 63) / 64, 0);
  }
  bool test(std::uint32_t i) const { return (words[i >> 6] >> (i & 63) & 1) != 0; }
  /// Sets bit i; true if it was clear.
  bool insert(std::uint32_t i) {
    std::uint64_t& w = words[i >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (i & 63);
    if ((w & bit) != 0) return false;
    w |= bit;
    return true;
  }
  /// Clears every bit of the inserted indices `inserted` (zeroing their words).
  void clear(std::span<const std::uint32_t> inserted) {
    for (std::uint32_t i : inserted) words[i >> 6] = 0;
  }
};

struct VertexIsometryScratch {
  BitSet face_seen;                  ///< all clear between calls
  BitSet vertex_seen;                ///< all clear between calls
  std::vector<Quat> rotation_sum;    ///< sum of (q_face - 1) over changed faces
  std::vector<std::uint32_t> faces;  ///< faces around changed vertices, first-touch order
  std::vector<Quat> face_offset;     ///< per listed face: q_face - 1 (zero if degenerate)
  std::vector<std::uint32_t> redo;   ///< positions in `faces` left to the double kernel
  std::vector<Vec3f> edited;         ///< per touched vertex: its edited position
  std::vector<DualQuat> finished;    ///< per position in `touched`: its isometry

  void resize(std::size_t vertex_count, std::size_t face_count) {
    face_seen.resize(face_count);
    vertex_seen.resize(vertex_count);
    if (rotation_sum.size() < vertex_count) {
      rotation_sum.resize(vertex_count);
      edited.resize(vertex_count);
    }
  }
};

/// For every vertex on a face that has a changed vertex: q = q_R + eps q_T with q_R the
/// normalised sum of its incident face rotations (unchanged and degenerate faces count as
/// the identity) and q_T such that the vertex lands exactly on its edited position.
/// Lists those vertices in `touched` (in a deterministic order).
/// `store(v, q)` receives each result.
template <class EditedPosition, class Store>
void compute_vertex_isometries(const Topology& topology, std::span<const Vec3f> base,
                               std::span<const std::uint32_t> changed, EditedPosition&& edited,
                               VertexIsometryScratch& scratch, Store&& store,
                               std::vector<std::uint32_t>& touched, const Frame& frame = {}) {
  touched.clear();
  scratch.faces.clear();
  const auto& vf = topology.vertex_faces;
  // 1. the faces around changed vertices and the vertices they touch
  for (std::uint32_t v : changed) {
    if (scratch.vertex_seen.insert(v)) {  // also a changed vertex on no face
      scratch.rotation_sum[v] = {0, 0, 0, 0};
      scratch.edited[v] = edited(v);
      touched.push_back(v);
    }
    for (std::uint32_t i = vf.offsets[v]; i < vf.offsets[v + 1]; ++i) {
      const std::uint32_t f = vf.items[i];
      if (!scratch.face_seen.insert(f)) continue;
      scratch.faces.push_back(f);
      for (std::uint32_t u : topology.triangles[f]) {
        if (scratch.vertex_seen.insert(u)) {
          scratch.rotation_sum[u] = {0, 0, 0, 0};
          scratch.edited[u] = edited(u);
          touched.push_back(u);
        }
      }
    }
  }
  scratch.face_seen.clear(scratch.faces);
  scratch.vertex_seen.clear(touched);
  // 2. their rotations: independent, so the divisions and roots of successive faces overlap.
  // Well-conditioned faces in single precision, 4 or 8 per register (face_rotation_lanes.h),
  // the rest (listed in `redo`, in increasing order) in double.
  const std::size_t face_count = scratch.faces.size();
  scratch.face_offset.resize(face_count);
  auto& redo = scratch.redo;
  redo.resize(face_count);
  std::size_t first_scalar = 0;
#if defined(__SSE2__)
  static_assert(sizeof(Triangle) == 3 * sizeof(std::uint32_t));
  FaceRotationArgs args;
  args.triangles = topology.triangles.empty() ? nullptr : topology.triangles.front().data();
  args.base = base.data();
  args.edited = scratch.edited.data();
  args.faces = scratch.faces.data();
  args.count = face_count;
  args.offsets = scratch.face_offset.data();
  args.redo = redo.data();
  redo.resize(face_rotations_kernel()(args));
  for (; first_scalar + 2 <= redo.size(); first_scalar += 2) {
    const Vec3f* p[2][6];
    for (int f = 0; f < 2; ++f) {
      const Triangle& t = topology.triangles[scratch.faces[redo[first_scalar + f]]];
      for (int i = 0; i < 3; ++i) {
        p[f][i] = &base[t[i]];
        p[f][3 + i] = &scratch.edited[t[i]];
      }
    }
    Quat q[2];
    bool ok[2];
    face_rotation_kernel_x2(p, q, ok);
    for (int f = 0; f < 2; ++f)
      scratch.face_offset[redo[first_scalar + f]] =
          ok[f] ? Quat{q[f].w - 1.f, q[f].x, q[f].y, q[f].z} : Quat{0, 0, 0, 0};
  }
#else
  std::size_t declined = 0;
  for (std::size_t k = 0; k < face_count; ++k) {
    const Triangle& t = topology.triangles[scratch.faces[k]];
    Quat q;
    if (face_rotation_kernel_f1(base[t[0]], base[t[1]], base[t[2]], scratch.edited[t[0]],
                                scratch.edited[t[1]], scratch.edited[t[2]], q))
      scratch.face_offset[k] = Quat{q.w - 1.f, q.x, q.y, q.z};
    else
      redo[declined++] = static_cast<std::uint32_t>(k);
  }
  redo.resize(declined);
#endif
  for (std::size_t r = first_scalar; r < redo.size(); ++r) {
    const std::uint32_t k = redo[r];
    const Triangle& t = topology.triangles[scratch.faces[k]];
    Quat q;
    scratch.face_offset[k] =
        face_rotation_kernel(base[t[0]], base[t[1]], base[t[2]], scratch.edited[t[0]],
                             scratch.edited[t[1]], scratch.edited[t[2]], q)
            ? Quat{q.w - 1.f, q.x, q.y, q.z}
            : Quat{0, 0, 0, 0};
  }
  // 3. summed at their vertices
#if defined(__SSE2__)
  // The same operations on registers, lane by lane in the same order (dq_simd.h).
  for (std::size_t k = 0; k < scratch.faces.size(); ++k) {
    const __m128 o = _mm_loadu_ps(&scratch.face_offset[k].w);
    for (std::uint32_t u : topology.triangles[scratch.faces[k]])
      _mm_storeu_ps(&scratch.rotation_sum[u].w,
                    _mm_add_ps(_mm_loadu_ps(&scratch.rotation_sum[u].w), o));
  }
  // 4. per vertex: its rotation and the translation that lands it on its edited position,
  // 4 or 8 vertices per register (face_rotation_lanes.h), each lane the scalar sequence below
  VertexFinishArgs finish;
  finish.vertices = touched.data();
  finish.count = touched.size();
  finish.face_offsets = vf.offsets.data();
  finish.rotation_sum = scratch.rotation_sum.data();
  finish.base = base.data();
  finish.edited = scratch.edited.data();
  finish.center = frame.center;
  finish.inv_scale = frame.inv_scale;
  scratch.finished.resize(touched.size());
  finish.out = scratch.finished.data();
  vertex_finish_kernel()(finish);
  for (std::size_t i = 0; i < touched.size(); ++i) store(touched[i], scratch.finished[i]);
#else
  for (std::size_t k = 0; k < scratch.faces.size(); ++k)
    for (std::uint32_t u : topology.triangles[scratch.faces[k]])
      scratch.rotation_sum[u] = scratch.rotation_sum[u] + scratch.face_offset[k];
  for (std::uint32_t u : touched) {
    const Quat& s = scratch.rotation_sum[u];
    const float degree = static_cast<float>(vf.offsets[u + 1] - vf.offsets[u]);
    Quat r{degree + s.w, s.x, s.y, s.z};
    const float n2 = dot(r, r);
    r = n2 > 1e-30f ? (1.f / std::sqrt(n2)) * r : Quat{};
    store(u, canonical(DualQuat::from_rotation_and_points(r, frame.to_local(base[u]),
                                                          frame.to_local(scratch.edited[u]))));
  }
#endif
}

}  // namespace csculpt::detail
