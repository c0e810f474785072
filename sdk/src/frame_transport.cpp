#include "frame_transport.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "fold_repair.h"
#include "fold_test.h"

namespace csculpt::detail {
namespace {

/// A smoothing is read as one, as a grab is (radial_grab.h): an edit that takes at least 40 %
/// off the squared umbrella Laplacian (the neighbours' mean less the vertex) over the vertices
/// it moves removes features there, and acts at the scale of what it removes. The energies
/// below measure its rotations, which turn by tens of degrees where it erases a feature, and
/// read it as the finer edit under a pinch or a small grab inside it; the frame ideal (the
/// Smooth first, then the detail re-applied on what it left) takes it as the coarse edit.
/// Measured over every edit of the Blender sets (edit over base): every Smooth 0.11 - 0.54,
/// every other edit 0.80 (the torus' Cast) or more.
constexpr double kSmoothingRatio = 0.6;
/// The moved vertices a smoothing's ratio is read over, at most (every k-th, in list order).
constexpr std::size_t kSmoothingSamples = 2048;
/// A smoothing carries an overlapping edit that moves at most this fraction of the vertices it
/// moves; between edits of about one reach the energies decide, as between any two edits of
/// one scale. Taking back a stroke smooths too (the surface returns to what it was before the
/// stroke's features), and a rebased undo beside a colleague's grab of about its size (the
/// Python binding's undo test: 331 vertices against 313, 0.95) carried the grab and moved
/// vertices only the undo had moved. Under the Smooths of the Blender sets the details move
/// 0.02 - 0.61 of its vertices (set probe15's wide pinches, 292 against 477 on the shipped
/// Suzanne and 3,051 against 5,007 on the scan); at a bound of 0.4 those wide ones kept about
/// what addition keeps. Every one of them lies wholly inside the Smooth, as does the undo's
/// colleague (the undo's merge sees only the stroke's ring), so containment tells nothing.
constexpr double kSmoothingReach = 0.75;
/// An edit carries every edit whose moved vertices all lie among its own when it moves at
/// least this many times as many, whatever the energies say. The energies weigh each edit's
/// turns against the other's displacement, and a wide edit that turns the surface steeply
/// (broad bumps turning a scan by 10 degrees, varying as fast as a small grab's falloff) read
/// as the finer of the two, carried by the grab inside it (w 0.83): 0.126 against the frame
/// ideal, `sum` 0.114. Carried by the bumps: 0.061. Elsewhere it brought a swirl under bumps
/// on the torus from 0.061 to 0.007 and a pinch under the torus' Cast from 0.051 to 0.007,
/// changed no verdict of any set, and moved the crease test's sessions from 3,794 to 3,801
/// opposed pairs (strokes of one scale rarely lie wholly inside one four times wider).
constexpr double kNestedRatio = 4.0;
/// The listed vertices the mean turns M_ij (frame_transport.h) are read over, about: every
/// k-th in list order beyond this many. A mean needs no more, and a merge as wide as a
/// session's (45,000 vertices) read whole paid a second pass over them.
constexpr std::size_t kMeanTurnSamples = 4096;
/// The blocks of the list the mean turns are summed in, at most (each summed on one thread,
/// the blocks then added in order: the same bits for any thread count).
constexpr std::size_t kMeanTurnBlocks = 64;
constexpr std::uint32_t kNoSeam = 0xffffffffu;
constexpr std::uint8_t kNotCached = 0xff;

/// The spread of the faces' turns around a vertex up to which a diff's rotation there is
/// trusted as a frame, and the spread (a fold between faces) from which it is not at all.
constexpr double kSmoothSpread = 30.0 * 3.14159265358979323846 / 180.0;
constexpr double kFoldSpread = 90.0 * 3.14159265358979323846 / 180.0;
constexpr std::size_t kMaxUsers = 64;
/// How far from the stacked reading of a carried detail the merge may keep it, in multiples
/// of addition's distance from that reading (frame_transport.h, the hedge). Above 1, so that
/// the result is always nearer the frame's reading than addition; below the 1.5 the
/// stacked ideal's rule allows, for the error of the fitted Jacobian.
constexpr double kStackReach = 1.2;

bool has(const std::uint64_t* bits, std::uint32_t v) {
  return (bits[v >> 6] >> (v & 63) & 1) != 0;
}

/// (R - I) v for the rotation of unit quaternion q: v' - v = w t + q.xyz x t, t = 2 q.xyz x v.
Vec3d rotation_change(const Quat& q, const Vec3d& v) {
  const Vec3d u{q.x, q.y, q.z};
  const Vec3d t = scale(cross(u, v), 2.0);
  return add(scale(t, q.w), cross(u, t));
}

bool is_identity(const Quat& q) {
  return q.w == 1.f && q.x == 0.f && q.y == 0.f && q.z == 0.f;
}

/// A vertex's unit area-weighted base normal (zero when it has no faces) and mean edge length.
struct BaseFrame {
  Vec3d normal;
  double edge = 0;
};

/// Everything the per-vertex formula needs about one vertex.
struct VertexState {
  std::array<Vec3d, kMaxUsers> d;
  std::array<double, kMaxUsers> size;
  std::array<Quat, kMaxUsers> rotation;
  std::array<bool, kMaxUsers> moves, turns;
};

class Transport {
 public:
  Transport(const Topology& topology, std::span<const Vec3f> base,
            std::span<const std::uint32_t> vertices, std::span<const TransportInput> users,
            bool same_once, TransportScratch& scratch)
      : topology_(topology),
        base_(base),
        vertices_(vertices),
        users_(users),
        scratch_(scratch),
        n_(users.size()),
        same_once_(same_once) {}

  /// What the regional Jacobians of the diffs with carries[i] need before they are fitted
  /// around the carried vertices (serial work, run beside the carriers' averaging).
  void prepare_jacobians(const JacobianSamples& samples, std::span<const bool> carries);
  void fit_jacobians(std::span<const bool> carries, WorkerPool& pool);

  void find_seams();
  void share_normals();
  void share_agreements();
  /// moved_: how many listed vertices each diff moves.
  void count_moved();
  /// The sums the chunk's vertices add to mean_turn.
  void chunk_mean_turns(std::size_t begin, std::size_t end, double* sums);
  void finish_mean_turns(std::size_t blocks);
  /// The carrying energies of the chunk's vertices, and each one's carrying levels.
  void chunk_energy(std::size_t begin, std::size_t end, double* energy);
  void finish_weights(std::size_t chunks);
  bool smooths(std::size_t i, std::size_t moved) const;
  std::size_t moved_count(std::size_t i) const;
  Vec3d umbrella(std::size_t i, std::uint32_t v, bool edited) const;
  void carry_inside();
  bool contains(std::size_t i, std::size_t j) const;
  bool overlaps(std::size_t i, std::size_t j) const;
  void carry_wholly(std::size_t i, std::size_t j);
  void carry_nested();
  void carry_inside_smoothings();
  void cache_face_turns(std::span<const bool> carries, WorkerPool& pool, std::size_t grain);
  /// The merged position of the listed vertex `at`; `s` is scratch (its arrays are sized for
  /// the most users, so it is made once per chunk, not per vertex).
  Vec3f merged(std::size_t at, VertexState& s) const;

 private:
  void plan_levels(std::size_t at, const VertexState& s);
  bool may_carry(const VertexState& s) const;
  bool may_carry_by_bits(std::size_t at) const;
  void load_turns(std::size_t at, VertexState& s) const;
  void load_displacements(std::size_t at, VertexState& s) const;
  void ring_stretches(std::size_t at, const VertexState& s, const Vec3d& n, double* k) const;
  std::size_t sole_mover(std::size_t at) const;
  Vec3f lone_edit(std::size_t at, std::size_t i) const;
  Vec3f transported(std::size_t at, const VertexState& s) const;
  std::uint32_t group_coincident();
  void share_rotations(std::uint32_t groups);
  Quat rotation(std::size_t at, std::size_t i) const;
  Vec3d face_cross(std::uint32_t f) const;
  BaseFrame base_frame(std::uint32_t v) const;
  Vec3d base_normal(std::uint32_t v) const;
  Quat carrier(std::size_t at, std::size_t i, double level) const;
  Vec3d edited_position(std::size_t i, std::uint32_t v) const;
  double faces_agree(std::uint32_t v, std::size_t i) const;
  Vec4d turn_of_face(std::uint32_t f, std::size_t i) const;
  Vec4d face_turn(std::uint32_t f, std::size_t i) const;
  bool carried_vertex(std::uint32_t v) const;
  template <class Visit>
  void for_owned_faces(std::size_t begin, std::size_t end, Visit&& visit) const;
  double agreement(std::size_t at, std::size_t i) const;

  const Topology& topology_;
  std::span<const Vec3f> base_;
  std::span<const std::uint32_t> vertices_;
  std::span<const TransportInput> users_;
  TransportScratch& scratch_;
  std::size_t n_;
  bool same_once_;         ///< false: s = 0 (SameChange::add)
  bool hedged_ = false;    ///< carried details are hedged toward their stacked reading
  bool regional_ = false;  ///< the regional Jacobians are fitted
  /// Per diff: its column of face_turns, or kNotCached; carriers_ columns in all.
  std::array<std::uint8_t, kMaxUsers> cached_{};
  std::size_t carriers_ = 0;
  std::array<std::size_t, kMaxUsers> moved_{};  ///< per diff: the listed vertices it moves
  /// Every how many listed vertices one is read for the mean turns (kMeanTurnSamples).
  std::size_t mean_stride_ = 1;
  void fit_grabs(std::span<const bool> carries);
  double same(const VertexState& s, std::size_t i, std::size_t j) const;
};

std::uint64_t position_hash(const Vec3f& p) {
  std::uint32_t b[3];
  const float c[3] = {p.x + 0.f, p.y + 0.f, p.z + 0.f};  // -0 and +0 are one position
  std::memcpy(b, c, sizeof(b));
  std::uint64_t h = 0x9e3779b97f4a7c15ull;
  for (std::uint32_t x : b) h = (h ^ x) * 0xff51afd7ed558ccdull, h ^= h >> 29;
  return h;
}

/// Groups the listed vertices on an open rim that sit at the same base position (split
/// seams), and gives every member of a group, per diff, the normalised sum of the members'
/// rotations. Only a rim can open a crack: coincident vertices of closed parts that drift
/// apart leave both surfaces whole. A closed mesh has no rim, and then nothing is hashed.
void Transport::find_seams() {
  share_rotations(group_coincident());
}

/// seam_of: per listed vertex, its group of coincident rim vertices (kNoSeam when alone or
/// off the border), groups numbered in list order; returns how many groups there are.
std::uint32_t Transport::group_coincident() {
  const std::size_t count = vertices_.size();
  auto& seam_of = scratch_.seam_of;
  seam_of.assign(count, kNoSeam);
  std::size_t rim = 0;
  for (const std::uint32_t v : vertices_) rim += topology_.border[v];
  if (rim < 2) return 0;
  std::uint32_t groups = 0;
  std::size_t size = 64;
  while (size < 2 * rim) size *= 2;
  auto& table = scratch_.table;
  table.assign(size, 0);
  for (std::size_t at = 0; at < count; ++at) {
    if (topology_.border[vertices_[at]] == 0) continue;
    const Vec3f& p = base_[vertices_[at]];
    for (std::size_t h = position_hash(p) & (size - 1);; h = (h + 1) & (size - 1)) {
      if (table[h] == 0) {
        table[h] = static_cast<std::uint32_t>(at + 1);
        break;
      }
      const std::size_t other = table[h] - 1;
      const Vec3f& q = base_[vertices_[other]];
      if (!(q.x == p.x && q.y == p.y && q.z == p.z)) continue;
      if (seam_of[other] == kNoSeam) seam_of[other] = groups++;
      seam_of[at] = seam_of[other];
      break;
    }
  }
  return groups;
}

void Transport::share_rotations(std::uint32_t groups) {
  const std::size_t count = vertices_.size();
  const auto& seam_of = scratch_.seam_of;
  auto& shared = scratch_.seam_rotation;
  shared.assign(std::size_t{groups} * n_, Quat{0, 0, 0, 0});
  for (std::size_t at = 0; at < count; ++at) {
    if (seam_of[at] == kNoSeam) continue;
    for (std::size_t i = 0; i < n_; ++i) {
      const std::uint32_t v = vertices_[at];
      const Quat q = has(users_[i].rotated, v) ? users_[i].isometry[v].real : Quat{};
      Quat& sum = shared[seam_of[at] * n_ + i];
      sum = sum + (dot(sum, q) < 0 ? -1.f * q : q);
    }
  }
  for (Quat& q : shared) {
    const float n2 = dot(q, q);
    q = n2 > 1e-30f ? (1.f / std::sqrt(n2)) * q : Quat{};
  }
}

/// The part of q that turns the unit vector n (q = swing * twist, twist about n): a detail
/// follows the turn of the surface's normal, not a spin of the surface about it.
Quat swing(const Quat& q, const Vec3d& n) {
  if (is_identity(q)) return q;
  const double p = q.x * n.x + q.y * n.y + q.z * n.z;
  const double tw = q.w, tx = p * n.x, ty = p * n.y, tz = p * n.z;
  const double len = std::sqrt(tw * tw + tx * tx + ty * ty + tz * tz);
  if (!(len > 1e-12)) return q;
  const Quat twist{static_cast<float>(tw / len), static_cast<float>(tx / len),
                   static_cast<float>(ty / len), static_cast<float>(tz / len)};
  return q * conjugate(twist);
}

Quat Transport::rotation(std::size_t at, std::size_t i) const {
  const std::uint32_t group = scratch_.seam_of[at];
  if (group != kNoSeam) return scratch_.seam_rotation[group * n_ + i];
  const std::uint32_t v = vertices_[at];
  return has(users_[i].rotated, v) ? users_[i].isometry[v].real : Quat{};
}

/// Base face f's area vector, doubled: its normal times twice its area.
Vec3d Transport::face_cross(std::uint32_t f) const {
  const Triangle& t = topology_.triangles[f];
  const Vec3d p0 = widen(base_[t[0]]);
  return cross(sub(widen(base_[t[1]]), p0), sub(widen(base_[t[2]]), p0));
}

/// v's base normal, and its mean edge length from the area of its base faces (equilateral
/// triangles of that area; 0 when it has none): one pass over its faces for both.
BaseFrame Transport::base_frame(std::uint32_t v) const {
  Vec3d sum{};
  double area = 0;
  std::size_t faces = 0;
  for (std::uint32_t f : topology_.vertex_faces.row(v)) {
    const Vec3d c = face_cross(f);
    sum = add(sum, c);
    area += length(c) / 2;
    ++faces;
  }
  if (faces == 0) return {};
  const double len = length(sum);
  return {len > 0 ? scale(sum, 1.0 / len) : Vec3d{},
          std::sqrt(4 / std::sqrt(3.0) * area / static_cast<double>(faces))};
}

/// The carrying level a displacement of `size` reads where edges are `edge` long: log2 of
/// the edges it spans, 0 up to one edge, at most the last level (continuous in the size).
double carrying_level(double size, double edge) {
  const double span = edge > 0 ? size / edge : 0.0;
  return span > 1 ? std::min(std::log2(span), static_cast<double>(kCarryLevels - 1)) : 0.0;
}

/// The levels the listed vertex's displacements read (the two around each one's level), so
/// that only those are averaged there; its edge length is in scratch_.edge.
void Transport::plan_levels(std::size_t at, const VertexState& s) {
  const std::uint32_t v = vertices_[at];
  std::uint8_t bits = 0;
  for (std::size_t j = 0; j < n_; ++j) {
    if (!s.moves[j]) continue;
    const double level = carrying_level(s.size[j], scratch_.edge[at]);
    const auto below = static_cast<std::uint32_t>(level);
    bits |= static_cast<std::uint8_t>(1u << below);
    if (level > below) bits |= static_cast<std::uint8_t>(1u << (below + 1));
  }
  scratch_.reads_level[v] = bits;
}

/// Diff i's rotation at the listed vertex `at` read at carrying `level`: the vertex's own at
/// level 0, then the hierarchy's averages, interpolated between levels so that it changes
/// continuously with the level. Split seams keep their shared rotation.
Quat Transport::carrier(std::size_t at, std::size_t i, double level) const {
  if (!(level > 0) || scratch_.seam_of[at] != kNoSeam || !users_[i].smoothed[1])
    return rotation(at, i);
  const std::uint32_t v = vertices_[at];
  const auto below = static_cast<std::size_t>(level);
  const double f = level - static_cast<double>(below);
  const Quat a = below == 0 ? rotation(at, i) : users_[i].smoothed[below][v];
  if (!(f > 0)) return a;
  Quat b = users_[i].smoothed[below + 1][v];
  if (dot(a, b) < 0) b = -1.f * b;
  const double w = a.w + f * (b.w - a.w), x = a.x + f * (b.x - a.x), y = a.y + f * (b.y - a.y),
               z = a.z + f * (b.z - a.z);
  const double len = std::sqrt(w * w + x * x + y * y + z * z);
  if (!(len > 0)) return a;
  return {static_cast<float>(w / len), static_cast<float>(x / len), static_cast<float>(y / len),
          static_cast<float>(z / len)};
}

Vec3d Transport::base_normal(std::uint32_t v) const {
  return base_frame(v).normal;
}

/// Coincident vertices (split seams) share one normal, the normalised sum of theirs, as
/// they share one rotation.
void Transport::share_normals() {
  const auto& seam_of = scratch_.seam_of;
  auto& shared = scratch_.seam_normal;
  shared.assign(scratch_.seam_rotation.size() / std::max<std::size_t>(n_, 1), Vec3d{});
  for (std::size_t at = 0; at < vertices_.size(); ++at)
    if (seam_of[at] != kNoSeam)
      shared[seam_of[at]] = add(shared[seam_of[at]], base_normal(vertices_[at]));
  for (Vec3d& n : shared) {
    const double len = length(n);
    n = len > 0 ? scale(n, 1.0 / len) : Vec3d{};
  }
}

Vec3d Transport::edited_position(std::size_t i, std::uint32_t v) const {
  const TransportInput& u = users_[i];
  if (!has(u.changed, v)) return widen(base_[v]);
  const float* e = u.edited + 3 * std::size_t{u.slot[v]};
  return widen(Vec3f{e[0], e[1], e[2]});
}

/// The turn taking the direction of a to that of b (both non-zero), as a unit quaternion: (|a|
/// |b| + a.b, a x b) normalised, which needs neither vector normalised; for opposite
/// directions, a half turn about an axis perpendicular to a.
Vec4d turn_between(const Vec3d& a, const Vec3d& b) {
  const double ab = std::sqrt(norm2(a) * norm2(b));
  Vec3d axis = cross(a, b);
  double w = ab + dot(a, b);
  if (!(w > 1e-12 * ab)) {  // opposite: any perpendicular axis
    axis = std::fabs(a.x) < 0.9 * length(a) ? cross(a, Vec3d{1, 0, 0}) : cross(a, Vec3d{0, 1, 0});
    w = 0;
  }
  const double inverse = 1 / std::sqrt(w * w + norm2(axis));
  return {w * inverse, axis.x * inverse, axis.y * inverse, axis.z * inverse};
}

/// How well the faces around v agree on how diff i turns the surface: 1 where they turn
/// alike (a bend, a twist, a grab's or a cast's smooth falloff, however far they turn),
/// falling to 0 where they turn apart by a fold (a thin part crushed by a grab, a face
/// flipped beside faces that are not). Measured by the length of the mean of the faces'
/// turns as unit quaternions: 1 when all are one turn, cos(s/2) for turns s apart.
double Transport::faces_agree(std::uint32_t v, std::size_t i) const {
  Vec4d sum{}, first{};
  std::size_t faces = 0;
  for (std::uint32_t f : topology_.vertex_faces.row(v)) {
    Vec4d q = face_turn(f, i);
    if (q.w == 0 && q.x == 0 && q.y == 0 && q.z == 0) continue;  // a degenerate face
    if (faces == 0) first = q;
    if (q.w * first.w + q.x * first.x + q.y * first.y + q.z * first.z < 0)
      q = {-q.w, -q.x, -q.y, -q.z};
    sum = {sum.w + q.w, sum.x + q.x, sum.y + q.y, sum.z + q.z};
    ++faces;
  }
  if (faces == 0) return 1.0;
  const double mean = std::sqrt(sum.w * sum.w + sum.x * sum.x + sum.y * sum.y + sum.z * sum.z) /
                      static_cast<double>(faces);
  // Full trust while the faces' turns spread over up to 30 degrees, none from 90 (a fold).
  const double lo = std::cos(kFoldSpread / 2), hi = std::cos(kSmoothSpread / 2);
  const double x = std::clamp((mean - lo) / (hi - lo), 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

/// How diff i turns base face f, as a unit quaternion; zero for a face degenerate before or
/// after (it says nothing of the turn).
Vec4d Transport::turn_of_face(std::uint32_t f, std::size_t i) const {
  const Triangle& t = topology_.triangles[f];
  const Vec3d a = face_cross(f);
  const Vec3d p0 = edited_position(i, t[0]);
  const Vec3d b = cross(sub(edited_position(i, t[1]), p0), sub(edited_position(i, t[2]), p0));
  if (!(norm2(a) > 0) || !(norm2(b) > 0)) return {};
  return turn_between(a, b);
}

/// turn_of_face(), from the rows cache_face_turns() filled where it did.
Vec4d Transport::face_turn(std::uint32_t f, std::size_t i) const {
  const std::uint32_t row = f < scratch_.face_row.size() ? scratch_.face_row[f] : kNoRow;
  if (row != kNoRow && cached_[i] != kNotCached)
    return scratch_.face_turns[row * carriers_ + cached_[i]];
  return turn_of_face(f, i);
}

/// Whether v is carried (its levels planned: every carried vertex reads some level).
bool Transport::carried_vertex(std::uint32_t v) const {
  return scratch_.reads_level[v] != 0;
}

/// The faces around the carried vertices listed from `begin` to `end`, each from its lowest
/// carried vertex only; `visit(f)` for each.
template <class Visit>
void Transport::for_owned_faces(std::size_t begin, std::size_t end, Visit&& visit) const {
  auto carried = [this](std::uint32_t u) { return carried_vertex(u); };
  for (std::size_t at = begin; at < end; ++at) {
    if (!scratch_.carried_here[at]) continue;
    const std::uint32_t v = vertices_[at];
    for (std::uint32_t f : topology_.vertex_faces.row(v))
      if (lowest_listed(topology_.triangles[f], v, carried)) visit(f);
  }
}

/// Every carrier's turn of each face around the carried vertices, once per face: the
/// agreement of each of its three vertices reads it. Rows are numbered in chunk order.
void Transport::cache_face_turns(std::span<const bool> carries, WorkerPool& pool,
                                 std::size_t grain) {
  carriers_ = 0;
  for (std::size_t i = 0; i < n_; ++i)
    cached_[i] = carries[i] ? static_cast<std::uint8_t>(carriers_++) : kNotCached;
  const std::size_t chunks = (vertices_.size() + grain - 1) / grain;
  auto& first_row = scratch_.chunk_first_row;
  first_row.assign(chunks + 1, 0);
  pool.for_chunks(vertices_.size(), grain, [&](std::size_t begin, std::size_t end) {
    std::uint32_t rows = 0;
    for_owned_faces(begin, end, [&](std::uint32_t) { ++rows; });
    first_row[begin / grain + 1] = rows;
  });
  for (std::size_t c = 0; c < chunks; ++c) first_row[c + 1] += first_row[c];
  if (scratch_.face_row.size() < topology_.triangles.size())
    scratch_.face_row.resize(topology_.triangles.size(), kNoRow);
  scratch_.row_face.resize(first_row[chunks]);
  scratch_.face_turns.resize(first_row[chunks] * carriers_);
  pool.for_chunks(vertices_.size(), grain, [&](std::size_t begin, std::size_t end) {
    std::uint32_t row = first_row[begin / grain];
    for_owned_faces(begin, end, [&](std::uint32_t f) {
      scratch_.face_row[f] = row;
      scratch_.row_face[row] = f;
      for (std::size_t i = 0; i < n_; ++i)
        if (cached_[i] != kNotCached)
          scratch_.face_turns[row * carriers_ + cached_[i]] = turn_of_face(f, i);
      ++row;
    });
  });
}

/// Coincident vertices (split seams) take the least agreement of their members, per diff, so
/// that they are carried alike and the seam stays closed.
void Transport::share_agreements() {
  const auto& seam_of = scratch_.seam_of;
  auto& shared = scratch_.seam_agreement;
  shared.assign(scratch_.seam_rotation.size(), 1.0);
  for (std::size_t at = 0; at < vertices_.size(); ++at) {
    if (seam_of[at] == kNoSeam) continue;
    for (std::size_t i = 0; i < n_; ++i) {
      double& a = shared[seam_of[at] * n_ + i];
      a = std::min(a, faces_agree(vertices_[at], i));
    }
  }
}

double Transport::agreement(std::size_t at, std::size_t i) const {
  const std::uint32_t group = scratch_.seam_of[at];
  return group != kNoSeam ? scratch_.seam_agreement[group * n_ + i] : faces_agree(vertices_[at], i);
}

/// The displacements at the listed vertex `at` (no rotations).
void Transport::load_displacements(std::size_t at, VertexState& s) const {
  const std::uint32_t v = vertices_[at];
  const Vec3f& b = base_[v];
  for (std::size_t i = 0; i < n_; ++i) {
    const TransportInput& u = users_[i];
    s.moves[i] = has(u.changed, v);
    if (s.moves[i]) {
      const float* e = u.edited + 3 * std::size_t{u.slot[v]};
      s.d[i] = sub(widen(Vec3f{e[0], e[1], e[2]}), widen(b));
    } else {
      s.d[i] = {};
    }
    s.size[i] = length(s.d[i]);
  }
}

/// Which diffs move the listed vertex `at` and their rotations there (no displacements).
void Transport::load_turns(std::size_t at, VertexState& s) const {
  const std::uint32_t v = vertices_[at];
  for (std::size_t i = 0; i < n_; ++i) {
    s.moves[i] = has(users_[i].changed, v);
    s.rotation[i] = rotation(at, i);
    s.turns[i] = !is_identity(s.rotation[i]);
  }
}

/// Whether some diff turns the surface under another diff's displacement, from how many
/// diffs move the vertex, how many turn it and how many do both.
bool carries_between(std::size_t movers, std::size_t turners, std::size_t both) {
  // some i != j with turns[i] and moves[j]: unless the only turner is the only mover
  return turners > 0 && movers > 0 && !(turners == 1 && movers == 1 && both == 1);
}

/// Whether some diff turns the surface at the vertex under another diff's displacement:
/// elsewhere nothing is carried (every T_j is the identity), so the vertex needs no energy,
/// no carrying level and no frame.
bool Transport::may_carry(const VertexState& s) const {
  std::size_t movers = 0, turners = 0, both = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    movers += s.moves[i];
    turners += s.turns[i];
    both += s.moves[i] && s.turns[i];
  }
  return carries_between(movers, turners, both);
}

/// may_carry() from the diffs' bits alone, before their rotations are read: a diff with no
/// rotation at the vertex does not turn it, one with a rotation may still not, so a vertex
/// this rules out may_carry() rules out too (most of them: one diff edits them alone). A
/// split seam's rotation is its group's, not its own: it is left to may_carry().
bool Transport::may_carry_by_bits(std::size_t at) const {
  if (scratch_.seam_of[at] != kNoSeam) return true;
  const std::uint32_t v = vertices_[at];
  std::size_t movers = 0, turners = 0, both = 0;
  for (std::size_t i = 0; i < n_; ++i) {
    const bool moves = has(users_[i].changed, v), turns = has(users_[i].rotated, v);
    movers += moves;
    turners += turns;
    both += moves && turns;
  }
  return carries_between(movers, turners, both);
}

/// Adds the `chunks` runs of `width` sums in `sums` into the first, in chunk order: the same
/// bits whichever threads summed the chunks.
void add_chunks_in_order(std::vector<double>& sums, std::size_t chunks, std::size_t width) {
  for (std::size_t c = 1; c < chunks; ++c)
    for (std::size_t k = 0; k < width; ++k) sums[k] += sums[c * width + k];
}

void Transport::count_moved() {
  for (std::size_t i = 0; i < n_; ++i) moved_[i] = moved_count(i);
  mean_stride_ = std::max<std::size_t>(1, vertices_.size() / kMeanTurnSamples);
}

/// How much of diff i's ring stretching counts against it carrying diff j: all of it where j
/// moves at least as many vertices as i, else the share j's reach is of i's. A pinch stretches
/// the rings of its own small support, which marks it as the finer edit; a smoothing of a
/// whole figure stretches rings all over its reach, and counted whole under a swirl a quarter
/// its size, that stretching would make the smoothing the finer edit and the swirl its frame.
double stretch_reach(std::size_t moved_i, std::size_t moved_j) {
  return moved_j >= moved_i ? 1.0 : static_cast<double>(moved_j) / static_cast<double>(moved_i);
}

/// Sums, for each pair (i, j), of diff i's turns weighted by the length of diff j's
/// displacement, over the chunk's vertices whose energy E_ij reads them, every
/// mean_stride_-th in list order (four doubles per pair: a quaternion, each aligned to w >= 0).
void Transport::chunk_mean_turns(std::size_t begin, std::size_t end, double* sums) {
  std::fill(sums, sums + 4 * n_ * n_, 0.0);
  VertexState s;
  for (std::size_t at = begin + (mean_stride_ - begin % mean_stride_) % mean_stride_; at < end;
       at += mean_stride_) {
    if (!may_carry_by_bits(at)) continue;
    load_turns(at, s);
    if (!may_carry(s)) continue;
    load_displacements(at, s);
    for (std::size_t i = 0; i < n_; ++i) {
      if (!s.turns[i] && !s.moves[i]) continue;  // as chunk_energy reads them
      const Quat& q = s.rotation[i];
      const double sign = q.w < 0 ? -1.0 : 1.0;
      for (std::size_t j = 0; j < n_; ++j) {
        if (j == i || !s.moves[j]) continue;
        double* sum = sums + 4 * (i * n_ + j);
        const double weight = sign * s.size[j];
        sum[0] += weight * q.w, sum[1] += weight * q.x, sum[2] += weight * q.y,
            sum[3] += weight * q.z;
      }
    }
  }
}

/// mean_turn: the blocks' sums, added in block order, normalised; the identity for a pair
/// with none.
void Transport::finish_mean_turns(std::size_t blocks) {
  std::vector<double>& sums = scratch_.chunk_turns;
  const std::size_t pairs = n_ * n_;
  add_chunks_in_order(sums, blocks, 4 * pairs);
  scratch_.mean_turn.assign(pairs, Quat{});
  for (std::size_t k = 0; k < pairs; ++k) {
    const double* q = sums.data() + 4 * k;
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (len > 0)
      scratch_.mean_turn[k] = {static_cast<float>(q[0] / len), static_cast<float>(q[1] / len),
                               static_cast<float>(q[2] / len), static_cast<float>(q[3] / len)};
  }
}

void Transport::chunk_energy(std::size_t begin, std::size_t end, double* energy) {
  std::fill(energy, energy + n_ * n_, 0.0);
  std::array<double, kMaxUsers * kMaxUsers> reach;
  for (std::size_t i = 0; i < n_; ++i)
    for (std::size_t j = 0; j < n_; ++j) reach[i * n_ + j] = stretch_reach(moved_[i], moved_[j]);
  const std::vector<Quat>& mean_turn = scratch_.mean_turn;
  VertexState s;
  for (std::size_t at = begin; at < end; ++at) {
    scratch_.carried_here[at] = 0;
    if (!may_carry_by_bits(at)) continue;
    load_turns(at, s);
    scratch_.carried_here[at] = may_carry(s);
    if (!scratch_.carried_here[at]) continue;  // its energy terms are zero, its levels unread
    load_displacements(at, s);
    const BaseFrame frame = base_frame(vertices_[at]);
    scratch_.edge[at] = frame.edge;
    plan_levels(at, s);
    // Coincident vertices (split seams) share one normal, as they share one rotation.
    const std::uint32_t group = scratch_.seam_of[at];
    const Vec3d n = scratch_.normal[at] =
        group != kNoSeam ? scratch_.seam_normal[group] : frame.normal;
    std::array<double, kMaxUsers> k;
    ring_stretches(at, s, n, k.data());
    for (std::size_t i = 0; i < n_; ++i) {
      if (!s.turns[i] && !s.moves[i]) continue;
      for (std::size_t j = 0; j < n_; ++j)
        if (j != i && s.moves[j])
          energy[i * n_ + j] += std::sqrt(
              norm2(rotation_change(s.rotation[i] * conjugate(mean_turn[i * n_ + j]), s.d[j])) +
              reach[i * n_ + j] * k[i] * norm2(s.d[j]));
    }
  }
}

/// The share of displacement d that lies in the tangent plane of unit normal n, in [0, 1]; a
/// vertex that hardly moves counts as sideways (a pinch's centre stays put while its ring
/// closes in), continuously, on the scale of its edges' length `edge`.
double sideways(const Vec3d& d, const Vec3d& n, double edge) {
  const double along = dot(d, n);
  const double all = norm2(d) + 1e-4 * edge * edge;
  return (all - along * along) / all;
}

/// An edge's change of length, from its ratio r of lengths after to before, relative to the
/// mean of the two lengths: r - 1 for small changes, but bounded by 2. A smoothing spikes a few
/// vertices of a fine patch (Blender's Laplacian smooth at factor 0.1 sent two vertices of the
/// human figure's head about twelve edges out); unbounded, the few edges around them made
/// nearly all of the smoothing's stretch over the head.
double relative_change(double r) {
  return 2 * (r - 1) / (r + 1);
}

/// How much each diff stretches the one ring of the listed vertex `at` (base normal n), into
/// k[i] for the diffs that move or turn there (one pass over the ring for all): twice the
/// mean squared relative change of its edges' lengths (a stretch by s along one direction gives
/// about (s - 1)^2, its share of |F - I|^2 for F the deformation gradient). A detail that moves
/// the surface sideways (a pinch, a small grab) hardly turns it but squeezes and shears it; by
/// its turn alone it passed for the coarser edit under a Cast, a taper or a twist.
///
/// The ring's even change (its mean) counts only as far as the vertex moves sideways: a lift
/// h along the normals of a surface of radius r grows every ring by h / r, the curvature's
/// doing and not a fine edit (read as one, a Wave over a head passed for finer than a swirl in
/// it). A lift's fineness is in its slope, which its turns measure. A pinch, which moves the
/// vertex sideways, keeps its even squeeze. A rigid motion changes no length, so whatever its
/// direction it adds nothing.
void Transport::ring_stretches(std::size_t at, const VertexState& s, const Vec3d& n,
                               double* k) const {
  const std::uint32_t v = vertices_[at];
  const Vec3d b = widen(base_[v]);
  std::array<Vec3d, kMaxUsers> e;
  std::array<double, kMaxUsers> sum, squares;
  for (std::size_t i = 0; i < n_; ++i) {
    e[i] = add(b, s.d[i]);
    sum[i] = squares[i] = 0;
  }
  std::size_t edges = 0;
  for (const std::uint32_t u : topology_.vertex_vertices.row(v)) {
    const double before = norm2(sub(widen(base_[u]), b));
    if (!(before > 0)) continue;  // a collapsed edge says nothing
    const double inverse = 1 / before;
    for (std::size_t i = 0; i < n_; ++i) {
      if (!s.turns[i] && !s.moves[i]) continue;
      const double change =
          relative_change(std::sqrt(norm2(sub(edited_position(i, u), e[i])) * inverse));
      sum[i] += change;
      squares[i] += change * change;
    }
    ++edges;
  }
  for (std::size_t i = 0; i < n_; ++i) {
    k[i] = 0;
    if (edges == 0 || (!s.turns[i] && !s.moves[i])) continue;
    const double mean = sum[i] / static_cast<double>(edges);
    const double uneven = std::max(0.0, squares[i] / static_cast<double>(edges) - mean * mean);
    k[i] = 2 * (uneven + sideways(s.d[i], n, scratch_.edge[at]) * mean * mean);
  }
}

/// Diff i's umbrella Laplacian (the neighbours' mean less the vertex) at v, on the base
/// (`edited` false) or on diff i's edit.
Vec3d Transport::umbrella(std::size_t i, std::uint32_t v, bool edited) const {
  auto at = [&](std::uint32_t u) { return edited ? edited_position(i, u) : widen(base_[u]); };
  Vec3d mean{};
  std::size_t k = 0;
  for (const std::uint32_t u : topology_.vertex_vertices.row(v)) {
    mean = add(mean, at(u));
    ++k;
  }
  return k == 0 ? Vec3d{} : sub(scale(mean, 1.0 / static_cast<double>(k)), at(v));
}

std::size_t Transport::moved_count(std::size_t i) const {
  std::size_t moved = 0;
  for (const std::uint32_t v : vertices_) moved += has(users_[i].changed, v);
  return moved;
}

/// Whether diff i smooths what it moves: over (a sample of at most kSmoothingSamples of) the
/// `moved` vertices it moves, the squared umbrella Laplacian of its edit falls under
/// kSmoothingRatio of the base's.
bool Transport::smooths(std::size_t i, std::size_t moved) const {
  const std::size_t stride = std::max<std::size_t>(1, moved / kSmoothingSamples);
  std::size_t seen = 0;
  double before = 0, after = 0;
  for (const std::uint32_t v : vertices_) {
    if (!has(users_[i].changed, v) || seen++ % stride != 0) continue;
    before += norm2(umbrella(i, v, false));
    after += norm2(umbrella(i, v, true));
  }
  return before > 0 && after < kSmoothingRatio * before;
}

/// Where one edit lies inside a much wider one, or inside a smoothing, the outer one carries it
/// (w = 1, and 0 back), whatever the energies say: see kNestedRatio and kSmoothingRatio.
void Transport::carry_inside() {
  carry_nested();
  carry_inside_smoothings();
}

/// Whether every vertex diff j moves, diff i moves too.
bool Transport::contains(std::size_t i, std::size_t j) const {
  for (const std::uint32_t v : vertices_)
    if (has(users_[j].changed, v) && !has(users_[i].changed, v)) return false;
  return true;
}

/// Whether diffs i and j (i != j) meet: either's rotations would move the other's
/// displacements somewhere (a carrying energy either way).
bool Transport::overlaps(std::size_t i, std::size_t j) const {
  const std::vector<double>& e = scratch_.chunk_energy;
  return j != i && (e[i * n_ + j] > 0 || e[j * n_ + i] > 0);
}

/// Diff i carries diff j wholly, and j carries nothing of i.
void Transport::carry_wholly(std::size_t i, std::size_t j) {
  scratch_.weight[i * n_ + j] = 1.0;
  scratch_.weight[j * n_ + i] = 0.0;
}

/// Each edit carries the overlapping edits that lie wholly inside it and move at most
/// 1 / kNestedRatio of the vertices it moves.
void Transport::carry_nested() {
  const std::array<std::size_t, kMaxUsers>& moved = moved_;
  for (std::size_t i = 0; i < n_; ++i)
    for (std::size_t j = 0; j < n_; ++j) {
      const bool small =
          static_cast<double>(moved[j]) * kNestedRatio <= static_cast<double>(moved[i]);
      if (overlaps(i, j) && small && contains(i, j)) carry_wholly(i, j);
    }
}

/// A smoothing carries every edit it overlaps that moves at most kSmoothingReach of the
/// vertices it moves.
void Transport::carry_inside_smoothings() {
  const std::array<std::size_t, kMaxUsers>& moved = moved_;
  auto inside = [&](std::size_t i, std::size_t j) {
    return overlaps(i, j) &&
           static_cast<double>(moved[j]) <= kSmoothingReach * static_cast<double>(moved[i]);
  };
  for (std::size_t i = 0; i < n_; ++i) {
    bool carries = false;  // the Laplacians are read only where there is something to carry
    for (std::size_t j = 0; j < n_ && !carries; ++j) carries = inside(i, j);
    if (!carries || !smooths(i, moved[i])) continue;
    for (std::size_t j = 0; j < n_; ++j)
      if (inside(i, j)) carry_wholly(i, j);
  }
}

/// a_ij from E_ij and E_ji (frame_transport.h): to the fourth power, so that the finer
/// edit's share falls as the fourth power of the scale ratio; 1/2 where neither changes the
/// other. As ratios, so that the powers of small sums neither underflow nor overflow.
double carrying_share(double ij, double ji) {
  if (!(ij > 0)) return ji > 0 ? 1.0 : 0.5;
  if (!(ji > 0)) return 0.0;
  const double r = ij <= ji ? ij / ji : ji / ij;  // in (0, 1]
  const double r4 = (r * r) * (r * r);
  return ij <= ji ? 1 / (1 + r4) : r4 / (1 + r4);
}

void Transport::finish_weights(std::size_t chunks) {
  auto& w = scratch_.weight;
  w.assign(n_ * n_, 0.0);
  std::vector<double>& e = scratch_.chunk_energy;
  add_chunks_in_order(e, chunks, n_ * n_);
  for (std::size_t i = 0; i < n_; ++i)
    for (std::size_t j = 0; j < n_; ++j) {
      if (i == j) continue;
      const double share = carrying_share(e[i * n_ + j], e[j * n_ + i]);
      // Only a coarser edit is a frame: two edits of one scale (a grab beside a twist, the
      // strokes a session merges and rebases every sync) add, each at full share of neither.
      // Carried halfway through each other's steep rotations they creased where they met.
      w[i * n_ + j] = std::max(0.0, 2.0 * share - 1.0);
    }
  carry_inside();
}

/// How close two displacements must be, relative to the smaller, to count partly as one.
/// Identical edits are one intent (the same edit merged twice, what two branches of a
/// session share); two artists pushing the same way by similar amounts are two. Wherever a
/// sameness band lies, the merged displacement dips there, so it is kept to float rounding:
/// two inflates along one normal whose heights cross would otherwise groove the surface along
/// the band where they are close (sessions rebase such overlaps every sync).
constexpr double kSameTolerance = 0.001;

/// s_ij: 1 for the same displacement, 0 for unrelated ones (or either zero). Measured against
/// the smaller of the two: a small detail moving the same way as a large edit around it is
/// not a copy of it (against the larger, a 0.02 grab inside a 0.05 swirl counted 8 % as one).
double sameness(const VertexState& s, std::size_t i, std::size_t j) {
  const double m = kSameTolerance * std::min(s.size[i], s.size[j]);
  if (!(m > 0)) return 0;
  const double r = std::max(0.0, 1.0 - length(sub(s.d[i], s.d[j])) / m);
  return r * r;
}

double Transport::same(const VertexState& s, std::size_t i, std::size_t j) const {
  return same_once_ ? sameness(s, i, j) : 0.0;
}

/// The diff that alone moves the listed vertex `at`; n_ when several do.
std::size_t Transport::sole_mover(std::size_t at) const {
  const std::uint32_t v = vertices_[at];
  std::size_t mover = n_;
  for (std::size_t i = 0; i < n_; ++i) {
    if (!has(users_[i].changed, v)) continue;
    if (mover != n_) return n_;
    mover = i;
  }
  return mover;
}

Vec3f Transport::merged(std::size_t at, VertexState& s) const {
  scratch_.sole[at] = kNoSoleEdit;
  if (scratch_.carried_here[at] != 0) {
    load_turns(at, s);
    load_displacements(at, s);
  } else if (const std::size_t i = sole_mover(at); i < n_) {
    return lone_edit(at, i);
  } else {  // no carrier: the displacements add (identical intents counted once)
    load_displacements(at, s);
    std::fill_n(s.turns.begin(), n_, false);
  }
  return transported(at, s);
}

/// Diff i's edit of the listed vertex `at`, which it alone moves: b + (e - b) in double, bit
/// for bit what transported() gives a lone displacement. Notes it in `sole` when exact.
Vec3f Transport::lone_edit(std::size_t at, std::size_t i) const {
  const Vec3d e = edited_position(i, vertices_[at]);
  const Vec3d b = widen(base_[vertices_[at]]);
  const Vec3f result = narrow(add(b, sub(e, b)));
  if (result == narrow(e)) scratch_.sole[at] = static_cast<std::uint8_t>(i);
  scratch_.framed[at] = result;
  return result;
}

/// The carried displacement between the frame's reading `carried` and the stack's `stacked`
/// of displacement d (frame_transport.h, the hedge), as far toward the stack's as the
/// fitted Jacobians vouch for it.
Vec3d hedge(const Vec3d& d, const Vec3d& carried, const Vec3d& stacked, double vouched) {
  const double apart = length(sub(carried, stacked));
  if (!(apart > 0) || !(vouched > 0)) return carried;
  const double a = std::clamp(1 - kStackReach * length(sub(d, stacked)) / apart, 0.0, 1.0);
  return add(carried, scale(sub(stacked, carried), vouched * a));
}

/// The formula (frame_transport.h) at the listed vertex `at`, its state loaded in `s`.
Vec3f Transport::transported(std::size_t at, const VertexState& s) const {
  Vec3d sum{};
  std::array<double, kMaxUsers> agrees;   // per carrier, once it carries anything here
  std::array<double, kMaxUsers> vouches;  // per carrier, once its Jacobian is read here
  std::array<Mat3d, kMaxUsers> jacobians;
  RegionalJacobians::Reading reading;  // the fitted samples near the vertex, once gathered
  bool gathered = false;
  std::fill_n(agrees.begin(), n_, -1.0);
  std::fill_n(vouches.begin(), n_, -1.0);
  Vec3d framed{};
  for (std::size_t j = 0; j < n_; ++j) {
    if (!s.moves[j]) continue;
    double count = 1;
    for (std::size_t k = 0; k < n_; ++k)
      if (k != j && s.moves[k]) count += same(s, j, k);
    Vec3d carried = s.d[j], stacked = s.d[j];
    double level = -1;  // read once some diff carries d_j here
    double vouched = 1;
    for (std::size_t i = n_; i-- > 0;) {
      if (i == j || !s.turns[i]) continue;
      double g = (1.0 - same(s, i, j)) * scratch_.weight[i * n_ + j];
      if (!(g > 0)) continue;
      if (agrees[i] < 0) agrees[i] = agreement(at, i);
      g *= agrees[i];
      if (!(g > 0)) continue;
      if (level < 0) level = carrying_level(s.size[j], scratch_.edge[at]);
      const Quat frame = carrier(at, i, level);
      carried = add(carried, scale(rotation_change(swing(frame, scratch_.normal[at]), carried), g));
      if (!hedged_) continue;
      if (const RadialGrab& grab = scratch_.grabs[i]; grab.valid()) {
        const Vec3d p = widen(base_[vertices_[at]]);
        stacked = add(stacked, scale(sub(grab.carry(p, stacked), stacked), g));
        continue;
      }
      if (!regional_) {
        vouched = 0;
        continue;
      }
      if (vouches[i] < 0) {
        if (!gathered) scratch_.jacobians.gather(widen(base_[vertices_[at]]), reading);
        gathered = true;
        vouches[i] = scratch_.jacobians.at(reading, i, jacobians[i]);
      }
      vouched = std::min(vouched, vouches[i]);
      stacked = add(stacked, scale(sub(apply(jacobians[i], stacked), stacked), g));
    }
    framed = add(framed, count == 1 ? carried : scale(carried, 1.0 / count));
    if (hedged_ && level >= 0) carried = hedge(s.d[j], carried, stacked, vouched);
    sum = add(sum, count == 1 ? carried : scale(carried, 1.0 / count));
  }
  scratch_.framed[at] = narrow(add(widen(base_[vertices_[at]]), framed));
  return narrow(add(widen(base_[vertices_[at]]), sum));
}

/// Recognises the carrying diffs that are grabs and lists the samples near the vertices the
/// others may carry at.
void Transport::prepare_jacobians(const JacobianSamples& samples, std::span<const bool> carries) {
  if (!(samples.radius > 0)) return;  // frame-transport: the frames alone carry
  hedged_ = true;
  fit_grabs(carries);
  RegionalJacobians& jacobians = scratch_.jacobians;
  jacobians.prepare(base_, samples, n_);
  regional_ = jacobians.ready();
  if (!regional_) return;
  for (std::size_t at = 0; at < vertices_.size(); ++at)
    if (scratch_.carried_here[at]) jacobians.need(widen(base_[vertices_[at]]));
}

/// Fits the Jacobians of the carrying diffs that are not grabs at the samples listed, from
/// each diff's displacement and the base normals there.
void Transport::fit_jacobians(std::span<const bool> carries, WorkerPool& pool) {
  if (!regional_) return;
  RegionalJacobians& jacobians = scratch_.jacobians;
  jacobians.plan([&](std::uint32_t v) { return base_normal(v); }, pool);
  for (std::size_t i = 0; i < n_; ++i) {
    if (!carries[i] || scratch_.grabs[i].valid()) continue;
    jacobians.fit(
        i, [&](std::uint32_t v) { return sub(edited_position(i, v), widen(base_[v])); }, pool);
  }
}

/// Recognises the carrying diffs that are grabs (radial_grab.h), from the vertices each moves.
void Transport::fit_grabs(std::span<const bool> carries) {
  if (scratch_.grabs.size() < n_) scratch_.grabs.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) {
    RadialGrab& grab = scratch_.grabs[i];
    grab.reset();
    if (!carries[i]) continue;
    std::vector<std::uint32_t>& moved = scratch_.moved_by;
    moved.clear();
    for (const std::uint32_t v : vertices_)
      if (has(users_[i].changed, v)) moved.push_back(v);
    grab.fit(base_, moved,
             [&](std::uint32_t v) { return sub(edited_position(i, v), widen(base_[v])); });
  }
}

/// Puts the per-vertex levels and per-face rows back to their state between merges when the
/// transport ends, also by an exception: the next merge reads them.
struct ScratchReset {
  TransportScratch& scratch;
  std::span<const std::uint32_t> vertices;
  ~ScratchReset() {
    for (const std::uint32_t v : vertices)
      if (v < scratch.reads_level.size()) scratch.reads_level[v] = 0;
    for (const std::uint32_t f : scratch.row_face) scratch.face_row[f] = kNoRow;
    scratch.row_face.clear();
  }
};

}  // namespace

void transport_positions(const Topology& topology, std::span<const Vec3f> base,
                         std::span<const std::uint32_t> vertices,
                         std::span<const TransportInput> users, bool same_once,
                         const JacobianSamples& samples, TransportScratch& scratch,
                         WorkerPool& pool, std::size_t grain, const CarryingFields& carriers,
                         std::span<Vec3f> moved) {
  const ScratchReset reset{scratch, vertices};
  Transport t(topology, base, vertices, users, same_once, scratch);
  t.find_seams();
  t.count_moved();
  t.share_normals();
  t.share_agreements();
  const std::size_t n = users.size();
  const std::size_t chunks = std::max<std::size_t>(1, (vertices.size() + grain - 1) / grain);
  scratch.chunk_energy.resize(chunks * n * n);
  scratch.edge.resize(vertices.size());
  scratch.normal.resize(vertices.size());
  scratch.carried_here.resize(vertices.size());
  scratch.sole.resize(vertices.size());
  scratch.framed.resize(vertices.size());
  if (scratch.reads_level.size() < base.size()) scratch.reads_level.resize(base.size(), 0);
  // The mean turns' sums in at most kMeanTurnBlocks blocks of the list (four doubles per pair
  // and block: per chunk of `grain`, 64 diffs over a million vertices would take 260 MB).
  const std::size_t block =
      std::max(grain, (vertices.size() + kMeanTurnBlocks - 1) / kMeanTurnBlocks);
  const std::size_t blocks = std::max<std::size_t>(1, (vertices.size() + block - 1) / block);
  scratch.chunk_turns.resize(blocks * 4 * n * n);
  std::fill(scratch.chunk_turns.begin(), scratch.chunk_turns.begin() + 4 * n * n, 0.0);
  pool.for_chunks(vertices.size(), block, [&](std::size_t begin, std::size_t end) {
    t.chunk_mean_turns(begin, end, scratch.chunk_turns.data() + (begin / block) * 4 * n * n);
  });
  t.finish_mean_turns(blocks);
  std::fill(scratch.chunk_energy.begin(), scratch.chunk_energy.begin() + n * n, 0.0);
  pool.for_chunks(vertices.size(), grain, [&](std::size_t begin, std::size_t end) {
    t.chunk_energy(begin, end, scratch.chunk_energy.data() + (begin / grain) * n * n);
  });
  t.finish_weights(chunks);
  std::array<bool, kMaxUsers> carries{};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) carries[i] = carries[i] || scratch.weight[i * n + j] > 0;
  const std::span<const bool> carrying(carries.data(), n);
  carriers(carrying, scratch.reads_level, [&] { t.prepare_jacobians(samples, carrying); });
  t.fit_jacobians(carrying, pool);
  t.cache_face_turns(carrying, pool, grain);
  pool.for_chunks(vertices.size(), grain, [&](std::size_t begin, std::size_t end) {
    VertexState s;
    for (std::size_t at = begin; at < end; ++at) moved[at] = t.merged(at, s);
  });
}

}  // namespace csculpt::detail
