// Paper §3.1 "Hierarchy Construction": greedy selection of coarse nodes, horizontal links
// between first parents, parent sets smoothed over neighbours and trimmed to K.
#include "csculpt/hierarchy.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>

#include "csculpt/error.h"
#include "csculpt/hash.h"

namespace csculpt {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// Sorts each row's items.
void sort_rows(Csr& csr) {
  for (std::size_t r = 0; r < csr.rows(); ++r)
    std::sort(csr.items.begin() + csr.offsets[r], csr.items.begin() + csr.offsets[r + 1]);
}

/// Drops the repeats within each (sorted) row.
void unique_rows(Csr& csr) {
  std::uint32_t write = 0;
  std::uint32_t begin = 0;
  for (std::size_t r = 0; r + 1 < csr.offsets.size(); ++r) {
    const std::uint32_t end = csr.offsets[r + 1];
    auto first = csr.items.begin() + begin;
    auto last = std::unique(first, csr.items.begin() + end);
    csr.offsets[r] = write;
    for (auto it = first; it != last; ++it) csr.items[write++] = *it;
    begin = end;
  }
  csr.offsets.back() = write;
  csr.items.resize(write);
}

/// Builds rows from (row, item) pairs already counted: sorts and de-duplicates each row.
void sort_unique_rows(Csr& csr) {
  sort_rows(csr);
  unique_rows(csr);
}

/// Prefix sums counts (size rows+1, counts in [1..]) into offsets in place.
void counts_to_offsets(std::vector<std::uint32_t>& offsets) {
  for (std::size_t i = 1; i < offsets.size(); ++i) offsets[i] += offsets[i - 1];
}

template <class T>
std::uint64_t fnv1a(std::uint64_t h, const std::vector<T>& v) {
  return csculpt::fnv1a(h, v.data(), v.size() * sizeof(T));
}

struct WeightedParent {
  std::uint32_t node;
  float weight;
};

/// Least change to the weights (sum 1) that makes sum w_k X_k = x in the tangent directions
/// of the parents' spread, then clamped positive and renormalised: smooth edits then leave
/// (almost) no residual at fine levels, so edits of different scales stay on their own levels.
template <class PositionOf>
void adjust_for_linear_precision(const Vec3f& x, std::span<WeightedParent> parents,
                                 PositionOf&& position_of) {
  const std::size_t n = parents.size();
  double cx = 0, cy = 0, cz = 0;
  for (const auto& p : parents) {
    const Vec3f& q = position_of(p.node);
    cx += p.weight * q.x;
    cy += p.weight * q.y;
    cz += p.weight * q.z;
  }
  // constraint rows: sum w = 1 (already), sum w (X - x) = 0 -> residual r = c - x
  const double r[3] = {cx - x.x, cy - x.y, cz - x.z};
  // Solve (D D^T + eps I) lam = r for D = centred parent offsets (3 x n), w += -D^T lam.
  double mean[3] = {0, 0, 0};
  std::array<std::array<double, 3>, 32> d{};
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3f& q = position_of(parents[k].node);
    d[k] = {double(q.x) - x.x, double(q.y) - x.y, double(q.z) - x.z};
    for (int i = 0; i < 3; ++i)
      mean[i] += d[k][static_cast<std::size_t>(i)] / static_cast<double>(n);
  }
  double m[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  double scale = 0;
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < 3; ++i) d[k][i] -= mean[i];
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = 0; j < 3; ++j) m[i][j] += d[k][i] * d[k][j];
  }
  scale = m[0][0] + m[1][1] + m[2][2];
  if (!(scale > 0)) return;
  // regularise the (nearly flat) normal direction so it takes no part
  for (int i = 0; i < 3; ++i) m[i][i] += 1e-3 * scale;
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  if (!(std::abs(det) > 0)) return;
  double inv[3][3];
  inv[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det;
  inv[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
  inv[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
  inv[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det;
  inv[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
  inv[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
  inv[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det;
  inv[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
  inv[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
  double lam[3];
  for (int i = 0; i < 3; ++i) lam[i] = inv[i][0] * r[0] + inv[i][1] * r[1] + inv[i][2] * r[2];
  double total = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double w = parents[k].weight - (d[k][0] * lam[0] + d[k][1] * lam[1] + d[k][2] * lam[2]);
    parents[k].weight = static_cast<float>(std::max(w, 0.0));
    total += parents[k].weight;
  }
  if (!(total > 0)) return;
  for (std::size_t k = 0; k < n; ++k)
    parents[k].weight = static_cast<float>(parents[k].weight / total);
}

/// What one level of the construction works in, reused from level to level.
struct LevelScratch {
  std::vector<std::uint32_t> new_index;  ///< coarse index of a selected node, else kNone
  std::vector<std::uint8_t> has_parent;
  std::vector<std::uint32_t> first_parent;
  Csr provisional;  ///< each node's provisional parent set
  std::vector<WeightedParent> gather;
  std::vector<std::uint32_t> selected;  ///< the coarse nodes, as fine indices
};

/// Greedy selection in index order: a node without a parent becomes a coarse node and the
/// parent of itself and all its neighbours. Returns the number of coarse nodes.
std::uint32_t select_coarse_nodes(const Csr& adjacency, std::uint32_t n, LevelScratch& s) {
  s.new_index.assign(n, kNone);
  s.has_parent.assign(n, 0);
  s.selected.clear();
  for (std::uint32_t x = 0; x < n; ++x) {
    if (s.has_parent[x]) continue;
    s.new_index[x] = static_cast<std::uint32_t>(s.selected.size());
    s.selected.push_back(x);
    s.has_parent[x] = 1;
    for (std::uint32_t y : adjacency.row(x)) s.has_parent[y] = 1;
  }
  return static_cast<std::uint32_t>(s.selected.size());
}

/// Provisional parent sets, sorted by coarse index (= creation order, so the first entry is
/// the node's first parent).
void provisional_parents(const Csr& adjacency, std::uint32_t n, LevelScratch& s) {
  Csr& provisional = s.provisional;
  provisional.offsets.assign(n + 1, 0);
  for (std::uint32_t x = 0; x < n; ++x) {
    std::uint32_t c = s.new_index[x] != kNone ? 1 : 0;
    for (std::uint32_t y : adjacency.row(x)) c += s.new_index[y] != kNone ? 1 : 0;
    provisional.offsets[x + 1] = c;
  }
  counts_to_offsets(provisional.offsets);
  provisional.items.resize(provisional.offsets.back());
  s.first_parent.resize(n);
  for (std::uint32_t x = 0; x < n; ++x) {
    std::uint32_t* out = provisional.items.data() + provisional.offsets[x];
    std::uint32_t* const row_begin = out;
    bool self_done = s.new_index[x] == kNone;
    for (std::uint32_t y : adjacency.row(x)) {
      if (!self_done && x < y) {
        *out++ = s.new_index[x];
        self_done = true;
      }
      if (s.new_index[y] != kNone) *out++ = s.new_index[y];
    }
    if (!self_done) *out++ = s.new_index[x];
    s.first_parent[x] = *row_begin;
  }
}

/// Horizontal links of the coarse level: between distinct first parents of linked nodes.
Csr coarse_links(const Csr& adjacency, std::uint32_t n, std::uint32_t m,
                 const std::vector<std::uint32_t>& first_parent) {
  Csr coarse_adjacency;
  coarse_adjacency.offsets.assign(m + 1, 0);
  for (std::uint32_t x = 0; x < n; ++x)
    for (std::uint32_t y : adjacency.row(x))
      if (first_parent[y] != first_parent[x]) ++coarse_adjacency.offsets[first_parent[x] + 1];
  counts_to_offsets(coarse_adjacency.offsets);
  coarse_adjacency.items.resize(coarse_adjacency.offsets.back());
  std::vector<std::uint32_t> cursor(coarse_adjacency.offsets.begin(),
                                    coarse_adjacency.offsets.end() - 1);
  for (std::uint32_t x = 0; x < n; ++x)
    for (std::uint32_t y : adjacency.row(x))
      if (first_parent[y] != first_parent[x])
        coarse_adjacency.items[cursor[first_parent[x]]++] = first_parent[y];
  sort_unique_rows(coarse_adjacency);
  return coarse_adjacency;
}

/// The coarse level of `fine`'s `selected` nodes, empty of weights; `fine`'s parent arrays
/// sized for K parents per node.
HierarchyLevel begin_coarse_level(HierarchyLevel& fine, std::uint32_t K,
                                  const std::vector<std::uint32_t>& selected) {
  const std::uint32_t n = fine.node_count;
  const auto m = static_cast<std::uint32_t>(selected.size());
  fine.parent.assign(std::size_t{n} * K, 0);
  fine.parent_weight.assign(std::size_t{n} * K, 0.f);
  fine.parent_count.assign(n, 0);
  HierarchyLevel coarse;
  coarse.node_count = m;
  coarse.child_weight_sum.assign(m, 0.f);
  coarse.tree_child_count.assign(m, 0.f);
  coarse.representative.resize(m);
  for (std::uint32_t c = 0; c < m; ++c) coarse.representative[c] = fine.representative[selected[c]];
  return coarse;
}

bool heavier(const WeightedParent& a, const WeightedParent& b) {
  return a.weight != b.weight ? a.weight > b.weight : a.node < b.node;
}

/// Node x's parent set smoothed over its neighbours: the union of their provisional sets,
/// each weighing 1 / its size, equal parents' weights summed (into s.gather).
void smoothed_parents(const Csr& adjacency, std::uint32_t x, LevelScratch& s) {
  std::vector<WeightedParent>& gather = s.gather;
  gather.clear();
  auto add_set = [&](std::uint32_t node) {
    const auto row = s.provisional.row(node);
    const float w = 1.f / static_cast<float>(row.size());
    for (std::uint32_t p : row) gather.push_back({p, w});
  };
  add_set(x);
  for (std::uint32_t y : adjacency.row(x)) add_set(y);
  std::sort(gather.begin(), gather.end(), [](const WeightedParent& a, const WeightedParent& b) {
    return a.node != b.node ? a.node < b.node : a.weight < b.weight;
  });
  std::size_t unique = 0;
  for (std::size_t i = 0; i < gather.size(); ++i) {
    if (unique > 0 && gather[unique - 1].node == gather[i].node)
      gather[unique - 1].weight += gather[i].weight;
    else
      gather[unique++] = gather[i];
  }
  gather.resize(unique);
}

/// Trims s.gather to the K heaviest and normalises them; returns how many are kept. The
/// normalisation to 1 before the trim does not change which K are heaviest, so the trim and
/// one final normalisation give the paper's weights.
std::size_t trim_parents(std::vector<WeightedParent>& gather, std::uint32_t K) {
  const std::size_t keep = std::min<std::size_t>(K, gather.size());
  std::partial_sort(gather.begin(), gather.begin() + static_cast<std::ptrdiff_t>(keep),
                    gather.end(), heavier);
  float total = 0;
  for (std::size_t k = 0; k < keep; ++k) total += gather[k].weight;
  for (std::size_t k = 0; k < keep; ++k) gather[k].weight /= total;
  return keep;
}

/// Node x's K parent slots on `fine` from the first `keep` of `gather` (the rest: the first
/// parent with weight 0), and their sums on `coarse`.
void write_parents(HierarchyLevel& fine, HierarchyLevel& coarse, std::uint32_t x, std::uint32_t K,
                   const std::vector<WeightedParent>& gather, std::size_t keep) {
  std::uint32_t* parent = fine.parent.data() + std::size_t{x} * K;
  float* weight = fine.parent_weight.data() + std::size_t{x} * K;
  for (std::size_t k = 0; k < K; ++k) {
    if (k < keep) {
      parent[k] = gather[k].node;
      weight[k] = gather[k].weight;
      coarse.child_weight_sum[parent[k]] += weight[k];
    } else {
      parent[k] = gather[0].node;
      weight[k] = 0.f;
    }
  }
  fine.parent_count[x] = static_cast<std::uint8_t>(keep);
  coarse.tree_child_count[parent[0]] += 1.f;
}

/// Every node's parents on `fine`: smoothed over its neighbours, trimmed to the K heaviest,
/// renormalised (and, with `positions`, corrected for linear precision).
void assign_parents(const Csr& adjacency, HierarchyLevel& fine, HierarchyLevel& coarse,
                    std::uint32_t K, std::span<const Vec3f> positions, LevelScratch& s) {
  for (std::uint32_t x = 0; x < fine.node_count; ++x) {
    smoothed_parents(adjacency, x, s);
    std::vector<WeightedParent>& gather = s.gather;
    std::size_t keep = trim_parents(gather, K);
    if (!positions.empty() && keep > 1) {
      const Vec3f& self = positions[fine.representative[x]];
      adjust_for_linear_precision(self, {gather.data(), keep},
                                  [&](std::uint32_t node) -> const Vec3f& {
                                    return positions[coarse.representative[node]];
                                  });
      // parents the adjustment clamped to zero are dropped; heaviest first again
      std::sort(gather.begin(), gather.begin() + static_cast<std::ptrdiff_t>(keep), heavier);
      while (keep > 1 && !(gather[keep - 1].weight > 0)) --keep;
    }
    write_parents(fine, coarse, x, K, gather, keep);
  }
}

/// border[v] from the sorted rows of `corners` (row v: the other two corners of every triangle
/// at v, one entry per triangle): v is on the border when some other vertex shares exactly one
/// of its triangles with it.
std::vector<std::uint8_t> border_of(const Csr& corners) {
  std::vector<std::uint8_t> border(corners.rows(), 0);
  for (std::uint32_t v = 0; v < corners.rows(); ++v) {
    const std::span<const std::uint32_t> row = corners.row(v);
    for (std::size_t i = 0; i < row.size() && !border[v];) {
      std::size_t run = i + 1;
      while (run < row.size() && row[run] == row[i]) ++run;
      border[v] = row[i] != v && run - i == 1;
      i = run;
    }
  }
  return border;
}

}  // namespace

Topology Topology::build(std::uint32_t vertex_count, std::span<const Triangle> triangles) {
  Topology t;
  t.vertex_count = vertex_count;
  t.triangles.assign(triangles.begin(), triangles.end());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    for (std::uint32_t v : triangles[f]) {
      if (v >= vertex_count) {
        throw InvalidInput("triangle " + std::to_string(f) + " uses vertex " + std::to_string(v) +
                           " but the mesh has " + std::to_string(vertex_count) + " vertices");
      }
    }
  }
  // vertex -> faces (increasing face order by construction)
  auto& vf = t.vertex_faces;
  vf.offsets.assign(vertex_count + 1, 0);
  for (const Triangle& tri : triangles)
    for (std::uint32_t v : tri) ++vf.offsets[v + 1];
  counts_to_offsets(vf.offsets);
  vf.items.resize(vf.offsets.back());
  {
    std::vector<std::uint32_t> cursor(vf.offsets.begin(), vf.offsets.end() - 1);
    for (std::uint32_t f = 0; f < triangles.size(); ++f)
      for (std::uint32_t v : triangles[f]) vf.items[cursor[v]++] = f;
  }
  // vertex -> vertices: two entries per triangle corner, then sort + unique per row (an edge
  // of one triangle appears once in a sorted row: the border)
  auto& vv = t.vertex_vertices;
  vv.offsets.assign(vertex_count + 1, 0);
  for (const Triangle& tri : triangles)
    for (std::uint32_t v : tri) vv.offsets[v + 1] += 2;
  counts_to_offsets(vv.offsets);
  vv.items.resize(vv.offsets.back());
  {
    std::vector<std::uint32_t> cursor(vv.offsets.begin(), vv.offsets.end() - 1);
    for (const Triangle& tri : triangles) {
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = tri[c];
        vv.items[cursor[v]++] = tri[(c + 1) % 3];
        vv.items[cursor[v]++] = tri[(c + 2) % 3];
      }
    }
  }
  sort_rows(vv);
  t.border = border_of(vv);
  unique_rows(vv);
  // A triangle that repeats a vertex would make it its own neighbour; drop self-links.
  std::uint32_t write = 0, begin = 0;
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    const std::uint32_t end = vv.offsets[v + 1];
    vv.offsets[v] = write;
    for (std::uint32_t i = begin; i < end; ++i)
      if (vv.items[i] != v) vv.items[write++] = vv.items[i];
    begin = end;
  }
  vv.offsets[vertex_count] = write;
  vv.items.resize(write);
  return t;
}

Hierarchy Hierarchy::build(std::uint32_t vertex_count, std::span<const Triangle> triangles,
                           const HierarchyOptions& options, std::span<const Vec3f> positions) {
  const bool precise = options.linear_precision && positions.size() == vertex_count;
  if (options.max_parents < 1 || options.max_parents > 32)
    throw InvalidInput("hierarchy: K (max parents) must be between 1 and 32, got " +
                       std::to_string(options.max_parents));
  Hierarchy h;
  h.options_ = options;
  h.stride_ = options.max_parents;
  h.topology_ = Topology::build(vertex_count, triangles);
  const std::uint32_t K = options.max_parents;

  Csr adjacency = h.topology_.vertex_vertices;  // horizontal links of the current level
  HierarchyLevel level0;
  level0.node_count = vertex_count;
  level0.representative.resize(vertex_count);
  for (std::uint32_t v = 0; v < vertex_count; ++v) level0.representative[v] = v;
  h.levels_.push_back(std::move(level0));

  LevelScratch scratch;
  while (h.levels_.size() < options.max_levels) {
    HierarchyLevel& fine = h.levels_.back();
    const std::uint32_t n = fine.node_count;
    const std::uint32_t m = select_coarse_nodes(adjacency, n, scratch);
    if (m == n) break;  // one node per connected component: the construction is over
    provisional_parents(adjacency, n, scratch);
    Csr coarse_adjacency = coarse_links(adjacency, n, m, scratch.first_parent);
    HierarchyLevel coarse = begin_coarse_level(fine, K, scratch.selected);
    assign_parents(adjacency, fine, coarse, K, precise ? positions : std::span<const Vec3f>{},
                   scratch);
    adjacency = std::move(coarse_adjacency);
    h.levels_.push_back(std::move(coarse));
  }
  return h;
}

std::uint64_t Hierarchy::total_nodes() const {
  std::uint64_t total = 0;
  for (const auto& l : levels_) total += l.node_count;
  return total;
}

HierarchyStats Hierarchy::stats() const {
  HierarchyStats s;
  s.vertices = topology_.vertex_count;
  s.faces = static_cast<std::uint32_t>(topology_.triangles.size());
  s.levels = static_cast<std::uint32_t>(levels_.size());
  s.nodes = total_nodes();
  s.node_ratio = s.vertices ? static_cast<double>(s.nodes) / s.vertices : 0.0;
  double ratio_sum = 0;
  std::uint64_t parent_sum = 0, child_nodes = 0;
  for (std::size_t i = 0; i < levels_.size(); ++i) {
    s.level_nodes.push_back(levels_[i].node_count);
    if (i + 1 < levels_.size()) {
      ratio_sum += static_cast<double>(levels_[i + 1].node_count) / levels_[i].node_count;
      for (std::uint8_t c : levels_[i].parent_count) parent_sum += c;
      child_nodes += levels_[i].node_count;
    }
  }
  s.mean_level_ratio = levels_.size() > 1 ? ratio_sum / static_cast<double>(levels_.size() - 1) : 0;
  s.mean_parents =
      child_nodes ? static_cast<double>(parent_sum) / static_cast<double>(child_nodes) : 0;
  s.top_nodes = levels_.empty() ? 0 : levels_.back().node_count;
  return s;
}

std::uint64_t Hierarchy::digest() const {
  std::uint64_t h = 1469598103934665603ull;
  h = fnv1a(h, topology_.vertex_faces.items);
  h = fnv1a(h, topology_.vertex_vertices.items);
  for (const auto& l : levels_) {
    h = fnv1a(h, &l.node_count, sizeof l.node_count);
    h = fnv1a(h, l.parent);
    h = fnv1a(h, l.parent_weight);
    h = fnv1a(h, l.parent_count);
    h = fnv1a(h, l.child_weight_sum);
  }
  return h;
}

std::string to_json(const HierarchyStats& s) {
  std::ostringstream o;
  o.precision(4);
  o << "{\"vertices\":" << s.vertices << ",\"faces\":" << s.faces << ",\"levels\":" << s.levels
    << ",\"nodes\":" << s.nodes << ",\"node_ratio\":" << s.node_ratio
    << ",\"mean_level_ratio\":" << s.mean_level_ratio << ",\"mean_parents\":" << s.mean_parents
    << ",\"top_nodes\":" << s.top_nodes << ",\"level_nodes\":[";
  for (std::size_t i = 0; i < s.level_nodes.size(); ++i) o << (i ? "," : "") << s.level_nodes[i];
  o << "]}";
  return o.str();
}

}  // namespace csculpt
