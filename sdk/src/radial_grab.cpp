// A grab recognised in a diff (radial_grab.h).
#include "radial_grab.h"

#include <algorithm>
#include <cmath>

#include "regional_jacobian.h"

namespace csculpt::detail {
namespace {

/// Fewer moved vertices than this fit no falloff worth trusting: a stroke of a few vertices is
/// a detail, not a grab.
constexpr std::size_t kLeastMoved = 32;

/// The share of the displacements' squared length allowed off their common direction: float
/// rounding keeps parallel moves below 1e-11 (Blender's Warps and Hooks in the eval sets); the
/// nearest other edit there, a Cast of one part, spreads 0.6 %.
constexpr double kParallel = 1e-6;

/// The least displacement, relative to the peak, that trilaterate() reads a distance from: at
/// the falloff's rim the distance changes fastest with the length and is no polynomial of it
/// (a smoothstep's goes as its square root).
constexpr double kRim = 0.05;

/// The least determinant, relative to its trace cubed, of what the samples say about the
/// centre (the centre block of the trilateration's normal equations once the falloff is
/// eliminated). A sphere about the grab's axis would say nothing but for the falloff's degree:
/// 2e-7 (RadialGrab.ASphereAboutTheGrabHidesItsCentre); an ellipsoid of axes 1 : 0.8 : 1.3,
/// 2.5e-4, centre found to 0.003; the Warps of the eval sets (a house, a duck, a keyboard, an
/// engine, faces, a capsule and a torus) 2.5e-3 - 3.4e-2, centres found to 0.002.
constexpr double kDetermined = 1e-5;

/// The largest RMS distance, relative to the peak displacement, of the displacements from the
/// fitted falloff: the Warps of the eval sets lie within 6e-4 of theirs; a Hook's per-vertex
/// weights (0.29 in RadialGrab.RefusesWhatIsNoGrab), a grab cut by the mesh's thin parts or two
/// grabs in one diff do not.
constexpr double kScatter = 0.01;

/// Solves A x = b for A symmetric positive definite (N x N, row-major) by Cholesky, in place
/// (x into b): false when A is not positive definite.
template <std::size_t N>
bool cholesky_solve(std::array<double, N * N>& a, std::array<double, N>& b) {
  for (std::size_t j = 0; j < N; ++j) {
    double d = a[j * N + j];
    for (std::size_t k = 0; k < j; ++k) d -= a[j * N + k] * a[j * N + k];
    if (!(d > 0)) return false;
    const double l = std::sqrt(d);
    a[j * N + j] = l;
    for (std::size_t i = j + 1; i < N; ++i) {
      double s = a[i * N + j];
      for (std::size_t k = 0; k < j; ++k) s -= a[i * N + k] * a[j * N + k];
      a[i * N + j] = s / l;
    }
  }
  for (std::size_t i = 0; i < N; ++i) {  // L y = b
    for (std::size_t k = 0; k < i; ++k) b[i] -= a[i * N + k] * b[k];
    b[i] /= a[i * N + i];
  }
  for (std::size_t i = N; i-- > 0;) {  // L^T x = y
    for (std::size_t k = i + 1; k < N; ++k) b[i] -= a[k * N + i] * b[k];
    b[i] /= a[i * N + i];
  }
  return true;
}

/// Adds row r with right-hand side y to the normal equations (ata, atb).
template <std::size_t N>
void accumulate(const std::array<double, N>& r, double y, std::array<double, N * N>& ata,
                std::array<double, N>& atb) {
  for (std::size_t u = 0; u < N; ++u) {
    atb[u] += r[u] * y;
    for (std::size_t v = 0; v < N; ++v) ata[u * N + v] += r[u] * r[v];
  }
}

/// Whether the first three unknowns of the normal equations `ata` (N x N, N > 3) are fixed by
/// them once the others are eliminated: the Schur complement of the rest, by kDetermined.
template <std::size_t N>
bool centre_determined(const std::array<double, N * N>& ata) {
  constexpr std::size_t m = N - 3;
  double s[3][3];
  for (std::size_t c = 0; c < 3; ++c) {
    std::array<double, m * m> rest;
    std::array<double, m> x;
    for (std::size_t u = 0; u < m; ++u) {
      x[u] = ata[(3 + u) * N + c];
      for (std::size_t v = 0; v < m; ++v) rest[u * m + v] = ata[(3 + u) * N + 3 + v];
    }
    if (!cholesky_solve<m>(rest, x)) return false;
    for (std::size_t r = 0; r < 3; ++r) {
      double e = ata[r * N + c];
      for (std::size_t u = 0; u < m; ++u) e -= ata[r * N + 3 + u] * x[u];
      s[r][c] = e;
    }
  }
  const Sym3 schur{s[0][0], s[0][1], s[0][2], s[1][1], s[1][2], s[2][2]};
  const double trace = schur.xx + schur.yy + schur.zz;
  return trace > 0 && determinant(schur) >= kDetermined * trace * trace * trace;
}

double norm2(const Vec3d& v) {
  return dot(v, v);
}

}  // namespace

/// The direction, whether the displacements are parallel to it, and the samples (at most
/// kMostSamples of the moved vertices, evenly in their order). The centre starts at the vertex
/// moved most.
bool RadialGrab::sample(std::span<const Vec3f> base, std::span<const std::uint32_t> vertices) {
  const std::size_t n = vertices.size();
  if (n < kLeastMoved) return false;
  std::size_t peak = 0;
  for (std::size_t k = 1; k < n; ++k)
    if (norm2(moves_[k]) > norm2(moves_[peak])) peak = k;
  peak_ = std::sqrt(norm2(moves_[peak]));
  if (!(peak_ > 0)) return false;
  direction_ = scale(moves_[peak], 1.0 / peak_);
  double total = 0, off = 0;
  for (const Vec3d& g : moves_) {
    total += norm2(g);
    off += norm2(sub(g, scale(direction_, dot(g, direction_))));
  }
  if (!(off <= kParallel * total)) return false;
  centre_ = widen(base[vertices[peak]]);
  const std::size_t stride = (n + kMostSamples - 1) / kMostSamples;
  at_.clear();
  length_.clear();
  rho_ = 0;
  for (std::size_t k = 0; k < n; k += stride) {
    at_.push_back(widen(base[vertices[k]]));
    length_.push_back(dot(moves_[k], direction_));
    rho_ = std::max(rho_, length(sub(at_.back(), centre_)));
  }
  return rho_ > 0;
}

/// The centre, from every distance being one function of the displacement's length: with
/// positions p taken from the starting centre, |p|^2 = 2 p.c + q(f) for f the length over the
/// peak and q(f) = r(f)^2 - |c|^2, which is linear in c and in q's coefficients (a polynomial
/// of degree kInverseDegree). Distances in units of rho.
bool RadialGrab::trilaterate() {
  constexpr std::size_t m = 3 + kInverseDegree + 1;
  std::array<double, m * m> ata{};
  std::array<double, m> atb{};
  std::size_t used = 0;
  for (std::size_t i = 0; i < at_.size(); ++i) {
    const double f = length_[i] / peak_;
    if (!(f >= kRim)) continue;
    const Vec3d p = scale(sub(at_[i], centre_), 1.0 / rho_);
    std::array<double, m> row;
    row[0] = 2 * p.x, row[1] = 2 * p.y, row[2] = 2 * p.z, row[3] = 1;
    for (std::size_t k = 1; k <= kInverseDegree; ++k) row[3 + k] = row[2 + k] * f;
    accumulate<m>(row, norm2(p), ata, atb);
    ++used;
  }
  if (used < 2 * m || !centre_determined<m>(ata)) return false;
  if (!cholesky_solve<m>(ata, atb)) return false;
  centre_ = add(centre_, scale(Vec3d{atb[0], atb[1], atb[2]}, rho_));
  return true;
}

/// The falloff, a polynomial in the distance from the centre over rho fitted by least squares
/// to every sample, and whether the samples lie on it (kScatter).
bool RadialGrab::fit_falloff() {
  constexpr std::size_t m = kFalloffDegree + 1;
  std::array<double, m * m> ata{};
  std::array<double, m> atb{};
  reach_ = 0;
  for (std::size_t i = 0; i < at_.size(); ++i) {
    const double x = length(sub(at_[i], centre_)) / rho_;
    reach_ = std::max(reach_, x);
    std::array<double, m> power;
    power[0] = 1;
    for (std::size_t k = 1; k < m; ++k) power[k] = power[k - 1] * x;
    accumulate<m>(power, length_[i], ata, atb);
  }
  if (!cholesky_solve<m>(ata, atb)) return false;
  falloff_ = atb;
  double squares = 0;
  for (std::size_t i = 0; i < at_.size(); ++i) {
    const double e = falloff(length(sub(at_[i], centre_))) - length_[i];
    squares += e * e;
  }
  return std::sqrt(squares / static_cast<double>(at_.size())) <= kScatter * peak_;
}

double RadialGrab::falloff(double r) const {
  const double x = std::min(r / rho_, reach_);
  double p = 0;
  for (std::size_t k = kFalloffDegree + 1; k-- > 0;) p = p * x + falloff_[k];
  return p;
}

Vec3d RadialGrab::carry(const Vec3d& p, const Vec3d& d) const {
  const double before = falloff(length(sub(p, centre_)));
  const double after = falloff(length(sub(add(p, d), centre_)));
  return add(d, scale(direction_, after - before));
}

}  // namespace csculpt::detail
