// Internal: the face test behind every fold count (folds.cpp) and the merge's fold repair
// (fold_repair.cpp), so what the merge removes is exactly what the counts call a new fold.
//
// The arithmetic follows shared/eval/score_merge.py `flipped` operation for operation: float
// positions widened to double, numpy.cross's component formulas, products summed left to
// right.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "csculpt/diff.h"
#include "csculpt/mesh.h"
#include "csculpt/vec3.h"

namespace csculpt::detail {

/// (b - a) x (c - a), unnormalised.
inline Vec3d face_normal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return cross(sub(b, a), sub(c, a));
}

/// Turned by more than 90 degrees; a zero normal gives 0, never a flip.
inline bool opposed(const Vec3d& n, const Vec3d& m) {
  return dot(n, m) < 0;
}

inline Vec3d base_normal(std::span<const Vec3f> base, const Triangle& t) {
  return face_normal(widen(base[t[0]]), widen(base[t[1]]), widen(base[t[2]]));
}

/// Where `diff` puts its i-th changed position.
inline Vec3d changed_position(const Diff& diff, std::size_t i) {
  const float* p = diff.positions.values.data() + 3 * i;
  return {p[0], p[1], p[2]};
}

/// Vertex `v` of `base` with `diff` applied (sparse: the base unless the diff moved it).
inline Vec3d position_after(std::span<const Vec3f> base, const Diff& diff, std::uint32_t v) {
  const std::vector<std::uint32_t>& indices = diff.positions.indices;
  const auto it = std::lower_bound(indices.begin(), indices.end(), v);
  if (it == indices.end() || *it != v) return widen(base[v]);
  return changed_position(diff, static_cast<std::size_t>(it - indices.begin()));
}

/// Whether one of `diffs`, applied to `base` on its own, flips `t` (whose base normal is `n`):
/// then a flip in the merge is that artist's, not a new fold.
inline bool flipped_by_a_diff(std::span<const Vec3f> base, std::span<const Diff* const> diffs,
                              const Triangle& t, const Vec3d& n) {
  return std::any_of(diffs.begin(), diffs.end(), [&](const Diff* d) {
    return opposed(n, face_normal(position_after(base, *d, t[0]), position_after(base, *d, t[1]),
                                  position_after(base, *d, t[2])));
  });
}

/// A new fold: `t` flipped from the base to the merge (whose normal of `t` is `merged`) and by
/// no single diff — a crease or spike no artist made. The diffs are searched only for faces
/// the merge flipped, which are few.
inline bool is_new_fold(std::span<const Vec3f> base, std::span<const Diff* const> diffs,
                        const Triangle& t, const Vec3d& merged) {
  const Vec3d n = base_normal(base, t);
  return opposed(n, merged) && !flipped_by_a_diff(base, diffs, t, n);
}

/// Whether `v` is the lowest vertex of `t` that `listed` (a predicate on vertices) holds for:
/// a face around several listed vertices is visited from each and tested from that one only.
template <class Listed>
bool lowest_listed(const Triangle& t, std::uint32_t v, Listed&& listed) {
  for (std::uint32_t u : t)
    if (u < v && listed(u)) return false;
  return true;
}

}  // namespace csculpt::detail
