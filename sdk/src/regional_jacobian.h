// Internal: how a diff deforms the space around the surface, read from the surface itself.
//
// A volumetric deformer (a taper, a Cast, a grab's falloff) moves a detail that stands on the
// surface as its Jacobian J = I + grad u moves the detail's vector: that is the stacked ideal
// (docs/merge-quality.md). One face shows J only along the surface, but the displacements of
// a curved region, whose points spread in three dimensions, fix all of it: a weighted
// least-squares affine fit of the diff's displacement u over the samples within `radius`
// (weights (1 - d^2 / r^2)^2). Samples of every part count, as a volumetric deformer moves
// every part within its reach, and coincident vertices of a split seam read the same fit, so
// the seam stays closed. Where the region is flat the normal column is not seen, and a ridge
// along the normal pulls it toward sigma n: the region scaling its thickness as evenly as its
// surface (sigma the geometric mean of the tangent stretches).
//
// Fitted at sample vertices (a hierarchy level's representatives: at most 2,048 over the
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

/// A symmetric 3 x 3 matrix in double.
struct Sym3 {
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
};

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
  /// Gathers, once for every diff, the marked samples' neighbourhoods and what of their fit
  /// does not depend on the diff; `normal(v)` gives the base normal at vertex v.
  template <class Normal>
  void plan(const Normal& normal, WorkerPool& pool);
  /// Fits diff `user`'s Jacobian at every marked sample (after plan());
  /// `displacement(v)` gives its displacement at vertex v.
  template <class Displacement>
  void fit(std::size_t user, const Displacement& displacement, WorkerPool& pool);

  /// The fitted samples near one position, with their weights: gathered once, read for each
  /// diff that carries there.
  struct Reading {
    static constexpr std::uint32_t kMost = 48;
    Vec3d p;
    std::uint32_t count = 0;
    bool overflow = false;  ///< more than kMost near: each diff's read gathers its own
    std::array<std::uint32_t, kMost> site;
    std::array<double, kMost> weight;
  };
  void gather(const Vec3d& p, Reading& reading) const;
  /// Diff `user`'s Jacobian at the reading's position, interpolated from the fitted samples
  /// near it; returns how much they vouch for it, in [0, 1] (0: none near, and a = I).
  double at(const Reading& reading, std::size_t user, Mat3d& a) const;

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
  /// What a sample's fit takes from its neighbourhood whatever the diff: the weighted mean
  /// offset of its neighbours and their ridged covariance (the neighbours and their weights
  /// are in near_site_ and near_weight_ from near_offset_[k]).
  struct Plan {
    Vec3d n, mean;
    Sym3 cov;
    double w_sum = 0, ridge = 0;
    std::uint32_t count = 0;
    bool ok = false;
  };
  std::size_t seen_slot(std::uint64_t key) const;
  std::uint32_t count_near(std::size_t k) const;
  void plan_site(std::size_t k, const Vec3d& n);
  Mat3d fit_site(std::size_t k) const;
  template <class Offer>
  double mean_fit(std::size_t user, Mat3d& a, const Offer& offer) const;

  double radius_ = 0;
  double cell_ = 0;  ///< the grid's cell: the reach of a read, so that one visits few samples
  Vec3d origin_{};
  std::vector<Site> site_;                             ///< sorted by cell key, then by vertex
  std::vector<std::pair<std::uint64_t, Site>> keyed_;  ///< scratch of prepare()
  std::vector<Cell> table_;                            ///< open addressing by cell key
  std::vector<std::uint8_t> needed_;                   ///< per site
  std::vector<std::uint32_t> needed_list_;
  /// The cells need() has visited, open addressing; their candidates_ are [begin, end - 1).
  std::vector<Cell> seen_;
  std::size_t seen_count_ = 0;
  std::vector<std::uint32_t> candidates_;   ///< per visited cell, the samples its points read
  std::vector<Plan> plan_;                  ///< per marked sample (needed_list_ order)
  std::vector<std::uint32_t> near_offset_;  ///< per marked sample, into near_site_
  std::vector<std::uint32_t> near_site_;    ///< the marked samples' neighbours
  std::vector<double> near_weight_;         ///< and their weights
  std::vector<Vec3d> moved_;                ///< per site: the displacement being fitted
  std::vector<Mat3d> fitted_;               ///< per user and site
  std::vector<std::uint8_t> ok_;            ///< per user and site: fitted and well posed
};

template <class Normal>
void RegionalJacobians::plan(const Normal& normal, WorkerPool& pool) {
  const std::size_t marked = needed_list_.size();
  plan_.resize(marked);
  near_offset_.resize(marked + 1);
  pool.for_chunks(marked, 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) near_offset_[k + 1] = count_near(k);
  });
  near_offset_[0] = 0;
  for (std::size_t k = 0; k < marked; ++k) near_offset_[k + 1] += near_offset_[k];
  near_site_.resize(near_offset_[marked]);
  near_weight_.resize(near_offset_[marked]);
  pool.for_chunks(marked, 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) plan_site(k, normal(site_[needed_list_[k]].vertex));
  });
}

template <class Displacement>
void RegionalJacobians::fit(std::size_t user, const Displacement& displacement, WorkerPool& pool) {
  for (std::size_t s = 0; s < site_.size(); ++s) moved_[s] = displacement(site_[s].vertex);
  pool.for_chunks(needed_list_.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t s = needed_list_[k];
      const Mat3d a = fit_site(k);
      const bool good =
          std::all_of(a.m.begin(), a.m.end(), [](double x) { return std::isfinite(x); });
      fitted_[user * site_.size() + s] = good ? a : kIdentity3;
      ok_[user * site_.size() + s] = good;
    }
  });
}

}  // namespace csculpt::detail
