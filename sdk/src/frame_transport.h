// Internal: the position merge of `full` — every artist's displacement carried in the local
// frames of the other artists' edits (docs/merge-quality.md says why and what it fixes).
//
// For each vertex v changed by some diff, with d_j = e_j - b the displacement of diff j and
// R_i the rotation of diff i at v (the per-vertex isometry's rotation, paper §3.1):
//
//   result = b + sum_j  T_j d_j / c_j,   T_j = prod_{i != j} (I + g_ij (S_i - I))
//
// - T_j transports a displacement into the frame the other edits give the surface there: a
//   detail on a bend turns with the bend and keeps its height, on a cast it follows the new
//   normals. Where no other diff rotates v, T_j = I and the edit comes back exactly; such
//   vertices (most of a merge where few edits overlap) skip the energy, the carrying level
//   and the frame altogether.
// - R_i is read at the scale of the displacement it carries: averaged over the hierarchy
//   (level l spans about 2^l edges) across |d_j| / h edges around v, h the local edge length,
//   interpolated between levels. A displacement of several edges rides the turn of the
//   surface around it, as a brush's stroke follows the surface under its footprint; read
//   vertex by vertex, the rough rotations of a finer stroke beside it sheared it into creases
//   (a session's rebases meet that every sync). A detail of an edge or less reads the
//   vertex's own rotation, so it follows the deformed normals exactly.
// - S_i is the swing of R_i about the base normal n (R_i = S_i * twist about n): the turn
//   that takes n to R_i n. A displacement rides the turn of the surface, not a spin of the
//   surface about its normal: at the rim of a grab or a pinch the faces' closest rotations
//   spin in the tangent plane, and a sideways detail turned by that spin lands elsewhere
//   (measured: 0.24 -> 0.03 rel_err for the chin pinch under a twist, four_artists_monkey).
// - g_ij = (1 - s_ij) w_ij: whether i's frame carries j. w_ij = max(0, 2 a_ij - 1) with
//   a_ij = E_ji^4 / (E_ij^4 + E_ji^4) and
//   E_ij = sum_v sqrt(|(R_i M_ij^-1 - I) d_j|^2 + k_i |d_j|^2), the change i's deformation
//   would make to j's displacement: its whole rotations (with the spin: a small grab's spin
//   marks it as the finer edit) relative to M_ij, i's mean turn over j's displacement (the
//   normalised sum of R_i weighted by |d_j| over the vertices E_ij reads; in a merge of more
//   than 4,096 changed vertices, over every k-th in list order, about 4,096 in all), and k_i,
//   twice the mean squared relative change of the edges around v under i (its stretch; a
//   pinch or a small grab hardly turns the surface but squeezes and shears it); the coarser edit
//   changes the finer one's displacement little and the finer edit's deformation would change
//   the coarser's a lot, so the coarser edit carries the finer one (for a bump of width w on
//   a bend of radius r the ratio is r / w, the share falls as its fourth power). The changes
//   add as lengths, not squared lengths, so that the few vertices an edit spikes (where a
//   smoothing overshoots on a fine patch) weigh as a few vertices: squared, two spiked
//   vertices of 599 outweighed the rest of the patch and made a smoothing of a whole figure
//   the finer edit under a swirl on its head. The turn i gives the whole of j's support alike
//   is a rigid motion of it, which changes j's shape not at all: only how i's turn varies
//   across j tells i's scale. Whole, it read a bend as fine as a grab near the bend's origin,
//   where the bend turns the surface by tens of degrees but moves it little (the grab carried
//   the bend: 0.27 from the frame ideal, `sum` 0.27; now 0.006, the bend carrying). Edits of one
//   scale (a_ij = 1/2) carry neither: they add, as strokes one after the other would. Every
//   term is bounded by |(R_i - I) d_j|, so the result is continuous even where the weights
//   switch.
// - s_ij = max(0, 1 - |d_i - d_j| / (0.001 min(|d_i|, |d_j|)))^2 and c_j = sum_k s_jk count
//   each intent once: identical edits come back once (idempotence), independent ones add, and
//   two edits moving the same way by similar amounts (two inflates along one normal) are two.
// - g_ij is scaled by how well the faces around v agree on how diff i turns the surface (the
//   length of the mean of their turns as unit quaternions: 1 for one turn, however large):
//   full up to a spread of 30 degrees, none from 90 (a fold between them). Where a grab
//   crushes a thin part, some faces flip beside others that do not, and the averaged rotation
//   is no frame: a detail turned by it landed 3.3x addition's error from the stacked ideal
//   on a 275-piece house. A bend's or twist's faces turn alike and carry as before.
// - Coincident vertices that are not connected (split seams) share one rotation per diff,
//   so a seam that the artists moved together stays closed.
// - The hedge between the two readings of a coarse edit. The frames above read it as a turn
//   of the surface, and a detail keeps its height along the new normals (ideal_frame). A
//   volumetric deformer moves the detail by its Jacobian J instead (the stacked ideal): a
//   taper's side keeps the detail's direction and shrinks it, a Cast tilts it against the
//   surface's turn. J is fitted from the carrier's displacement over the curved region
//   around v (regional_jacobian.h); with x = T_j d_j (the frame's reading) and
//   y = prod (I + g_ij (J_i - I)) d_j (the stack's), the carried displacement is the point
//   of the segment x..y nearest x within kStackReach |d_j - y| of y:
//     x + a (y - x),  a = clamp(1 - kStackReach |d_j - y| / |x - y|, 0, 1).
//   As |x - d_j| <= |x - y| + |y - d_j|, that point is nearer the frame's reading than
//   addition is whenever kStackReach > 1, and it is never further than kStackReach times
//   addition's distance from the stack's. Where the readings agree (bends, twists: J turns
//   the detail as the surface turns) a is 0 and the frames carry alone.
// Products and sums run in the canonical order of the diffs, per vertex in double, and the
// sums E in fixed chunks added in order: the result is bit-identical for any diff order,
// thread count or SIMD width.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "csculpt/dual_quat.h"
#include "csculpt/hierarchy.h"
#include "csculpt/vec3.h"
#include "radial_grab.h"
#include "regional_jacobian.h"
#include "worker_pool.h"

namespace csculpt::detail {

/// Levels of the hierarchy a carrying rotation is read at: 0 (the vertex's own) to 4 (about
/// 16 edges around it). A displacement longer than that still reads level 4.
constexpr std::size_t kCarryLevels = 5;

/// A quaternion in double: a face's turn, and the faces' turns summed around a vertex.
struct Vec4d {
  double w = 0, x = 0, y = 0, z = 0;
};

/// No row of TransportScratch::face_turns.
constexpr std::uint32_t kNoRow = 0xffffffffu;

/// One diff as the transport reads it, in the merge's canonical order.
struct TransportInput {
  /// Per vertex: its rotation under this diff, valid where `rotated` has the vertex's bit.
  const DualQuat* isometry = nullptr;
  const std::uint64_t* rotated = nullptr;
  /// Per vertex: the slot of its edited position in `edited`, valid where `changed` is set.
  const std::uint32_t* slot = nullptr;
  const std::uint64_t* changed = nullptr;
  const float* edited = nullptr;  ///< xyz per changed vertex
  /// Per level l in [1, kCarryLevels): the rotations averaged over the hierarchy's level l and
  /// interpolated back to the vertices, valid where `rotated` has the vertex's bit (level 0
  /// is `isometry`).
  std::array<const Quat*, kCarryLevels> smoothed{};
};

/// Scratch reused across merges (no allocation once warm).
struct TransportScratch {
  std::vector<double> chunk_energy;    ///< per chunk, users x users sums E_ij (above)
  std::vector<double> chunk_turns;     ///< per block, users x users sums of R_i over d_j
  std::vector<Quat> mean_turn;         ///< users x users: M_ij (above)
  std::vector<double> weight;          ///< users x users: w_ij
  std::vector<Quat> seam_rotation;     ///< per seam group and diff: the shared rotation
  std::vector<std::uint32_t> seam_of;  ///< per listed vertex: its seam group or kNoSeam
  std::vector<std::uint32_t> table;    ///< open addressing by position: 1 + list index, 0 empty
  std::vector<Vec3d> seam_normal;      ///< per seam group: the sum of its members' normals
  std::vector<double> seam_agreement;  ///< per seam group and diff: the least agreement
  std::vector<double> edge;            ///< per listed vertex: its mean edge length
  std::vector<Vec3d> normal;           ///< per listed vertex where carried_here: its base normal
  /// Per face: its row of face_turns, or kNoRow (all kNoRow between merges).
  std::vector<std::uint32_t> face_row;
  std::vector<std::uint32_t> row_face;  ///< per row: its face
  std::vector<Vec4d> face_turns;        ///< per row and carrier: how the carrier turns the face
  std::vector<std::uint32_t> chunk_first_row;  ///< per chunk of listed vertices: its first row
  /// Per listed vertex: 1 where some diff turns the surface under another's displacement.
  std::vector<std::uint8_t> carried_here;
  /// Per listed vertex: the diff whose edited position the merge gave it exactly, or
  /// kNoSoleEdit (fold_repair.h: a face all of whose vertices hold one diff's edit or the base
  /// is that diff's face, and cannot be a new fold).
  std::vector<std::uint8_t> sole;
  /// Per listed vertex: its merged position with the frames alone carrying (no hedge toward
  /// the stacked reading); the fold repair pulls back toward it where the hedge folds.
  std::vector<Vec3f> framed;
  /// Per vertex: bit l set when a displacement there reads carrying level l (all clear
  /// between merges).
  std::vector<std::uint8_t> reads_level;
  /// The carriers' regional Jacobians, for the stacked reading of what they carry.
  RegionalJacobians jacobians;
  /// Per diff: the grab it is, when it carries and is one (its stacked reading is exact).
  std::vector<RadialGrab> grabs;
  std::vector<std::uint32_t> moved_by;  ///< the vertices one diff moves
};

/// Sets the carrying levels of the diffs with carries[i] (see transport_positions), and runs
/// `beside` once meanwhile, as one more task of the parallel region that averages them: the
/// transport's serial work that needs no carrying level overlaps the averaging (with one
/// carrier, the other threads would wait for it).
using CarryingFields = std::function<void(std::span<const bool> carries,
                                          std::span<const std::uint8_t> reads_level,
                                          const std::function<void()>& beside)>;

/// Merged positions of the vertices in `vertices` (increasing: the union of the changed
/// ones) into `moved` (one per vertex), using `pool` in chunks of `grain`. `same_once`: the
/// sameness s as above; false takes s = 0 (SameChange::add: every displacement adds).
/// `carriers(carries, reads_level, beside)`, once the weights are known and before any
/// position is merged, sets `smoothed` of each input i with carries[i] (it carries another
/// diff somewhere); level l is read only at the vertices v with bit l of reads_level[v].
/// `samples` with a radius: each carried displacement is kept within kStackReach times
/// addition's distance of how the carrier's regional Jacobian would move it (the hedge
/// above); without one, the frames alone carry.
void transport_positions(
    const Topology& topology, std::span<const Vec3f> base, std::span<const std::uint32_t> vertices,
    std::span<const TransportInput> users, bool same_once, const JacobianSamples& samples,
    TransportScratch& scratch, WorkerPool& pool, std::size_t grain,
    const CarryingFields& carriers, std::span<Vec3f> moved);

}  // namespace csculpt::detail
