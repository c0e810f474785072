// Internal: how a diff deforms the space around the surface, read from the surface itself.
//
// A volumetric deformer (a taper, a Cast, a grab's falloff) moves a detail that stands on the
// surface as its Jacobian J = I + grad u moves the detail's vector: that is the stacked ideal
// (docs/merge-quality.md). One face shows J only along the surface, but the displacements of
// a curved region, whose points spread in three dimensions, fix all of it: a weighted
// least-squares affine fit of the diff's displacement u over the samples within `radius`
// (weights (1 - d^2 / r^2)^2). Samples of every part count, as a volumetric deformer moves
// every part within its reach, and coincident vertices of a split seam read the same fit, so
// the seam stays closed. Where the region is flat
// the normal column is not seen, and a ridge pulls it toward sigma n: the region scaling its
// thickness as evenly as its surface (sigma the geometric mean of the tangent stretches).
//
// Fitted at sample vertices (a hierarchy level's representatives: about a thousand over the
// mesh, whatever its resolution), only those near a vertex that some diff carries, and
// interpolated from the samples within half the radius.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/vec3.h"
#include "worker_pool.h"

namespace csculpt::detail {

/// A 3 x 3 matrix in double, row-major. Left uninitialised by default: the transport keeps
/// one per diff for every vertex it merges.
struct Mat3d {
  std::array<double, 9> m;
};

inline constexpr Mat3d kIdentity3{{1, 0, 0, 0, 1, 0, 0, 0, 1}};

inline Vec3d apply(const Mat3d& a, const Vec3d& v) {
  return {a.m[0] * v.x + a.m[1] * v.y + a.m[2] * v.z, a.m[3] * v.x + a.m[4] * v.y + a.m[5] * v.z,
          a.m[6] * v.x + a.m[7] * v.y + a.m[8] * v.z};
}

/// Where the Jacobians are fitted: sample vertices (distinct) and the fitting radius.
struct JacobianSamples {
  std::span<const std::uint32_t> vertices;
  double radius = 0;
};

class RegionalJacobians {
 public:
  /// Sorts the samples into cells of the read reach; clears what the last merge fitted.
  void prepare(std::span<const Vec3f> base, const JacobianSamples& samples, std::size_t users);
  bool ready() const { return radius_ > 0 && !site_.empty(); }
  /// Marks the samples that a vertex at base position `p` reads.
  void need(const Vec3d& p);
  /// Fits diff `user`'s Jacobian at every marked sample; `displacement(v)` and `normal(v)`
  /// give its displacement and the base normal at vertex v.
  template <class Displacement, class Normal>
  void fit(std::size_t user, const Displacement& displacement, const Normal& normal,
           WorkerPool& pool);
  /// Diff `user`'s Jacobian at base position p, interpolated from the fitted samples near it;
  /// returns how much they vouch for it, in [0, 1] (0: none near, and a = I).
  double at(const Vec3d& p, std::size_t user, Mat3d& a) const;

 private:
  struct Site {
    Vec3d p;
    std::uint32_t vertex = 0;
  };
  /// A cell of the grid: its key and its samples, site_[begin, end); end == 0 marks a free
  /// slot of the table.
  struct Cell {
    std::uint64_t key = 0;
    std::uint32_t begin = 0, end = 0;
  };
  std::int64_t axis_cell(double x) const;
  static std::uint64_t key_of(std::int64_t x, std::int64_t y, std::int64_t z);
  std::uint64_t key_at(const Vec3d& p) const;
  /// The samples of the cell with `key`, as a range of site_.
  std::pair<std::uint32_t, std::uint32_t> cell(std::uint64_t key) const;
  template <class Visit>
  void near(const Vec3d& p, double reach, const Visit& visit) const;
  Mat3d fit_site(std::size_t s, const Vec3d& n) const;

  double radius_ = 0;
  double cell_ = 0;  ///< the grid's cell: the reach of a read, so that one visits few samples
  Vec3d origin_{};
  std::vector<Site> site_;                             ///< sorted by cell key, then by vertex
  std::vector<std::pair<std::uint64_t, Site>> keyed_;  ///< scratch of prepare()
  std::vector<Cell> table_;                            ///< open addressing by cell key
  std::vector<std::uint8_t> needed_;                   ///< per site
  std::vector<std::uint32_t> needed_list_;
  std::uint64_t last_needed_ = ~std::uint64_t{0};  ///< the cell need() marked last
  std::vector<Vec3d> moved_;                       ///< per site: the displacement being fitted
  std::vector<Mat3d> fitted_;                      ///< per user and site
  std::vector<std::uint8_t> ok_;                   ///< per user and site: fitted and well posed
  std::size_t users_ = 0;
};

template <class Displacement, class Normal>
void RegionalJacobians::fit(std::size_t user, const Displacement& displacement,
                            const Normal& normal, WorkerPool& pool) {
  for (std::size_t s = 0; s < site_.size(); ++s) moved_[s] = displacement(site_[s].vertex);
  pool.for_chunks(needed_list_.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t s = needed_list_[k];
      const Vec3d n = normal(site_[s].vertex);
      const Mat3d a = fit_site(s, n);
      const bool good =
          std::all_of(a.m.begin(), a.m.end(), [](double x) { return std::isfinite(x); });
      fitted_[user * site_.size() + s] = good ? a : kIdentity3;
      ok_[user * site_.size() + s] = good;
    }
  });
}

}  // namespace csculpt::detail
