#include "regional_jacobian.h"

#include <algorithm>
#include <cmath>

namespace csculpt::detail {
namespace {

/// The share of the covariance's trace by which the fit's normal column is pulled toward its
/// prior: enough to fix a flat region's, too little to bend a curved one's.
constexpr double kRidge = 1e-3;
/// The least determinant of the ridged covariance, relative to its trace cubed, that fixes a
/// Jacobian (a plane's is 2.5e-4 of it; samples along a line give next to none).
constexpr double kConditioning = 1e-6;
/// Samples interpolate the fitted Jacobians within this share of the fitting radius.
constexpr double kReadReach = 0.5;
constexpr std::int64_t kCellBias = 1 << 20;

double determinant(const Sym3& s) {
  return s.xx * (s.yy * s.zz - s.yz * s.yz) - s.xy * (s.xy * s.zz - s.xz * s.yz) +
         s.xz * (s.xy * s.yz - s.xz * s.yy);
}

/// x = S^-1 b for the columns of b (row-major 3 x 3); NaN where S is singular.
Mat3d solve(const Sym3& s, const Mat3d& b) {
  const double c00 = s.yy * s.zz - s.yz * s.yz, c01 = s.xz * s.yz - s.xy * s.zz,
               c02 = s.xy * s.yz - s.xz * s.yy, c11 = s.xx * s.zz - s.xz * s.xz,
               c12 = s.xy * s.xz - s.xx * s.yz, c22 = s.xx * s.yy - s.xy * s.xy;
  const double det = determinant(s);
  Mat3d x;
  const double inv[9] = {c00, c01, c02, c01, c11, c12, c02, c12, c22};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      x.m[r * 3 + c] =
          (inv[r * 3] * b.m[c] + inv[r * 3 + 1] * b.m[3 + c] + inv[r * 3 + 2] * b.m[6 + c]) / det;
  return x;
}

/// A unit vector perpendicular to unit n.
Vec3d perpendicular(const Vec3d& n) {
  const Vec3d t = std::fabs(n.x) < 0.9 ? cross(n, Vec3d{1, 0, 0}) : cross(n, Vec3d{0, 1, 0});
  return scale(t, 1.0 / length(t));
}

/// The geometric mean of the stretches A gives the plane of unit normal n.
double tangent_stretch(const Mat3d& a, const Vec3d& n) {
  const Vec3d t1 = perpendicular(n), t2 = cross(n, t1);
  const Vec3d a1 = apply(a, t1), a2 = apply(a, t2);
  const double g11 = dot(a1, a1), g12 = dot(a1, a2), g22 = dot(a2, a2);
  return std::sqrt(std::sqrt(std::max(0.0, g11 * g22 - g12 * g12)));
}

/// Spreads a cell key over the hash table's slots.
std::uint64_t mix(std::uint64_t key) {
  key = (key ^ (key >> 31)) * 0xbf58476d1ce4e5b9ull;
  return key ^ (key >> 29);
}

}  // namespace

std::int64_t RegionalJacobians::axis_cell(double x) const {
  return static_cast<std::int64_t>(std::floor(x / cell_));
}

std::uint64_t RegionalJacobians::key_of(std::int64_t x, std::int64_t y, std::int64_t z) {
  auto field = [](std::int64_t i) { return static_cast<std::uint64_t>(i + kCellBias) & 0x1fffff; };
  return field(x) << 42 | field(y) << 21 | field(z);
}

std::uint64_t RegionalJacobians::key_at(const Vec3d& p) const {
  const Vec3d q = sub(p, origin_);
  return key_of(axis_cell(q.x), axis_cell(q.y), axis_cell(q.z));
}

std::pair<std::uint32_t, std::uint32_t> RegionalJacobians::cell(std::uint64_t key) const {
  const std::size_t mask = table_.size() - 1;
  for (std::size_t h = mix(key) & mask; table_[h].end != 0; h = (h + 1) & mask)
    if (table_[h].key == key) return {table_[h].begin, table_[h].end};
  return {0, 0};
}

void RegionalJacobians::prepare(std::span<const Vec3f> base, const JacobianSamples& samples,
                                std::size_t users) {
  radius_ = samples.radius;
  cell_ = kReadReach * radius_;
  site_.clear();
  keyed_.clear();
  needed_list_.clear();
  if (!(radius_ > 0) || samples.vertices.empty()) return;
  origin_ = widen(base[samples.vertices[0]]);
  for (const std::uint32_t v : samples.vertices) {
    const Site s{widen(base[v]), v};
    keyed_.emplace_back(key_at(s.p), s);
  }
  std::sort(keyed_.begin(), keyed_.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : a.second.vertex < b.second.vertex;
  });
  std::size_t size = 64;
  while (size < 2 * keyed_.size()) size *= 2;
  table_.assign(size, Cell{});
  std::size_t slot = 0;  // the table's slot of the cell being filled
  for (std::uint32_t k = 0; k < keyed_.size(); ++k) {
    site_.push_back(keyed_[k].second);
    if (k > 0 && keyed_[k].first == keyed_[k - 1].first) {
      ++table_[slot].end;
      continue;
    }
    std::size_t h = mix(keyed_[k].first) & (size - 1);
    while (table_[h].end != 0) h = (h + 1) & (size - 1);
    table_[h] = {keyed_[k].first, k, k + 1};
    slot = h;
  }
  needed_.assign(site_.size(), 0);
  seen_.assign(std::max<std::size_t>(seen_.size(), 1024), Cell{});  // as large as last time
  seen_count_ = 0;
  candidates_.clear();
  moved_.resize(site_.size());
  fitted_.resize(users * site_.size());
  ok_.assign(users * site_.size(), 0);
}

/// Calls visit(site, squared distance) for the sites within `reach` of p, cell by cell along
/// x, y, z and by site within a cell: a fixed order, so the sums are bit-identical.
template <class Visit>
void RegionalJacobians::near(const Vec3d& p, double reach, const Visit& visit) const {
  const double r2 = reach * reach;
  const Vec3d q = sub(p, origin_);
  const std::int64_t x0 = axis_cell(q.x - reach), x1 = axis_cell(q.x + reach);
  const std::int64_t y0 = axis_cell(q.y - reach), y1 = axis_cell(q.y + reach);
  const std::int64_t z0 = axis_cell(q.z - reach), z1 = axis_cell(q.z + reach);
  for (std::int64_t x = x0; x <= x1; ++x)
    for (std::int64_t y = y0; y <= y1; ++y)
      for (std::int64_t z = z0; z <= z1; ++z) {
        const auto [begin, end] = cell(key_of(x, y, z));
        for (std::uint32_t s = begin; s < end; ++s) {
          const Vec3d d = sub(site_[s].p, p);
          const double d2 = dot(d, d);
          if (d2 < r2) visit(s, d2);
        }
      }
}

/// The slot of cell `key` in the table of cells need() has visited, or of the free slot
/// where it would go.
std::size_t RegionalJacobians::seen_slot(std::uint64_t key) const {
  const std::size_t mask = seen_.size() - 1;
  std::size_t h = mix(key) & mask;
  while (seen_[h].end != 0 && seen_[h].key != key) h = (h + 1) & mask;
  return h;
}

/// Marks every sample that a point of p's cell could read (within the read reach of the
/// cell's box), once per cell, and keeps them as the cell's candidates for gather().
void RegionalJacobians::need(const Vec3d& p) {
  const Vec3d q = sub(p, origin_);
  const std::int64_t x = axis_cell(q.x), y = axis_cell(q.y), z = axis_cell(q.z);
  const std::uint64_t key = key_of(x, y, z);
  if (seen_[seen_slot(key)].end != 0) return;
  if (2 * (seen_count_ + 1) > seen_.size()) {  // grow: rehash the cells seen
    std::vector<Cell> old(seen_.size() * 2);
    old.swap(seen_);
    for (const Cell& c : old)
      if (c.end != 0) seen_[seen_slot(c.key)] = c;
  }
  const double reach = kReadReach * radius_;
  const Vec3d lo =
      add(origin_, Vec3d{static_cast<double>(x) * cell_, static_cast<double>(y) * cell_,
                         static_cast<double>(z) * cell_});
  const Vec3d middle = add(lo, Vec3d{cell_ / 2, cell_ / 2, cell_ / 2});
  const auto begin = static_cast<std::uint32_t>(candidates_.size());
  // a point within reach of the cell is within reach + half its diagonal of its middle
  near(middle, cell_ * 0.8660254037844386 + reach, [&](std::uint32_t s, double) {
    const Vec3d d = sub(site_[s].p, lo);
    auto outside = [this](double t) { return t < 0 ? -t : (t > cell_ ? t - cell_ : 0.0); };
    const double dx = outside(d.x), dy = outside(d.y), dz = outside(d.z);
    if (dx * dx + dy * dy + dz * dz >= reach * reach) return;
    candidates_.push_back(s);
    if (needed_[s]) return;
    needed_[s] = 1;
    needed_list_.push_back(s);
  });
  // end > begin marks the slot used, even for a cell with no candidates
  seen_[seen_slot(key)] = {key, begin, static_cast<std::uint32_t>(candidates_.size()) + 1};
  ++seen_count_;
}

/// How many samples lie within the radius of marked sample k.
std::uint32_t RegionalJacobians::count_near(std::size_t k) const {
  std::uint32_t count = 0;
  near(site_[needed_list_[k]].p, radius_, [&count](std::uint32_t, double) { ++count; });
  return count;
}

/// The part of marked sample k's fit that no diff changes: its neighbours within the radius
/// and their weights, their weighted mean offset and covariance, ridged along the base normal
/// n (only there, so the tangent columns stay as measured); not ok where the neighbours cannot
/// fix a Jacobian (too few, about one point, or about a line: a thin part seen edge on).
void RegionalJacobians::plan_site(std::size_t k, const Vec3d& n) {
  const Site& c = site_[needed_list_[k]];
  const double r2 = radius_ * radius_;
  Plan& plan = plan_[k];
  plan = Plan{};
  plan.n = n;
  Vec3d pw{};
  Sym3 pp;
  std::uint32_t* sites = near_site_.data() + near_offset_[k];
  double* weights = near_weight_.data() + near_offset_[k];
  near(c.p, radius_, [&](std::uint32_t s, double d2) {
    const double f = 1 - d2 / r2, w = f * f;
    const Vec3d p = sub(site_[s].p, c.p);
    plan.w_sum += w;
    pw = add(pw, scale(p, w));
    pp.xx += w * p.x * p.x, pp.xy += w * p.x * p.y, pp.xz += w * p.x * p.z;
    pp.yy += w * p.y * p.y, pp.yz += w * p.y * p.z, pp.zz += w * p.z * p.z;
    sites[plan.count] = s, weights[plan.count] = w;
    ++plan.count;
  });
  if (plan.count < 4 || !(plan.w_sum > 0)) return;
  const double ws = plan.w_sum;
  const Vec3d pm = plan.mean = scale(pw, 1 / ws);
  Sym3 cov{pp.xx / ws - pm.x * pm.x, pp.xy / ws - pm.x * pm.y, pp.xz / ws - pm.x * pm.z,
           pp.yy / ws - pm.y * pm.y, pp.yz / ws - pm.y * pm.z, pp.zz / ws - pm.z * pm.z};
  const double trace = cov.xx + cov.yy + cov.zz;
  if (!(trace > 1e-6 * r2)) return;
  const double l = plan.ridge = kRidge * trace;
  cov.xx += l * n.x * n.x, cov.xy += l * n.x * n.y, cov.xz += l * n.x * n.z;
  cov.yy += l * n.y * n.y, cov.yz += l * n.y * n.z, cov.zz += l * n.z * n.z;
  if (!(determinant(cov) > kConditioning * trace * trace * trace)) return;
  plan.cov = cov;
  plan.ok = true;
}

/// The affine fit at marked sample k for the displacements in moved_: J = I + G^T with
/// G = (C + l n n^T)^-1 (B + l G0), C the neighbours' weighted covariance (plan_site), B
/// their positions' covariance with the displacements, G0 = (sigma - 1) n n^T the flat
/// region's prior. NaN where the plan is not ok.
Mat3d RegionalJacobians::fit_site(std::size_t k) const {
  const Plan& plan = plan_[k];
  Mat3d none;
  none.m.fill(std::nan(""));
  if (!plan.ok) return none;
  const Site& c = site_[needed_list_[k]];
  const std::uint32_t* sites = near_site_.data() + near_offset_[k];
  const double* weights = near_weight_.data() + near_offset_[k];
  Vec3d uw{};
  Mat3d pu;
  pu.m.fill(0);
  for (std::uint32_t j = 0; j < plan.count; ++j) {
    const double w = weights[j];
    const Vec3d p = sub(site_[sites[j]].p, c.p), u = moved_[sites[j]];
    uw = add(uw, scale(u, w));
    const double pv[3] = {p.x, p.y, p.z}, uv[3] = {u.x, u.y, u.z};
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) pu.m[r * 3 + q] += w * pv[r] * uv[q];
  }
  const double ws = plan.w_sum;
  const Vec3d um = scale(uw, 1 / ws);
  const double pmv[3] = {plan.mean.x, plan.mean.y, plan.mean.z}, umv[3] = {um.x, um.y, um.z};
  Mat3d b;
  for (int r = 0; r < 3; ++r)
    for (int q = 0; q < 3; ++q) b.m[r * 3 + q] = pu.m[r * 3 + q] / ws - pmv[r] * umv[q];
  auto jacobian = [](const Mat3d& g) {  // I + G^T
    Mat3d a;
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) a.m[r * 3 + q] = (r == q ? 1.0 : 0.0) + g.m[q * 3 + r];
    return a;
  };
  const Vec3d& n = plan.n;
  const double sigma = tangent_stretch(jacobian(solve(plan.cov, b)), n);
  const double nv[3] = {n.x, n.y, n.z};
  for (int r = 0; r < 3; ++r)
    for (int q = 0; q < 3; ++q) b.m[r * 3 + q] += plan.ridge * (sigma - 1) * nv[r] * nv[q];
  return jacobian(solve(plan.cov, b));
}

void RegionalJacobians::gather(const Vec3d& p, Reading& reading) const {
  const double reach = kReadReach * radius_, r2 = reach * reach;
  reading.p = p;
  reading.count = 0;
  reading.overflow = false;
  auto add = [&](std::uint32_t s, double d2) {
    if (reading.count == Reading::kMost) {
      reading.overflow = true;
      return;
    }
    const double f = 1 - d2 / r2;
    reading.site[reading.count] = s;
    reading.weight[reading.count++] = f * f;
  };
  const Cell& c = seen_[seen_slot(key_at(p))];
  if (c.end == 0) return near(p, reach, add);  // a cell need() was not told of
  for (std::uint32_t k = c.begin; k + 1 < c.end; ++k) {
    const Vec3d d = sub(site_[candidates_[k]].p, p);
    const double d2 = dot(d, d);
    if (d2 < r2) add(candidates_[k], d2);
  }
}

/// The weighted mean of diff `user`'s fits over the samples visit(add) offers, into `a`;
/// returns how much they vouch for it (their weight, at most 1; 0: none, and a = I).
template <class Offer>
double RegionalJacobians::mean_fit(std::size_t user, Mat3d& a, const Offer& offer) const {
  double w_sum = 0;
  Mat3d sum;
  sum.m.fill(0);
  const std::size_t offset = user * site_.size();
  offer([&](std::uint32_t s, double w) {
    if (!ok_[offset + s]) return;
    w_sum += w;
    for (int k = 0; k < 9; ++k) sum.m[k] += w * fitted_[offset + s].m[k];
  });
  if (!(w_sum > 0)) {
    a = kIdentity3;
    return 0.0;
  }
  for (int k = 0; k < 9; ++k) a.m[k] = sum.m[k] / w_sum;
  return std::min(1.0, w_sum);
}

double RegionalJacobians::at(const Reading& reading, std::size_t user, Mat3d& a) const {
  if (!reading.overflow)
    return mean_fit(user, a, [&](const auto& add) {
      for (std::uint32_t j = 0; j < reading.count; ++j) add(reading.site[j], reading.weight[j]);
    });
  // more samples near than a Reading holds: gathered anew for this diff
  const double reach = kReadReach * radius_, r2 = reach * reach;
  return mean_fit(user, a, [&](const auto& add) {
    near(reading.p, reach, [&](std::uint32_t s, double d2) {
      const double f = 1 - d2 / r2;
      add(s, f * f);
    });
  });
}

}  // namespace csculpt::detail
