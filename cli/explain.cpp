// `csculpt merge --explain` (explain.h). Distances are computed in double from the float
// positions, as shared/eval/score_merge.py computes them with numpy, so rel_err here is the
// scorer's number for the same files.
#include "explain.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include "csculpt/error.h"
#include "csculpt/folds.h"
#include "csculpt/io.h"
#include "csculpt/vec3.h"
#include "json_writer.h"

namespace csculpt::cli {
namespace {

constexpr std::size_t kWorst = 10;  ///< parts and vertices listed

// ---- per-vertex vectors -------------------------------------------------------------------

Vec3d minus(const Vec3f& a, const Vec3f& b) {
  return sub(widen(a), widen(b));
}
/// (x^2 + y^2) + z^2, numpy.linalg.norm's order.
double squared(const Vec3d& v) {
  return dot(v, v);
}

/// sqrt(mean(values[i]^2)) over `indices`; NaN when there are none (the scorer's nan).
double rms_over(const std::vector<double>& values, const std::vector<std::uint32_t>& indices) {
  if (indices.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (std::uint32_t v : indices) sum += values[v] * values[v];
  return std::sqrt(sum / static_cast<double>(indices.size()));
}

// ---- the artists' edits -------------------------------------------------------------------

/// One artist's edit: how far it moved each vertex, and where it acted.
struct Artist {
  std::string name;
  std::vector<double> moved;           ///< |edit - base| per vertex
  std::vector<std::uint32_t> support;  ///< increasing
  double size = 0;                     ///< RMS of `moved` over the support
  double rms_all = 0;                  ///< RMS over every vertex (picks the smallest edit)
};

std::vector<double> displacement_lengths(const Mesh& base, const Diff& diff) {
  std::vector<double> moved(base.vertex_count(), 0.0);
  const AttributeDiff& p = diff.positions;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::uint32_t v = p.indices[i];
    const Vec3f edited{p.values[3 * i], p.values[3 * i + 1], p.values[3 * i + 2]};
    moved[v] = length(minus(edited, base.positions[v]));
  }
  return moved;
}

/// The scorer's support: moved more than a millionth of the edit's largest move (+ 1e-9).
std::vector<std::uint32_t> support_of(const std::vector<double>& moved) {
  const double peak = moved.empty() ? 0.0 : *std::max_element(moved.begin(), moved.end());
  const double threshold = 1e-6 * std::max(1e-12, peak) + 1e-9;
  std::vector<std::uint32_t> support;
  for (std::uint32_t v = 0; v < moved.size(); ++v)
    if (moved[v] > threshold) support.push_back(v);
  return support;
}

Artist describe_artist(const Mesh& base, const Diff& diff, const std::string& name) {
  Artist a;
  a.name = name;
  a.moved = displacement_lengths(base, diff);
  a.support = support_of(a.moved);
  a.size = rms_over(a.moved, a.support);
  double sum = 0;
  for (double m : a.moved) sum += m * m;
  a.rms_all = a.moved.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(a.moved.size()));
  return a;
}

/// The edit with the least RMS move over the whole mesh (the first of equals, as Python's min).
std::size_t smallest_edit(const std::vector<Artist>& artists) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < artists.size(); ++k)
    if (artists[k].rms_all < artists[best].rms_all) best = k;
  return best;
}

bool moved_by(const Artist& a, std::uint32_t v) {
  return std::binary_search(a.support.begin(), a.support.end(), v);
}

// ---- connected parts ----------------------------------------------------------------------

struct Parts {
  std::vector<std::uint32_t> of_vertex;  ///< numbered by their lowest vertex
  std::uint32_t count = 0;
};

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];  // path halving
  return v;
}

/// Connected components of the triangles; a vertex on no triangle is a part of its own.
Parts connected_parts(const Mesh& mesh) {
  std::vector<std::uint32_t> parent(mesh.vertex_count());
  std::iota(parent.begin(), parent.end(), 0u);
  for (const Triangle& t : mesh.triangles)
    for (std::size_t k = 1; k < 3; ++k) {
      const std::uint32_t a = find_root(parent, t[0]), b = find_root(parent, t[k]);
      parent[std::max(a, b)] = std::min(a, b);  // the root is the part's lowest vertex
    }
  Parts parts;
  parts.of_vertex.resize(mesh.vertex_count());
  std::vector<std::uint32_t> number(mesh.vertex_count(), 0);
  for (std::uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    const std::uint32_t root = find_root(parent, v);
    if (root == v) number[v] = parts.count++;
    parts.of_vertex[v] = number[root];
  }
  return parts;
}

// ---- the error field over the hierarchy ---------------------------------------------------

/// Each node of the next level: the weighted average of its children (the decomposition the
/// merge runs on dual quaternions, paper §3.1, here on the error's translations).
std::vector<Vec3d> average_into_parents(const HierarchyLevel& fine, const HierarchyLevel& coarse,
                                        std::uint32_t stride, const std::vector<Vec3d>& values) {
  std::vector<Vec3d> sums(coarse.node_count);
  for (std::uint32_t c = 0; c < fine.node_count; ++c)
    for (std::uint32_t k = 0; k < fine.parent_count[c]; ++k) {
      const std::size_t slot = std::size_t{c} * stride + k;
      const double w = fine.parent_weight[slot];
      Vec3d& s = sums[fine.parent[slot]];
      s = add(s, scale(values[c], w));
    }
  for (std::uint32_t p = 0; p < coarse.node_count; ++p) {
    const double total = coarse.child_weight_sum[p];
    sums[p] = total > 0 ? Vec3d{sums[p].x / total, sums[p].y / total, sums[p].z / total} : Vec3d{};
  }
  return sums;
}

/// RMS over a level's nodes of node - (weighted average of its parents): what this level adds.
double residual_rms(const HierarchyLevel& fine, std::uint32_t stride,
                    const std::vector<Vec3d>& values, const std::vector<Vec3d>& parents) {
  if (fine.node_count == 0) return 0;
  double sum = 0;
  for (std::uint32_t c = 0; c < fine.node_count; ++c) {
    Vec3d r = values[c];
    for (std::uint32_t k = 0; k < fine.parent_count[c]; ++k) {
      const std::size_t slot = std::size_t{c} * stride + k;
      const double w = fine.parent_weight[slot];
      const Vec3d& p = parents[fine.parent[slot]];
      r = sub(r, scale(p, w));
    }
    sum += squared(r);
  }
  return std::sqrt(sum / fine.node_count);
}

double rms_of(const std::vector<Vec3d>& values) {
  if (values.empty()) return 0;
  double sum = 0;
  for (const Vec3d& v : values) sum += squared(v);
  return std::sqrt(sum / static_cast<double>(values.size()));
}

struct LevelError {
  std::uint32_t nodes = 0;
  double residual_rms = 0;  ///< what the level adds to its parents' blend
  double value_rms = 0;     ///< the field averaged down to this level
};

/// The error decomposed level by level: level 0 is per vertex, the coarsest's residual is
/// its whole value (it has no parents).
std::vector<LevelError> decompose(const Hierarchy& h, std::vector<Vec3d> values) {
  const std::span<const HierarchyLevel> levels = h.levels();
  std::vector<LevelError> out;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    LevelError e{levels[i].node_count, 0, rms_of(values)};
    if (i + 1 == levels.size()) {
      e.residual_rms = e.value_rms;
    } else {
      std::vector<Vec3d> coarse =
          average_into_parents(levels[i], levels[i + 1], h.stride(), values);
      e.residual_rms = residual_rms(levels[i], h.stride(), values, coarse);
      values = std::move(coarse);
    }
    out.push_back(e);
  }
  return out;
}

// ---- one ideal ----------------------------------------------------------------------------

/// An ideal is the base's vertices moved: stored with the base's triangles or with none (a
/// point set, as tests/eval/cases stores them to keep the cases small).
Mesh read_ideal(const std::string& path, const Mesh& base) {
  Mesh ideal = read_mesh(path, Faces::optional);
  if (ideal.vertex_count() != base.vertex_count())
    throw InvalidInput(path + ": an ideal must have the base's " +
                       std::to_string(base.vertex_count()) + " vertices; it has " +
                       std::to_string(ideal.vertex_count()));
  if (!ideal.triangles.empty() && ideal.triangles != base.triangles)
    throw InvalidInput(path + ": an ideal's triangles, when it has any, must be the base's");
  return ideal;
}

std::vector<Vec3d> error_field(const Mesh& result, const Mesh& ideal) {
  std::vector<Vec3d> e(result.vertex_count());
  for (std::size_t v = 0; v < e.size(); ++v) e[v] = minus(result.positions[v], ideal.positions[v]);
  return e;
}

std::vector<double> lengths(const std::vector<Vec3d>& field) {
  std::vector<double> out(field.size());
  std::transform(field.begin(), field.end(), out.begin(), length);
  return out;
}

/// The `count` largest of `values`, largest first (ties: lower index first).
std::vector<std::uint32_t> largest(const std::vector<double>& values, std::size_t count) {
  std::vector<std::uint32_t> order(values.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto middle = order.begin() + static_cast<std::ptrdiff_t>(std::min(count, order.size()));
  std::partial_sort(order.begin(), middle, order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return values[a] != values[b] ? values[a] > values[b] : a < b;
  });
  order.erase(middle, order.end());
  return order;
}

void write_rel_errors(JsonWriter& j, const std::vector<double>& error,
                      const std::vector<Artist>& artists) {
  const Artist& small = artists[smallest_edit(artists)];
  j.field("rel_err", rms_over(error, small.support) / small.size);
  j.field("smallest_edit", small.name);
  j.key("per_artist").begin_array();
  for (const Artist& a : artists)
    j.begin_object()
        .field("artist", a.name)
        .field("rel_err", rms_over(error, a.support) / a.size)
        .end_object();
  j.end_array();
}

void write_parts(JsonWriter& j, const std::vector<double>& error, const Parts& parts) {
  std::vector<double> squared_error(parts.count, 0.0);
  std::vector<std::uint32_t> vertices(parts.count, 0);
  double total = 0;
  for (std::size_t v = 0; v < error.size(); ++v) {
    squared_error[parts.of_vertex[v]] += error[v] * error[v];
    ++vertices[parts.of_vertex[v]];
    total += error[v] * error[v];
  }
  j.key("worst_parts").begin_array();
  for (std::uint32_t p : largest(squared_error, kWorst))
    j.begin_object()
        .field_int("part", p)
        .field_int("vertices", vertices[p])
        .field("error_share", total > 0 ? squared_error[p] / total : 0.0)
        .field("rms_error", std::sqrt(squared_error[p] / vertices[p]))
        .end_object();
  j.end_array();
}

void write_levels(JsonWriter& j, const Hierarchy& h, const std::vector<Vec3d>& field) {
  j.key("levels").begin_array();
  std::uint32_t level = 0;
  for (const LevelError& e : decompose(h, field))
    j.begin_object()
        .field_int("level", level++)
        .field_int("nodes", e.nodes)
        .field("rms_residual", e.residual_rms)
        .field("rms_value", e.value_rms)
        .end_object();
  j.end_array();
}

void write_worst_vertices(JsonWriter& j, const std::vector<double>& error,
                          const std::vector<Artist>& artists, const Parts& parts) {
  j.key("worst_vertices").begin_array();
  for (std::uint32_t v : largest(error, kWorst)) {
    j.begin_object().field_int("vertex", v).field("error", error[v]);
    j.field_int("part", parts.of_vertex[v]).key("moved_by").begin_array();
    for (const Artist& a : artists)
      if (moved_by(a, v)) j.string(a.name);
    j.end_array().end_object();
  }
  j.end_array();
}

void write_ideal(JsonWriter& j, const ExplainInput& in, const std::string& path,
                 const std::vector<Artist>& artists, const Parts& parts) {
  const std::vector<Vec3d> field = error_field(in.result, read_ideal(path, in.base));
  const std::vector<double> error = lengths(field);
  j.begin_object().field("file", path);
  write_rel_errors(j, error, artists);
  j.field("rms_error", rms_of(field));
  j.field("max_error", error.empty() ? 0.0 : *std::max_element(error.begin(), error.end()));
  write_parts(j, error, parts);
  write_levels(j, in.hierarchy, field);
  write_worst_vertices(j, error, artists, parts);
  j.end_object();
}

// ---- the report ---------------------------------------------------------------------------

void write_artists(JsonWriter& j, const std::vector<Artist>& artists) {
  j.key("artists").begin_array();
  for (const Artist& a : artists)
    j.begin_object()
        .field("artist", a.name)
        .field_int("support", a.support.size())
        .field("rms_size", a.size)
        .field("max_move",
               a.moved.empty() ? 0.0 : *std::max_element(a.moved.begin(), a.moved.end()))
        .end_object();
  j.end_array();
}

void write_folds(JsonWriter& j, const ExplainInput& in) {
  std::vector<const Diff*> diffs;
  for (const Diff& d : in.diffs) diffs.push_back(&d);
  j.field_int("new_folds", count_new_folds(in.hierarchy.topology(), in.base, diffs, in.merged));
  j.field_int("opposed_face_pairs", count_opposed_face_pairs(in.result));
  j.field_int("opposed_face_pairs_base", count_opposed_face_pairs(in.base));
}

}  // namespace

std::string explain_merge(const ExplainInput& in) {
  std::vector<Artist> artists;
  for (std::size_t k = 0; k < in.diffs.size(); ++k)
    artists.push_back(describe_artist(in.base, in.diffs[k], in.edit_names[k]));
  const Parts parts = connected_parts(in.base);
  JsonWriter j;
  j.begin_object()
      .field("method", to_string(in.method))
      .field_int("vertices", in.base.vertex_count())
      .field_int("faces", in.base.face_count())
      .field_int("hierarchy_levels", in.hierarchy.levels().size())
      .field_int("parts", parts.count);
  write_artists(j, artists);
  write_folds(j, in);
  j.key("ideals").begin_array();
  for (const std::string& path : in.ideal_paths) write_ideal(j, in, path, artists, parts);
  j.end_array().end_object();
  return j.str();
}

}  // namespace csculpt::cli
