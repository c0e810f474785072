// A grab recognised in a diff (radial_grab.h).
#include "radial_grab.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

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

template <int N>
using Square = Eigen::Matrix<double, N, N>;
template <int N>
using Column = Eigen::Matrix<double, N, 1>;

/// Normal equations A^T A x = A^T y, accumulated row by row.
template <int N>
struct NormalEquations {
  Square<N> ata = Square<N>::Zero();
  Column<N> atb = Column<N>::Zero();

  void add(const Column<N>& row, double y) {
    ata.noalias() += row * row.transpose();
    atb += row * y;
  }

  /// The least-squares solution into x (a ridge of 1e-12 of the diagonal keeps exact
  /// collinearity from dividing by zero); false when the equations are singular.
  bool solve(Column<N>& x) {
    ata.diagonal() *= 1 + 1e-12;
    const Eigen::LLT<Square<N>> llt(ata);
    if (llt.info() != Eigen::Success) return false;
    x = llt.solve(atb);
    return true;
  }

  /// Whether the first three unknowns are fixed once the others are eliminated: the Schur
  /// complement of the rest, by kDetermined.
  bool centre_determined() const {
    constexpr int m = N - 3;
    const Eigen::LLT<Square<m>> rest(ata.template bottomRightCorner<m, m>());
    if (rest.info() != Eigen::Success) return false;
    const Eigen::Matrix3d schur =
        ata.template topLeftCorner<3, 3>() -
        ata.template topRightCorner<3, m>() * rest.solve(ata.template bottomLeftCorner<m, 3>());
    const double trace = schur.trace();
    return trace > 0 && schur.determinant() >= kDetermined * trace * trace * trace;
  }
};

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
  constexpr int m = 3 + kInverseDegree + 1;
  NormalEquations<m> equations;
  std::size_t used = 0;
  for (std::size_t i = 0; i < at_.size(); ++i) {
    const double f = length_[i] / peak_;
    if (!(f >= kRim)) continue;
    const Vec3d p = scale(sub(at_[i], centre_), 1.0 / rho_);
    Column<m> row;
    row << 2 * p.x, 2 * p.y, 2 * p.z, 1, Column<m - 4>::Zero();
    for (int k = 1; k <= static_cast<int>(kInverseDegree); ++k) row[3 + k] = row[2 + k] * f;
    equations.add(row, norm2(p));
    ++used;
  }
  Column<m> x;
  if (used < 2 * m || !equations.centre_determined() || !equations.solve(x)) return false;
  centre_ = add(centre_, scale(Vec3d{x[0], x[1], x[2]}, rho_));
  return true;
}

/// The falloff, a polynomial in the distance from the centre over rho fitted by least squares
/// to every sample, and whether the samples lie on it (kScatter).
bool RadialGrab::fit_falloff() {
  constexpr int m = kFalloffDegree + 1;
  NormalEquations<m> equations;
  reach_ = 0;
  for (std::size_t i = 0; i < at_.size(); ++i) {
    const double x = length(sub(at_[i], centre_)) / rho_;
    reach_ = std::max(reach_, x);
    Column<m> power;
    power[0] = 1;
    for (int k = 1; k < m; ++k) power[k] = power[k - 1] * x;
    equations.add(power, length_[i]);
  }
  Column<m> a;
  if (!equations.solve(a)) return false;
  for (int k = 0; k < m; ++k) falloff_[k] = a[k];
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
