// Fold-overs (folds.h), with the scorer's face test (fold_test.h), so a count here equals
// shared/eval/score_merge.py's on the same meshes.
#include "csculpt/folds.h"

#include <algorithm>
#include <string>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/vec3.h"
#include "fold_test.h"

namespace csculpt {
namespace {

using detail::base_normal;
using detail::changed_position;
using detail::opposed;

Vec3d normal_of(const Mesh& base, const Triangle& t) {
  return base_normal(base.positions, t);
}

constexpr std::uint32_t kNone = 0xffffffffu;

/// `base` with `merged` applied, looked up in O(1) through `slot`: per vertex, its index among
/// merged's changed positions, or kNone.
struct MergedView {
  const Mesh& base;
  const Diff& merged;
  std::span<const std::uint32_t> slot;

  bool moved(std::uint32_t v) const { return slot[v] != kNone; }
  Vec3d position(std::uint32_t v) const {
    return moved(v) ? changed_position(merged, slot[v]) : widen(base.positions[v]);
  }
  Vec3d normal(const Triangle& t) const {
    return detail::face_normal(position(t[0]), position(t[1]), position(t[2]));
  }
};

bool is_new_fold(const MergedView& m, std::span<const Diff* const> diffs, const Triangle& t) {
  return detail::is_new_fold(m.base.positions, diffs, t, m.normal(t));
}

void check_vertex_counts(const Mesh& base, std::span<const Diff* const> diffs, const Diff& merged) {
  const std::size_t n = base.vertex_count();
  auto fits = [n](const Diff& d) {
    return d.positions.indices.empty() || d.positions.indices.back() < n;
  };
  if (!fits(merged) ||
      !std::all_of(diffs.begin(), diffs.end(), [&](const Diff* d) { return fits(*d); }))
    throw InvalidInput("count_new_folds: a diff moves a vertex past the base's " +
                       std::to_string(n) + " vertices");
}

/// Sets (or, with `clear`, resets) the slots of merged's changed positions.
void mark(std::vector<std::uint32_t>& slot, const Diff& merged, bool clear) {
  const std::vector<std::uint32_t>& indices = merged.positions.indices;
  for (std::uint32_t i = 0; i < indices.size(); ++i) slot[indices[i]] = clear ? kNone : i;
}

}  // namespace

FoldCounter::FoldCounter(const Topology& topology)
    : topology_(&topology), slot_(topology.vertex_count, kNone) {}

std::uint32_t FoldCounter::count_new_folds(const Mesh& base, std::span<const Diff* const> diffs,
                                           const Diff& merged) {
  check_vertex_counts(base, diffs, merged);
  if (topology_->vertex_count != base.vertex_count() ||
      topology_->triangles.size() != base.face_count())
    throw InvalidInput("count_new_folds: the topology is not the base's");
  mark(slot_, merged, false);
  const MergedView view{base, merged, slot_};
  std::uint32_t folds = 0;
  for (std::uint32_t v : merged.positions.indices)
    for (std::uint32_t f : topology_->vertex_faces.row(v)) {
      const Triangle& t = base.triangles[f];
      if (detail::lowest_listed(t, v, [&](std::uint32_t u) { return view.moved(u); }) &&
          is_new_fold(view, diffs, t))
        ++folds;
    }
  mark(slot_, merged, true);  // all kNone again for the next call
  return folds;
}

std::uint32_t count_new_folds(const Topology& topology, const Mesh& base,
                              std::span<const Diff* const> diffs, const Diff& merged) {
  return FoldCounter(topology).count_new_folds(base, diffs, merged);
}

std::uint32_t count_new_folds(const Mesh& base, std::span<const Diff* const> diffs,
                              const Diff& merged) {
  check_vertex_counts(base, diffs, merged);
  std::vector<std::uint32_t> slot(base.vertex_count(), kNone);
  mark(slot, merged, false);
  const MergedView view{base, merged, slot};
  std::uint32_t folds = 0;
  for (const Triangle& t : base.triangles)
    if ((view.moved(t[0]) || view.moved(t[1]) || view.moved(t[2])) && is_new_fold(view, diffs, t))
      ++folds;
  return folds;
}

std::uint32_t count_opposed_face_pairs(const Mesh& mesh) {
  struct EdgeFace {
    std::uint64_t edge;  ///< (lower vertex << 32) | higher vertex
    std::uint32_t face;
  };
  std::vector<EdgeFace> edges;
  edges.reserve(3 * mesh.face_count());
  std::vector<Vec3d> normals;
  normals.reserve(mesh.face_count());
  for (std::uint32_t f = 0; f < mesh.face_count(); ++f) {
    const Triangle& t = mesh.triangles[f];
    normals.push_back(normal_of(mesh, t));
    for (std::size_t k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      edges.push_back({std::uint64_t{std::min(a, b)} << 32 | std::max(a, b), f});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const EdgeFace& x, const EdgeFace& y) {
    return x.edge != y.edge ? x.edge < y.edge : x.face < y.face;
  });
  std::uint32_t pairs = 0;
  // Faces around one edge are adjacent in the sorted list; a non-manifold edge counts every
  // opposed pair among its faces.
  for (std::size_t begin = 0, end = 0; begin < edges.size(); begin = end) {
    while (end < edges.size() && edges[end].edge == edges[begin].edge) ++end;
    for (std::size_t i = begin; i < end; ++i)
      for (std::size_t j = i + 1; j < end; ++j)
        pairs += opposed(normals[edges[i].face], normals[edges[j].face]) ? 1u : 0u;
  }
  return pairs;
}

}  // namespace csculpt
