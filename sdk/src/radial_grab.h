// Internal: a grab recognised in a diff, so that how it moves the space off the surface, and
// with it a detail standing on the surface, is known rather than estimated.
//
// A grab (Blender's Warp, proportional editing, a sculpting grab brush) moves every point along
// one direction t by a falloff of its distance from a centre c: u(p) = t phi(|p - c|). Both
// show in the diff itself: its displacements are parallel, and their lengths are one function
// of the distance from some centre. Where both hold to rounding, the stacked reading of a
// detail d standing at p is exact, with no linearisation:
//
//   d + t (phi(|p + d - c|) - phi(|p - c|)).
//
// The regional Jacobian (regional_jacobian.h) reads a grab's falloff as affine over its
// radius; where the falloff is steep across that radius it read a detail stretched by 40 %
// where the stack stretched it by 8 % (docs/merge-quality.md, "A grab read as a grab").
//
// The fit (trilaterate()): t is the direction of the largest displacement; the centre comes
// from one linear least-squares problem, the falloff from another (a polynomial in the
// distance). A surface that is a sphere about the grab's axis shows no centre — every point
// of that axis explains it, each with its own falloff and its own action off the surface — so
// a grab whose centre the surface leaves undetermined is refused, as is one that does not fit.
// Everything runs in vertex order in double: peers fit bit-identical grabs.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/vec3.h"

namespace csculpt::detail {

class RadialGrab {
 public:
  static constexpr std::size_t kFalloffDegree = 4;
  static constexpr std::size_t kInverseDegree = 4;
  static constexpr std::size_t kMostSamples = 2048;

  /// Fits the grab to a diff that moves `vertices` (increasing) of `base` by
  /// `displacement(v)`; returns whether the diff is a grab (valid()).
  template <class Displacement>
  bool fit(std::span<const Vec3f> base, std::span<const std::uint32_t> vertices,
           const Displacement& displacement);

  bool valid() const { return valid_; }
  void reset() { valid_ = false; }

  /// How the grab moves a detail displacement `d` standing at base point `p`.
  Vec3d carry(const Vec3d& p, const Vec3d& d) const;

 private:
  using Falloff = std::array<double, kFalloffDegree + 1>;

  bool sample(std::span<const Vec3f> base, std::span<const std::uint32_t> vertices);
  bool trilaterate();
  bool fit_falloff();
  /// The falloff at distance `r` from the centre (constant beyond the farthest sample).
  double falloff(double r) const;

  bool valid_ = false;
  Vec3d direction_{};  ///< unit t
  Vec3d centre_{};
  double peak_ = 0;   ///< the largest displacement's length
  double rho_ = 0;    ///< the distances' unit: the farthest sample from the peak vertex
  double reach_ = 0;  ///< the farthest sample's distance from the centre, over rho
  Falloff falloff_{};
  std::vector<Vec3d> moves_;    ///< every moved vertex's displacement
  std::vector<Vec3d> at_;       ///< the samples' base positions
  std::vector<double> length_;  ///< the samples' displacement along t
};

template <class Displacement>
bool RadialGrab::fit(std::span<const Vec3f> base, std::span<const std::uint32_t> vertices,
                     const Displacement& displacement) {
  moves_.resize(vertices.size());
  for (std::size_t k = 0; k < vertices.size(); ++k) moves_[k] = displacement(vertices[k]);
  valid_ = sample(base, vertices) && trilaterate() && fit_falloff();
  return valid_;
}

}  // namespace csculpt::detail
