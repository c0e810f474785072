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

/// Symmetric 3 x 3 (xx, xy, xz, yy, yz, zz) and a general one, in double.
struct Sym3 {
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
};

double determinant(const Sym3& s) {
  return s.xx * (s.yy * s.zz - s.yz * s.yz) - s.xy * (s.xy * s.zz - s.xz * s.yz) +
         s.xz * (s.xy * s.yz - s.xz * s.yy);
}

/// x = S^-1 b for the columns of b (row-major 3 x 3); NaN where S is singular.
Mat3d solve(const Sym3& s, const Mat3d& b) {
  const double c00 = s.yy * s.zz - s.yz * s.yz, c01 = s.xz * s.yz - s.xy * s.zz,
               c02 = s.xy * s.yz - s.xz * s.yy, c11 = s.xx * s.zz - s.xz * s.xz,
               c12 = s.xy * s.xz - s.xx * s.yz, c22 = s.xx * s.yy - s.xy * s.xy;
  const double det = s.xx * c00 + s.xy * c01 + s.xz * c02;
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
  users_ = users;
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
  last_needed_ = ~std::uint64_t{0};
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

/// Marks every sample that a point of p's cell could read (within the read reach of the cell),
/// once per run of points in one cell: neighbouring vertices mostly share a cell.
void RegionalJacobians::need(const Vec3d& p) {
  const Vec3d q = sub(p, origin_);
  const std::int64_t x = axis_cell(q.x), y = axis_cell(q.y), z = axis_cell(q.z);
  const std::uint64_t key = key_of(x, y, z);
  if (key == last_needed_) return;
  last_needed_ = key;
  const double reach = kReadReach * radius_;
  const Vec3d lo =
      add(origin_, Vec3d{static_cast<double>(x) * cell_, static_cast<double>(y) * cell_,
                         static_cast<double>(z) * cell_});
  const Vec3d middle = add(lo, Vec3d{cell_ / 2, cell_ / 2, cell_ / 2});
  // a point within reach of the cell is within reach + half its diagonal of its middle
  near(middle, cell_ * 0.8660254037844386 + reach, [&](std::uint32_t s, double) {
    if (needed_[s]) return;
    const Vec3d d = sub(site_[s].p, lo);
    auto outside = [this](double t) { return t < 0 ? -t : (t > cell_ ? t - cell_ : 0.0); };
    const double dx = outside(d.x), dy = outside(d.y), dz = outside(d.z);
    if (dx * dx + dy * dy + dz * dz >= reach * reach) return;
    needed_[s] = 1;
    needed_list_.push_back(s);
  });
}

/// The affine fit at site s (base normal n there): J = I + G^T with
/// G = (C + l I)^-1 (B + l G0), C the samples' weighted covariance, B their positions'
/// covariance with the displacements, G0 = (sigma - 1) n n^T the flat region's prior.
Mat3d RegionalJacobians::fit_site(std::size_t s, const Vec3d& n) const {
  const Site& c = site_[s];
  const double r2 = radius_ * radius_;
  double w_sum = 0;
  Vec3d pw{}, uw{};
  Sym3 pp;
  Mat3d pu;
  pu.m.fill(0);
  std::size_t count = 0;
  near(c.p, radius_, [&](std::uint32_t k, double d2) {
    const double f = 1 - d2 / r2, w = f * f;
    const Vec3d p = sub(site_[k].p, c.p), u = moved_[k];
    w_sum += w;
    pw = add(pw, scale(p, w));
    uw = add(uw, scale(u, w));
    pp.xx += w * p.x * p.x, pp.xy += w * p.x * p.y, pp.xz += w * p.x * p.z;
    pp.yy += w * p.y * p.y, pp.yz += w * p.y * p.z, pp.zz += w * p.z * p.z;
    const double pv[3] = {p.x, p.y, p.z}, uv[3] = {u.x, u.y, u.z};
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) pu.m[r * 3 + q] += w * pv[r] * uv[q];
    ++count;
  });
  Mat3d none;
  none.m.fill(std::nan(""));
  if (count < 4 || !(w_sum > 0)) return none;
  const Vec3d pm = scale(pw, 1 / w_sum), um = scale(uw, 1 / w_sum);
  Sym3 cov{pp.xx / w_sum - pm.x * pm.x, pp.xy / w_sum - pm.x * pm.y, pp.xz / w_sum - pm.x * pm.z,
           pp.yy / w_sum - pm.y * pm.y, pp.yz / w_sum - pm.y * pm.z, pp.zz / w_sum - pm.z * pm.z};
  const double pmv[3] = {pm.x, pm.y, pm.z}, umv[3] = {um.x, um.y, um.z};
  Mat3d b;
  for (int r = 0; r < 3; ++r)
    for (int q = 0; q < 3; ++q) b.m[r * 3 + q] = pu.m[r * 3 + q] / w_sum - pmv[r] * umv[q];
  const double trace = cov.xx + cov.yy + cov.zz;
  // Samples along a line or at one point cannot fix a Jacobian.
  if (!(trace > 1e-6 * r2)) return none;
  // The ridge acts on the normal direction only, so the tangent columns stay as measured.
  const double l = kRidge * trace;
  cov.xx += l * n.x * n.x, cov.xy += l * n.x * n.y, cov.xz += l * n.x * n.z;
  cov.yy += l * n.y * n.y, cov.yz += l * n.y * n.z, cov.zz += l * n.z * n.z;
  // Samples about a line (a thin part seen edge on) leave a tangent column unfixed.
  if (!(determinant(cov) > kConditioning * trace * trace * trace)) return none;
  auto jacobian = [](const Mat3d& g) {  // I + G^T
    Mat3d a;
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) a.m[r * 3 + q] = (r == q ? 1.0 : 0.0) + g.m[q * 3 + r];
    return a;
  };
  const double sigma = tangent_stretch(jacobian(solve(cov, b)), n);
  const double nv[3] = {n.x, n.y, n.z};
  for (int r = 0; r < 3; ++r)
    for (int q = 0; q < 3; ++q) b.m[r * 3 + q] += l * (sigma - 1) * nv[r] * nv[q];
  return jacobian(solve(cov, b));
}

double RegionalJacobians::at(const Vec3d& p, std::size_t user, Mat3d& a) const {
  const double reach = kReadReach * radius_, r2 = reach * reach;
  double w_sum = 0;
  Mat3d sum;
  sum.m.fill(0);
  const std::size_t offset = user * site_.size();
  near(p, reach, [&](std::uint32_t s, double d2) {
    if (!ok_[offset + s]) return;
    const double f = 1 - d2 / r2, w = f * f;
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

}  // namespace csculpt::detail
