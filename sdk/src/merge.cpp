// Paper §3.1: per-vertex isometries -> averages up the hierarchy -> residuals per node ->
// magnitude-weighted blend per node -> recomposition coarse to fine.
//
// Everything is sparse: a diff touches a few percent of the vertices, so each level keeps
// a list of the nodes that differ from the identity plus a bitmap over its nodes (cleared
// word by word from the list at the next pass), and the merged result is computed only for the
// ancestors of vertices some diff changed. Untouched vertices keep their exact base values (paper's
// identity).
// Index (search for the section lines "// ----"):
//   The two algebras the pipeline runs on      DqOps (isometries), VecOps (translations)
//   Sparse per-level storage                   SparseLevel, SparsePyramid, decompose,
//                                              blend_residuals, blend_and_reconstruct
//   The Merger                                 Workspace, Merger::merge, Merger::Pass
//   positions as isometries                    full (frame transport + fold repair) and the
//                                              paper's hierarchy methods
//   positions as translations                  multiscale-translation, weighted, average, sum
//   channels                                   materials in their linear spaces
#include "csculpt/merge.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <functional>
#include <numeric>
#include <string>
#include <thread>
#include <type_traits>

#include "csculpt/dual_quat.h"
#include "csculpt/error.h"
#include "fold_repair.h"
#include "frame_transport.h"
#include "simd/aligned_allocator.h"
#include "simd/blend_kernel.h"
#include "simd/dq_simd.h"
#include "simd/dq_soa.h"
#include "simd/vertex_isometry_kernel.h"
#include "worker_pool.h"

namespace csculpt {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

constexpr std::array<MergeMethod, 10> kMethods = {MergeMethod::full,
                                                  MergeMethod::paper_blend,
                                                  MergeMethod::single_parent,
                                                  MergeMethod::single_level_isometry,
                                                  MergeMethod::multiscale_translation,
                                                  MergeMethod::weighted_translation,
                                                  MergeMethod::average,
                                                  MergeMethod::sum,
                                                  MergeMethod::hierarchy_blend,
                                                  MergeMethod::frame_transport};

// ---------------------------------------------------------------------------------------
// The two algebras the pipeline runs on.

/// Unit dual quaternions (positions in the isometry methods). The arithmetic runs on `Reg`:
/// on SSE2 two registers (dq_simd.h), lane by lane the scalar dual_quat.h operations in the
/// same order, so both paths give bit-identical results.
struct DqOps {
  using Value = DualQuat;
#if defined(__SSE2__)
  using Reg = detail::DQv;
  static Reg load(const Value& q) {
    return detail::dq_load(q);
  }
  static void store(Value& out, const Reg& q) {
    detail::dq_store(out, q);
  }
  static Reg identity() {
    return detail::dq_identity();
  }
  static Reg zero() {
    return detail::dq_zero();
  }
  static void add(Reg& acc, float w, const Reg& q) {
    detail::dq_add_scaled(acc, w, q);
  }
  static void add_offset(Reg& acc, float w, const Reg& q) {
    detail::dq_add_scaled_offset(acc, w, q);
  }
  /// Average of all children: the absent ones (identity) weigh total - listed.
  static Reg finish_average(const Reg& acc, float total_weight) {
    using namespace detail;
    return dq_canonical(dq_normalized(dq_add_real_w(acc, total_weight)));
  }
  static Reg residual(const Reg& parent, const Reg& node) {
    return detail::dq_canonical(detail::dq_inverse_mul(parent, node));
  }
  static Reg compose(const Reg& parent, const Reg& residual) {
    return detail::dq_canonical(detail::dq_mul(parent, residual));
  }
  static float magnitude(const Reg& q) {
    return detail::dq_magnitude(q);
  }
  static Reg finish_blend(const Reg& acc, float magnitude_sum, std::uint32_t /*users*/) {
    if (!(magnitude_sum > 0)) return identity();
    return detail::dq_canonical(detail::dq_normalized(acc));
  }
  /// 1 + the sum of offsets (q - 1) that add_offset accumulated into zero(), normalised
  static Reg compose_offsets(const Reg& acc) {
    using namespace detail;
    return dq_canonical(dq_normalized(dq_add_real_w(acc, 1.f)));
  }
  static float distance(const Reg& a, const Reg& b) {
    return detail::dq_distance(a, b);
  }
#else
  using Reg = DualQuat;
  static Reg load(const Value& q) {
    return q;
  }
  static void store(Value& out, const Reg& q) {
    out = q;
  }
  static Reg identity() {
    return DualQuat::identity();
  }
  static Reg zero() {
    return {{0, 0, 0, 0}, {0, 0, 0, 0}};
  }
  static void add(Reg& acc, float w, const Reg& q) {
    add_scaled(acc, w, q);
  }
  static void add_offset(Reg& acc, float w, const Reg& q) {
    add_scaled_offset(acc, w, q);
  }
  /// Average of all children: the absent ones (identity) weigh total - listed.
  static Reg finish_average(Reg acc, float total_weight) {
    acc.real.w += total_weight;
    return canonical(normalized(acc));
  }
  static Reg residual(const Reg& parent, const Reg& node) {
    return canonical(inverse(parent) * node);
  }
  static Reg compose(const Reg& parent, const Reg& residual) {
    return canonical(parent * residual);
  }
  static float magnitude(const Reg& q) {
    return csculpt::magnitude(q);
  }
  static Reg finish_blend(const Reg& acc, float magnitude_sum, std::uint32_t /*users*/) {
    if (!(magnitude_sum > 0)) return identity();
    return canonical(normalized(acc));
  }
  /// 1 + the sum of offsets (q - 1) that add_offset accumulated into zero(), normalised
  static Reg compose_offsets(Reg acc) {
    acc.real.w += 1.f;
    return canonical(normalized(acc));
  }
  static float distance(const Reg& a, const Reg& b) {
    const Quat dr = a.real - b.real, dd = a.dual - b.dual;
    return std::sqrt(dot(dr, dr) + dot(dd, dd));
  }
#endif
};

/// How translations of several diffs combine at a node.
enum class TranslationBlend { magnitude, sum, average };

/// Translations of up to 4 components (positions without rotation; material channels in
/// their linear space).
struct Vec4 {
  float v[4] = {0, 0, 0, 0};
  friend bool operator==(const Vec4&, const Vec4&) = default;
};

template <TranslationBlend Blend>
struct VecOps {
  using Value = Vec4;
  using Reg = Vec4;
  static Reg load(const Value& q) { return q; }
  static void store(Value& out, const Reg& q) { out = q; }
  static Value identity() { return {}; }
  static Value zero() { return {}; }
  static void add(Value& acc, float w, const Value& q) {
    for (int i = 0; i < 4; ++i) acc.v[i] += w * q.v[i];
  }
  static void add_offset(Value& acc, float w, const Value& q) { add(acc, w, q); }
  static Value finish_average(Value acc, float total_weight) {
    const float inv = total_weight > 0 ? 1.f / total_weight : 0.f;
    for (float& x : acc.v) x *= inv;
    return acc;
  }
  static Value residual(const Value& parent, const Value& node) {
    Value r;
    for (int i = 0; i < 4; ++i) r.v[i] = node.v[i] - parent.v[i];
    return r;
  }
  static Value compose(const Value& parent, const Value& residual) {
    Value r;
    for (int i = 0; i < 4; ++i) r.v[i] = parent.v[i] + residual.v[i];
    return r;
  }
  static float magnitude(const Value& q) {
    if constexpr (Blend == TranslationBlend::magnitude)
      return std::sqrt(q.v[0] * q.v[0] + q.v[1] * q.v[1] + q.v[2] * q.v[2] + q.v[3] * q.v[3]);
    else
      return 1.f;  // sum and average weigh every diff alike
  }
  static Value finish_blend(Value acc, float magnitude_sum, std::uint32_t users) {
    if constexpr (Blend == TranslationBlend::sum) {
      return acc;
    } else if constexpr (Blend == TranslationBlend::average) {
      const float inv = 1.f / static_cast<float>(users);
      for (float& x : acc.v) x *= inv;
      return acc;
    } else {
      if (!(magnitude_sum > 0)) return identity();
      const float inv = 1.f / magnitude_sum;
      for (float& x : acc.v) x *= inv;
      return acc;
    }
  }
  static Value compose_offsets(const Value& acc) { return acc; }
  static float distance(const Value& a, const Value& b) {
    float d2 = 0;
    for (int i = 0; i < 4; ++i) d2 += (a.v[i] - b.v[i]) * (a.v[i] - b.v[i]);
    return std::sqrt(d2);
  }
};

// ---------------------------------------------------------------------------------------
// Sparse per-level storage.

template <class Value>
struct SparseLevel {
  /// Values of the listed nodes (others undefined), 32-byte aligned: a dual quaternion is
  /// half a cache line and never straddles two.
  std::vector<Value, detail::AlignedAllocator<Value, 64>> values;
  /// One bit per node, set exactly for the listed ones: "does this node differ from the
  /// identity" is a bit test in a small array (a level-0 bitmap of 1M vertices is 128 KB),
  /// and the values of absent nodes are never loaded.
  std::vector<std::uint64_t> bits;
  std::vector<std::uint32_t> list;  ///< the marked nodes, in first-touch order

  /// Starts a pass over a level of n nodes: forgets the previous pass's marks (clearing
  /// only the bitmap words its list touched).
  void begin(std::size_t n) {
    for (std::uint32_t v : list) bits[v >> 6] = 0;
    list.clear();
    if (values.size() < n) values.resize(n);
    if (bits.size() < (n + 63) / 64) bits.resize((n + 63) / 64, 0);
  }
  Value& val(std::uint32_t node) { return values[node]; }
  const Value& val(std::uint32_t node) const { return values[node]; }
  /// Marks the node; returns true if it was new this pass.
  bool mark(std::uint32_t node) {
    std::uint64_t& word = bits[node >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (node & 63);
    if ((word & bit) != 0) return false;
    word |= bit;
    list.push_back(node);
    return true;
  }
  /// Sets the node's bit only; the caller lists the node itself.
  void set(std::uint32_t node) { bits[node >> 6] |= std::uint64_t{1} << (node & 63); }
};

/// A level read-only, as the per-node loops see it.
template <class Value>
struct LevelView {
  const Value* values = nullptr;
  const std::uint64_t* bits = nullptr;
  bool has(std::uint32_t node) const { return (bits[node >> 6] >> (node & 63) & 1) != 0; }
  static LevelView of(const SparseLevel<Value>& l) { return {l.values.data(), l.bits.data()}; }
};

/// The sparse loops below know their next nodes well before they read them.
inline void prefetch(const void* at) {
  __builtin_prefetch(at);
}

template <class Value>
struct SparsePyramid {
  std::vector<SparseLevel<Value>> levels;
  void begin(const Hierarchy& h, std::size_t level_count) {
    if (levels.size() < level_count) levels.resize(level_count);
    for (std::size_t i = 0; i < level_count; ++i) levels[i].begin(h.levels()[i].node_count);
  }
};

/// Where a vertex's merged value comes from when exactly one diff changed it: that diff
/// (position in the canonical order) and the entry in its list; otherwise owner = kNoOwner.
struct SoleChange {
  std::uint32_t owner;
  std::uint32_t entry;
};
constexpr std::uint32_t kNoOwner = 0xffffffffu;

/// Marks the union of several increasing index lists on `level`, appending the nodes in
/// increasing order (a k-way merge: no sort needed afterwards), and records for each
/// appended node whether a single list holds it.
template <class Value, class ListOf>
void mark_sorted_union(SparseLevel<Value>& level, std::size_t lists, ListOf&& list_of,
                       std::vector<SoleChange>& sole) {
  constexpr std::uint32_t kEnd = 0xffffffffu;
  // The lists as raw ranges, read through cursors; an exhausted list reads kEnd.
  const std::uint32_t* at[max_merge_diffs];
  const std::uint32_t* end[max_merge_diffs];
  const std::uint32_t* begin[max_merge_diffs];
  std::size_t total = 0;
  for (std::size_t j = 0; j < lists; ++j) {
    const auto& l = list_of(j);
    begin[j] = at[j] = l.data();
    end[j] = l.data() + l.size();
    total += l.size();
  }
  sole.clear();
  sole.reserve(total);
  level.list.reserve(level.list.size() + total);
  auto head = [&](std::size_t j) { return at[j] != end[j] ? *at[j] : kEnd; };
  for (;;) {
    std::uint32_t next = kEnd;
    for (std::size_t j = 0; j < lists; ++j) next = std::min(next, head(j));
    if (next == kEnd) return;
    level.mark(next);
    SoleChange who{kNoOwner, 0};
    std::uint32_t holders = 0;
    for (std::size_t j = 0; j < lists; ++j) {
      if (head(j) == next) {
        who = {static_cast<std::uint32_t>(j), static_cast<std::uint32_t>(at[j] - begin[j])};
        ++holders;
        ++at[j];
      }
    }
    sole.push_back(holders == 1 ? who : SoleChange{kNoOwner, 0});
  }
}

/// Lists on `level`, in increasing order, the nodes whose bits are set (its list is empty
/// before: the bits were set with set()).
template <class Value>
void list_set_bits(SparseLevel<Value>& level) {
  const std::size_t words = level.bits.size();
  for (std::size_t w = 0; w < words; ++w) {
    std::uint64_t word = level.bits[w];
    while (word != 0) {
      level.list.push_back(
          static_cast<std::uint32_t>(w * 64 + static_cast<unsigned>(__builtin_ctzll(word))));
      word &= word - 1;
    }
  }
}

/// Marks the union of several index lists on `level` (empty before), listing the nodes in
/// increasing order through the level's bitmap: linear in the lists' lengths plus
/// node_count / 64, and no per-node record of which list holds it (mark_sorted_union gives
/// that where it is needed).
template <class Value, class ListOf>
void mark_union(SparseLevel<Value>& level, std::size_t lists, ListOf&& list_of) {
  std::size_t total = 0;
  for (std::size_t j = 0; j < lists; ++j) {
    const auto& l = list_of(j);
    for (std::uint32_t v : l) level.set(v);
    total += l.size();
  }
  level.list.reserve(total);
  list_set_bits(level);
}

/// Which parent links the pipeline follows: the K blended parents, or only the heaviest
/// (the tree of the single-parent variant).
struct ParentLinks {
  const Hierarchy* hierarchy = nullptr;
  bool tree = false;

  /// One level's links as raw arrays, hoisted out of the per-node loops.
  struct Level {
    const std::uint32_t* parent;
    const float* weight;
    const std::uint8_t* parent_count;
    const float* child_weight_sum;  ///< of this level's nodes (tree: child counts)
    std::size_t stride;
    bool tree;
    /// A node's links: parents[k], weights[k] for k < count (the tree: the first parent,
    /// weight 1).
    struct Row {
      const std::uint32_t* parents;
      const float* weights;
      std::uint32_t count;
    };
    Row row(std::uint32_t node) const {
      static constexpr float kOne[1] = {1.f};
      const std::size_t at = std::size_t{node} * stride;
      return tree ? Row{parent + at, kOne, 1u} : Row{parent + at, weight + at, parent_count[node]};
    }
  };
  Level level(std::size_t i) const {
    const HierarchyLevel& l = hierarchy->levels()[i];
    return {l.parent.data(),       l.parent_weight.data(),
            l.parent_count.data(), tree ? l.tree_child_count.data() : l.child_weight_sum.data(),
            hierarchy->stride(),   tree};
  }
  std::uint32_t count(std::size_t level, std::uint32_t node) const {
    return tree ? 1u : hierarchy->levels()[level].parent_count[node];
  }
  std::uint32_t parent(std::size_t level, std::uint32_t node, std::uint32_t k) const {
    return hierarchy->levels()[level].parent[std::size_t{node} * hierarchy->stride() + k];
  }
};

/// Averages one diff's level-0 values up the hierarchy (paper: "the isometry of each node
/// is the average transformation of its children", normalised).
template <class Ops>
void decompose(const ParentLinks& links, std::size_t level_count,
               SparsePyramid<typename Ops::Value>& pyramid) {
  using Reg = typename Ops::Reg;
  for (std::size_t i = 0; i + 1 < level_count; ++i) {
    SparseLevel<typename Ops::Value>& fine = pyramid.levels[i];
    SparseLevel<typename Ops::Value>& coarse = pyramid.levels[i + 1];
    const ParentLinks::Level fl = links.level(i);
    // Raw pointers in locals: the SIMD stores below may alias anything in memory, so
    // pointers read through the level objects would be reloaded on every update.
    const std::uint32_t* const fine_list = fine.list.data();
    const std::size_t n_fine = fine.list.size();
    const auto* const fine_values = fine.values.data();
    auto* const coarse_values = coarse.values.data();
    std::uint64_t* const coarse_bits = coarse.bits.data();
    constexpr std::size_t kAhead = 8;
    for (std::size_t at = 0; at < n_fine; ++at) {
      if (at + kAhead < n_fine) prefetch(&fine_values[fine_list[at + kAhead]]);
      const std::uint32_t c = fine_list[at];
      const Reg q = Ops::load(fine_values[c]);
      const ParentLinks::Level::Row links_of_c = fl.row(c);
      for (std::uint32_t k = 0; k < links_of_c.count; ++k) {
        const std::uint32_t p = links_of_c.parents[k];
        std::uint64_t& word = coarse_bits[p >> 6];
        const std::uint64_t bit = std::uint64_t{1} << (p & 63);
        Reg acc;
        if ((word & bit) != 0) {
          acc = Ops::load(coarse_values[p]);
        } else {  // first touch: coarse.mark(p)
          word |= bit;
          coarse.list.push_back(p);
          acc = Ops::zero();
        }
        Ops::add_offset(acc, links_of_c.weights[k], q);
        Ops::store(coarse_values[p], acc);
      }
    }
    const float* child_weight_sum = links.level(i + 1).child_weight_sum;
    for (std::uint32_t p : coarse.list)
      Ops::store(coarse_values[p],
                 Ops::finish_average(Ops::load(coarse_values[p]), child_weight_sum[p]));
  }
}

/// How the residuals of several diffs at one node combine.
///  - magnitude: the paper's operator, normalize(sum_j m_j q_j) with m = |q - 1|. It
///    treats every residual at a node as one shared intent, so two edits of different scale
///    that both leave residuals at a node each lose part of theirs.
///  - intent: the same magnitude-weighted sum, but each residual's weight is divided by the
///    (magnitude-weighted, soft) count of residuals at that node that express the same
///    intent, s_jk = max(0, 1 - |d_j - d_k| / max(|d_j|, |d_k|))^2 with d = q - 1. Identical
///    residuals blend (idempotence), independent ones add (so a detail and the fine
///    residual of a large edit both survive), a null residual changes nothing (identity);
///    symmetric and continuous. With s = 1 everywhere it is the paper's operator.
///  - independent: intent with s_jk = 0 for j != k: every residual adds (SameChange::add).
enum class NodeBlend { magnitude, intent, independent };

using detail::kMaxDiffs;

template <class Ops>
typename Ops::Reg blend_residuals(NodeBlend rule, const typename Ops::Reg* r, const float* m,
                                  std::size_t n, std::uint32_t users) {
  typename Ops::Reg acc = Ops::zero();
  float magnitude_sum = 0;
  if (rule == NodeBlend::magnitude) {
    for (std::size_t j = 0; j < n; ++j) {
      Ops::add(acc, m[j], r[j]);
      magnitude_sum += m[j];
    }
    return Ops::finish_blend(acc, magnitude_sum, users);
  }
  // intent: acc = sum_j c_j (r_j - 1) with c_j = m_j / sum_k s_jk m_k
  for (std::size_t j = 0; j < n; ++j) {
    if (!(m[j] > 0)) continue;
    float same = 0;
    for (std::size_t k = 0; k < n; ++k) {
      if (!(m[k] > 0)) continue;
      if (k != j && rule == NodeBlend::independent) continue;
      const float closeness =
          k == j ? 1.f : std::max(0.f, 1.f - Ops::distance(r[j], r[k]) / std::max(m[j], m[k]));
      const float s = closeness * closeness;
      same += s * m[k];
    }
    Ops::add_offset(acc, m[j] / same, r[j]);
    magnitude_sum += m[j];
  }
  if (!(magnitude_sum > 0)) return Ops::identity();
  return Ops::compose_offsets(acc);
}

/// Marks the nodes the result needs above level 0, a superset of the ancestors of the
/// vertices listed on merged.levels[0]: the union of the diffs' own nodes there (each
/// diff's pyramid holds the ancestors of every vertex it changed, after decompose()). A
/// word-wise OR of their bitmaps, so no parent links are read; each level's list comes out
/// in increasing order. The blend computes every node on its own from coarser levels, so
/// nodes beyond the ancestors change no result.
template <class Value>
void mark_coarse_union(std::span<const SparsePyramid<Value>> users, std::size_t level_count,
                       SparsePyramid<Value>& merged) {
  for (std::size_t i = 1; i < level_count; ++i) {
    SparseLevel<Value>& out = merged.levels[i];
    const std::size_t words = out.bits.size();
    for (std::size_t w = 0; w < words; ++w) {
      std::uint64_t any = 0;
      for (const SparsePyramid<Value>& u : users) any |= u.levels[i].bits[w];
      out.bits[w] = any;
    }
    list_set_bits(out);
  }
}

/// Residuals of every diff at each needed node, blended per node, recomposed from the
/// coarsest level down (paper §3.1 "Final Merged Mesh"). Fills merged.levels[0] for the
/// nodes listed there, and the coarser levels for the nodes mark_coarse_union() listed.
/// Nodes per parallel chunk of the blend.
constexpr std::size_t kBlendGrain = 512;
/// The carriers' regional Jacobians (regional_jacobian.h): about this many samples over the
/// mesh, and a fitting radius of this share of their bounding box diagonal (a region curved
/// enough to show the normal column, small enough that a coarse deformer is about affine over
/// it: in a numpy sketch of the fit, 0.05 misread a four-artist case on the torus, 0.1 and
/// 0.15 none).
constexpr std::uint32_t kJacobianSamples = 2048;
constexpr double kJacobianRadius = 0.1;

/// `level0_done(begin, end)`, when given, runs on each chunk of level 0's list right after
/// the chunk is blended, while its values are still in cache.
template <class Ops>
void blend_and_reconstruct(
    const ParentLinks& links, std::size_t level_count,
    std::span<SparsePyramid<typename Ops::Value>> users, SparsePyramid<typename Ops::Value>& merged,
    NodeBlend rule, detail::WorkerPool& pool,
    const std::function<void(std::size_t, std::size_t)>* level0_done = nullptr) {
  using Value = typename Ops::Value;
  using Reg = typename Ops::Reg;
  using View = LevelView<Value>;
  const auto user_count = static_cast<std::uint32_t>(users.size());
  const std::size_t n_users = users.size();
  for (std::size_t level = level_count; level-- > 0;) {
    SparseLevel<Value>& out = merged.levels[level];
    const bool has_parents = level + 1 < level_count;
    const ParentLinks::Level fl = links.level(level);
    // Every diff at this level and at the next coarser one, then the merged result's
    // coarser level last.
    View here[kMaxDiffs];
    View coarse[kMaxDiffs + 1];
    for (std::size_t j = 0; j < n_users; ++j) {
      here[j] = View::of(users[j].levels[level]);
      if (has_parents) coarse[j] = View::of(users[j].levels[level + 1]);
    }
    if (has_parents) coarse[n_users] = View::of(merged.levels[level + 1]);
    Value* out_values = out.values.data();
    const std::uint32_t* out_list = out.list.data();
    // Each node reads only coarser, finished levels and writes only itself.
#if defined(__SSE2__)
    if constexpr (std::is_same_v<Ops, DqOps>) {
      if (rule == NodeBlend::intent) {
        detail::BlendLevelArgs args;
        args.list = out_list;
        args.parent = fl.parent;
        args.weight = fl.weight;
        args.parent_count = fl.parent_count;
        args.stride = fl.stride;
        args.tree = fl.tree;
        args.has_parents = has_parents;
        args.users = n_users;
        for (std::size_t j = 0; j < n_users; ++j) {
          args.here_values[j] = here[j].values;
          args.here_bits[j] = here[j].bits;
        }
        for (std::size_t j = 0; has_parents && j <= n_users; ++j) {
          args.coarse_values[j] = coarse[j].values;
          args.coarse_bits[j] = coarse[j].bits;
        }
        args.out_values = out_values;
        const detail::BlendChunkFn chunk = detail::blend_chunk_kernel();
        pool.for_chunks(out.list.size(), kBlendGrain, [&](std::size_t begin, std::size_t end) {
          chunk(args, begin, end);
          if (level == 0 && level0_done != nullptr) (*level0_done)(begin, end);
        });
        continue;
      }
    }
#endif
    pool.for_chunks(out.list.size(), kBlendGrain, [&](std::size_t begin, std::size_t end) {
      Reg residuals[kMaxDiffs];
      float magnitudes[kMaxDiffs];
      Reg parent_acc[kMaxDiffs + 1];  // the diffs' parent blends, then the merged one
      bool parent_any[kMaxDiffs + 1];
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t c = out_list[i];
        // One pass over the node's parent links serves every diff and the merged result.
        // Sum of w (q - 1) over parents that differ from the identity; the identity's share
        // (the weights' total) is added once at the end.
        for (std::size_t j = 0; j <= n_users; ++j) {
          parent_acc[j] = Ops::zero();
          parent_any[j] = false;
        }
        float weight_total = 0;
        if (has_parents) {
          const ParentLinks::Level::Row links_of_c = fl.row(c);
          for (std::uint32_t k = 0; k < links_of_c.count; ++k) {
            const std::uint32_t p = links_of_c.parents[k];
            const float w = links_of_c.weights[k];
            weight_total += w;
            for (std::size_t j = 0; j <= n_users; ++j) {
              if (coarse[j].has(p)) {
                Ops::add_offset(parent_acc[j], w, Ops::load(coarse[j].values[p]));
                parent_any[j] = true;
              }
            }
          }
        }
        // identity exactly when no parent differs from it, so untouched regions stay exact
        for (std::size_t j = 0; j < n_users; ++j) {
          const Reg q = here[j].has(c) ? Ops::load(here[j].values[c]) : Ops::identity();
          residuals[j] = parent_any[j]
                             ? Ops::residual(Ops::finish_average(parent_acc[j], weight_total), q)
                             : q;
          magnitudes[j] = Ops::magnitude(residuals[j]);
        }
        const Reg residual = blend_residuals<Ops>(rule, residuals, magnitudes, n_users, user_count);
        Ops::store(
            out_values[c],
            parent_any[n_users]
                ? Ops::compose(Ops::finish_average(parent_acc[n_users], weight_total), residual)
                : residual);
      }
      if (level == 0 && level0_done != nullptr) (*level0_done)(begin, end);
    });
  }
}

struct MethodTraits {
  bool isometry;    // dual quaternions for positions
  bool multiscale;  // use the hierarchy
  bool tree;        // K = 1
  TranslationBlend blend;
  NodeBlend node_blend;      // for positions and channels
  bool channels_per_vertex;  // channels blend per vertex (else over the hierarchy)
  bool transport = false;    // positions: displacements carried in each other's frames
  bool same_once = true;     // matching changes count once (SameChange::once)
  bool hedge = false;        // transport: carried details hedged toward the stacked reading
};

MethodTraits traits(MergeMethod m) {
  switch (m) {
    // Channels need no rotation invariance, and counting intents already keeps a broad fill
    // and a fine stroke inside it apart, so they merge per vertex (exact where one artist
    // painted, no hierarchy leak); paper-blend keeps the paper's hierarchy for them.
    case MergeMethod::full:
      return {true, false, false, TranslationBlend::magnitude, NodeBlend::intent, true,
              true, true,  true};
    case MergeMethod::frame_transport:
      return {true, false, false, TranslationBlend::magnitude, NodeBlend::intent, true, true};
    case MergeMethod::hierarchy_blend:
      return {true, true, false, TranslationBlend::magnitude, NodeBlend::intent, true};
    case MergeMethod::single_parent:
      return {true, true, true, TranslationBlend::magnitude, NodeBlend::intent, true};
    case MergeMethod::single_level_isometry:
      return {true, false, false, TranslationBlend::magnitude, NodeBlend::intent, true};
    case MergeMethod::multiscale_translation:
      return {false, true, false, TranslationBlend::magnitude, NodeBlend::intent, true};
    case MergeMethod::weighted_translation:
      return {false, false, false, TranslationBlend::magnitude, NodeBlend::magnitude, true};
    case MergeMethod::average:
      return {false, false, false, TranslationBlend::average, NodeBlend::magnitude, true};
    case MergeMethod::sum:
      return {false, false, false, TranslationBlend::sum, NodeBlend::magnitude, true};
    case MergeMethod::paper_blend:
      return {true, true, false, TranslationBlend::magnitude, NodeBlend::magnitude, false};
  }
  throw InvalidInput("unknown merge method " + std::to_string(static_cast<std::uint32_t>(m)));
}

/// The method's traits with the merge's rule for matching changes.
MethodTraits traits(MergeMethod m, SameChange same) {
  MethodTraits t = traits(m);
  if (same == SameChange::add) {
    t.same_once = false;
    if (t.node_blend == NodeBlend::intent) t.node_blend = NodeBlend::independent;
  }
  return t;
}

/// Canonical order of diffs by content, so the floating-point sums do not depend on the
/// order the diffs arrived in.
/// `keys` holds each diff's digest().
std::vector<std::size_t> canonical_order(std::span<const Diff* const> diffs,
                                         std::span<const std::uint64_t> keys) {
  std::vector<std::size_t> order(diffs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto bytes_less = [](const auto& a, const auto& b) {
    if (a.size() != b.size()) return a.size() < b.size();
    return std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) < 0;
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (keys[a] != keys[b]) return keys[a] < keys[b];
    const Diff& x = *diffs[a];
    const Diff& y = *diffs[b];
    if (x.positions.indices != y.positions.indices)
      return bytes_less(x.positions.indices, y.positions.indices);
    if (x.positions.values != y.positions.values)
      return bytes_less(x.positions.values, y.positions.values);
    for (std::size_t c = 0; c < std::min(x.channels.size(), y.channels.size()); ++c) {
      if (x.channels[c].change.indices != y.channels[c].change.indices)
        return bytes_less(x.channels[c].change.indices, y.channels[c].change.indices);
      if (x.channels[c].change.values != y.channels[c].change.values)
        return bytes_less(x.channels[c].change.values, y.channels[c].change.values);
    }
    return false;  // identical content: either order gives the same sums
  });
  return order;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// The Merger: its workspace, validation, and the pass (Merger::Pass) that runs the steps.

/// One carrying task's scratch (Merger::Pass::carrying_rotations), per level between the
/// vertices and the averaged level: the interpolated rotations, and the nodes the readers
/// below need, each listed once (marked; the marks are cleared after the task).
struct CarryingScratch {
  std::vector<std::vector<Quat>> rotation;
  std::vector<std::vector<std::uint32_t>> need;
  std::vector<std::vector<std::uint8_t>> marked;
};

struct Merger::Workspace {
  std::vector<SparsePyramid<DualQuat>> dq_users;
  SparsePyramid<DualQuat> dq_merged;
  std::vector<SparsePyramid<Vec4>> vec_users;
  SparsePyramid<Vec4> vec_merged;
  /// Per diff: where each vertex's edited position sits in the diff (valid where `changed`).
  struct Lookup {
    std::vector<std::uint32_t> slot;
    detail::BitSet changed;  ///< all clear between merges
    detail::VertexIsometryScratch isometry;
    std::vector<std::uint32_t> touched;
  };
  std::vector<Lookup> lookups;
  std::vector<SoleChange> sole;
  std::vector<Vec3f> moved;  ///< merged positions of the changed vertices, before listing
  std::vector<std::size_t> chunk_offset;  ///< where each chunk of them starts in the list
  std::vector<detail::TransportInput> transport_inputs;
  detail::TransportScratch transport;
  /// Per diff and carrying level (u * kCarryLevels + l): its rotations averaged over level l,
  /// per vertex; and per such task, the levels between as scratch.
  std::vector<std::vector<Quat>> carrying;
  std::vector<CarryingScratch> carrying_scratch;
  detail::FoldRepairScratch fold_repair;
  detail::WorkerPool pool;

  explicit Workspace(unsigned threads) : pool(threads) {}
};

Merger::Merger(const Hierarchy& hierarchy, unsigned threads)
    : hierarchy_(hierarchy), workspace_(std::make_unique<Workspace>(threads)) {}
Merger::~Merger() = default;

namespace {

/// Runs the translation pipeline with the blend rule chosen at run time.
template <class Fn>
void with_translation_ops(TranslationBlend blend, Fn&& fn) {
  switch (blend) {
    case TranslationBlend::magnitude:
      fn(VecOps<TranslationBlend::magnitude>{});
      break;
    case TranslationBlend::sum:
      fn(VecOps<TranslationBlend::sum>{});
      break;
    case TranslationBlend::average:
      fn(VecOps<TranslationBlend::average>{});
      break;
  }
}

void require_diff_count(std::size_t count) {
  if (count > max_merge_diffs)
    throw InvalidInput("merge: " + std::to_string(count) + " diffs given, at most " +
                       std::to_string(max_merge_diffs) + " are merged at once");
}

/// The base must be the mesh the hierarchy was built for: the same vertex count, and a
/// sampled check of the triangles (count, ends and 1024 strided triangles): O(1) per merge,
/// and a mesh of other connectivity with the same vertex count is caught all the same.
void require_hierarchy_mesh(const Hierarchy& hierarchy, const Mesh& base) {
  if (base.vertex_count() != hierarchy.topology().vertex_count)
    throw InvalidInput("merge: the mesh has " + std::to_string(base.vertex_count()) +
                       " vertices but the hierarchy was built for " +
                       std::to_string(hierarchy.topology().vertex_count));
  const auto& mine = hierarchy.topology().triangles;
  bool same = base.triangles.size() == mine.size();
  const std::size_t n = mine.size();
  for (std::size_t k = 0; same && n > 0 && k <= 1024; ++k) {
    const std::size_t f = k == 1024 ? n - 1 : k * n / 1024;
    same = base.triangles[f] == mine[f];
  }
  if (!same)
    throw InvalidInput("merge: the mesh's triangles differ from those the hierarchy was built for");
}

using DiffKeys = std::array<std::uint64_t, max_merge_diffs>;

/// Each diff validated and digested in parallel (read-only); the first invalid one in
/// argument order throws, as a serial loop would. Returns each diff's digest().
DiffKeys validate_and_digest(detail::WorkerPool& pool, const Mesh& base,
                             std::span<const Diff* const> diffs) {
  std::exception_ptr invalid[max_merge_diffs];
  DiffKeys keys{};
  pool.run(diffs.size(), [&](std::size_t i) {
    try {
      validate(*diffs[i], base, "diff " + std::to_string(i));
      keys[i] = digest(*diffs[i]);
    } catch (...) {
      invalid[i] = std::current_exception();
    }
  });
  for (std::size_t i = 0; i < diffs.size(); ++i)
    if (invalid[i]) std::rethrow_exception(invalid[i]);
  return keys;
}

void require_valid_frame(const MergeFrame& frame) {
  if (!(frame.scale > 0) || !std::isfinite(frame.scale))
    throw InvalidInput("merge: the frame scale must be positive and finite");
}

const std::vector<std::uint32_t> kNoChanges;

/// `d` as a merge returns it: one channel entry per channel of `base`, in its order.
Diff in_base_order(const Diff& d, const Mesh& base) {
  Diff out;
  clear_to_layout(out, base);  // d's vertex count: validated
  out.positions = d.positions;
  for (ChannelDiff& channel : out.channels)
    for (const ChannelDiff& given : d.channels)
      if (given.desc.name == channel.desc.name) channel.change = given.change;
  return out;
}

}  // namespace

/// One merge of validated diffs, step by step: the positions (as isometries, or as
/// translations), then each channel. Holds what every step reads; writes only the Merger's
/// workspace and timings.
struct Merger::Pass {
  using Lookup = Workspace::Lookup;

  const Hierarchy& hierarchy;
  Workspace& ws;
  MergeTimings& timings;
  const Mesh& base;
  std::span<const Diff* const> diffs;
  const MethodTraits t;
  const std::vector<std::size_t> order;  ///< canonical: diff u of the merge is diffs[order[u]]
  const MergeFrame frame;
  const std::uint32_t users = static_cast<std::uint32_t>(diffs.size());
  /// The hierarchy's levels the positions use: all of them, the transport's carrying levels
  /// (rotations averaged for carrying, not blended), or only the vertices.
  const std::size_t level_count = t.multiscale ? hierarchy.levels().size()
                                  : t.transport
                                      ? std::min(hierarchy.levels().size(), detail::kCarryLevels)
                                      : 1;
  const ParentLinks links{&hierarchy, t.tree};
  const std::uint32_t vertex_count = static_cast<std::uint32_t>(base.vertex_count());
  const detail::Frame local{frame.center, 1.f / frame.scale};

  Diff run();

 private:
  const AttributeDiff& positions_of(std::size_t u) const { return diffs[order[u]]->positions; }
  Vec3f from_local(const Vec3f& p) const {
    return Vec3f{p.x * frame.scale + frame.center.x, p.y * frame.scale + frame.center.y,
                 p.z * frame.scale + frame.center.z};
  }
  template <class UserPyramids, class MergedPyramid>
  void count_work(const UserPyramids& user_pyramids, const MergedPyramid& merged_pyramid,
                  std::size_t levels, std::size_t value_bytes);
  void prepare_lookups();

  // positions as isometries
  void isometry_positions(AttributeDiff& out, Clock::time_point t0);
  void isometries_and_averages(Clock::time_point t0);
  double diff_isometries(std::size_t u);
  void blend_isometries(std::size_t kept_chunks);
  void transport_positions();
  void carrying_fields(std::span<const bool> carries, std::span<const std::uint8_t> reads_level,
                       const std::function<void()>& beside);
  detail::JacobianSamples jacobian_samples() const;
  void carrying_rotations(std::size_t u, std::size_t top, std::span<const std::uint8_t> reads_level,
                          CarryingScratch& scratch);
  void list_carrying_needs(const SparsePyramid<DualQuat>& pyramid, std::size_t top,
                           std::span<const std::uint8_t> reads_level,
                           CarryingScratch& scratch) const;
  void repair_folds(std::span<const std::uint32_t> changed, std::span<Vec3f> moved);
  void count_kept(std::size_t begin, std::size_t end);
  void list_moved_positions(AttributeDiff& out, std::size_t chunks);

  // positions as translations
  template <class Ops>
  void translation_positions(AttributeDiff& out, Clock::time_point t0);
  template <class Ops>
  void list_translated_positions(AttributeDiff& out) const;

  // channels: translations in each channel's linear space
  ChannelDiff merge_channel(const Channel& channel);
  template <class Ops>
  void channel_translations(const Channel& channel, std::size_t channel_levels,
                            std::span<const std::vector<std::uint32_t>*> changed_lists,
                            std::span<const float*> changed_values);
  template <class Ops>
  void list_channel_result(const Channel& channel, std::size_t channel_levels,
                           std::span<const float* const> changed_values,
                           ChannelDiff& out_diff) const;
};

Diff Merger::merge(const Mesh& base, std::span<const Diff> diffs, MergeMethod method,
                   const MergeFrame& frame) {
  require_diff_count(diffs.size());  // before the pointers are taken
  std::array<const Diff*, max_merge_diffs> pointers{};
  for (std::size_t i = 0; i < diffs.size(); ++i) pointers[i] = &diffs[i];
  return merge(base, std::span<const Diff* const>(pointers.data(), diffs.size()), method, frame);
}

Diff Merger::merge(const Mesh& base, std::span<const Diff* const> diffs, MergeMethod method,
                   const MergeFrame& frame, SameChange same) {
  const MethodTraits t = traits(method, same);
  timings_ = {};
  require_hierarchy_mesh(hierarchy_, base);
  require_diff_count(diffs.size());
  const DiffKeys keys = validate_and_digest(workspace_->pool, base, diffs);
  require_valid_frame(frame);
  // One edit merges to itself, exactly, whatever the method: there is nothing to blend it
  // with. A session merges as submits arrive, so most of its merges hold one.
  if (diffs.size() == 1) return in_base_order(*diffs[0], base);
  Pass pass{hierarchy_,
            *workspace_,
            timings_,
            base,
            diffs,
            t,
            canonical_order(diffs, std::span<const std::uint64_t>(keys.data(), diffs.size())),
            frame};
  return pass.run();
}

Diff Merger::Pass::run() {
  Diff merged;
  merged.vertex_count = vertex_count;
  if (users == 0) {
    for (const Channel& c : base.channels) merged.channels.push_back({c.desc, {}});
    return merged;
  }
  if (ws.lookups.size() < users) ws.lookups.resize(users);
  const auto t0 = Clock::now();
  prepare_lookups();
  if (t.isometry) {
    isometry_positions(merged.positions, t0);
  } else {
    with_translation_ops(
        t.blend, [&](auto ops) { translation_positions<decltype(ops)>(merged.positions, t0); });
  }
  for (const Channel& channel : base.channels) merged.channels.push_back(merge_channel(channel));
  return merged;
}

/// Per node visited: its value and its parent links (index + weight); its bit is noise.
template <class UserPyramids, class MergedPyramid>
void Merger::Pass::count_work(const UserPyramids& user_pyramids,
                              const MergedPyramid& merged_pyramid, std::size_t levels,
                              std::size_t value_bytes) {
  const std::size_t per_node = value_bytes + hierarchy.stride() * 8;
  auto add = [&](const auto& pyramid) {
    for (std::size_t i = 0; i < levels; ++i) {
      timings.nodes_visited += pyramid.levels[i].list.size();
      timings.bytes_touched += pyramid.levels[i].list.size() * per_node;
    }
  };
  for (std::uint32_t u = 0; u < users; ++u) add(user_pyramids[u]);
  add(merged_pyramid);
  for (const Diff* d : diffs) timings.bytes_touched += d->positions.indices.size() * 16;
}

/// Edited-position lookups per diff, sized for the base (each filled in its diff's own task).
void Merger::Pass::prepare_lookups() {
  for (std::uint32_t u = 0; u < users; ++u) {
    Lookup& lk = ws.lookups[u];
    if (lk.slot.size() < vertex_count) lk.slot.resize(vertex_count);
    lk.changed.resize(vertex_count);
  }
}

// ---- positions as isometries ----------------------------------------------------------

void Merger::Pass::isometry_positions(AttributeDiff& out, Clock::time_point t0) {
  isometries_and_averages(t0);
  t0 = Clock::now();
  const std::size_t n_changed = ws.dq_merged.levels[0].list.size();
  const std::size_t chunks = (n_changed + kBlendGrain - 1) / kBlendGrain;
  blend_isometries(chunks);
  timings.blend_ms += ms_since(t0);
  count_work(ws.dq_users, ws.dq_merged, level_count, sizeof(DualQuat));
  t0 = Clock::now();
  list_moved_positions(out, chunks);
  timings.apply_ms += ms_since(t0);
}

/// One region, one task per diff (its lookup, isometries and averages: independent of the
/// other diffs), plus one task, listed last so that the thread that finishes first takes it,
/// for the vertices the result needs (the union of the changed ones): it writes only the
/// merged pyramid's level 0, so no barrier between.
void Merger::Pass::isometries_and_averages(Clock::time_point t0) {
  if (ws.dq_users.size() < users) ws.dq_users.resize(users);
  for (std::uint32_t u = 0; u < users; ++u) ws.dq_users[u].begin(hierarchy, level_count);
  ws.dq_merged.begin(hierarchy, level_count);
  double iso_task_ms[max_merge_diffs] = {};
  ws.pool.run(users + 1, [&](std::size_t u) {
    if (u == users) {
      mark_union(
          ws.dq_merged.levels[0],
          users, [&](std::size_t j) -> const auto& { return positions_of(j).indices; });
      return;
    }
    iso_task_ms[u] = diff_isometries(u);
    // The transport averages only the diffs that carry another (carrying_fields()).
    if (!t.transport) decompose<DqOps>(links, level_count, ws.dq_users[u]);
  });
  // The transport reads each diff's averages, never a blend of them.
  if (!t.transport)
    mark_coarse_union<DualQuat>(std::span(ws.dq_users.data(), users), level_count, ws.dq_merged);
  // The region's time split: isometries = the longest diff's isometry part, the rest
  // (decomposition and its imbalance) to decompose.
  const double region_ms = ms_since(t0);
  const double iso_ms = *std::max_element(iso_task_ms, iso_task_ms + users);
  timings.isometry_ms += std::min(iso_ms, region_ms);
  timings.decompose_ms += std::max(0.0, region_ms - iso_ms);
}

/// Diff u's lookup and per-vertex isometries into its pyramid's level 0; returns the time
/// it took.
double Merger::Pass::diff_isometries(std::size_t u) {
  const auto task_t0 = Clock::now();
  Lookup& lk = ws.lookups[u];
  const AttributeDiff& pd = positions_of(u);
  for (std::uint32_t i = 0; i < pd.indices.size(); ++i) {
    lk.slot[pd.indices[i]] = i;
    lk.changed.insert(pd.indices[i]);
  }
  lk.isometry.resize(vertex_count, base.face_count());
  auto& level0 = ws.dq_users[u].levels[0];
  auto edited = [&lk, &pd, this](std::uint32_t v) -> Vec3f {
    if (!lk.changed.test(v)) return base.positions[v];
    const float* p = pd.values.data() + 3 * std::size_t{lk.slot[v]};
    return {p[0], p[1], p[2]};
  };
  detail::compute_vertex_isometries(
      hierarchy.topology(), base.positions, pd.indices, edited, lk.isometry,
      [&level0](std::uint32_t v, const DualQuat& q) {
        level0.values[v] = q;
        level0.set(v);
      },
      lk.touched, local);
  if (!t.transport) lk.changed.clear(pd.indices);  // the transport reads it
  level0.list.assign(lk.touched.begin(), lk.touched.end());
  return ms_since(task_t0);
}

/// Moved positions of the changed vertices (the union, increasing) and, per chunk, how many
/// differ from the base: by the frame transport, or computed by the node blend as soon as
/// each chunk of level 0 is done.
void Merger::Pass::blend_isometries(std::size_t chunks) {
  const std::size_t n_changed = ws.dq_merged.levels[0].list.size();
  if (ws.moved.size() < n_changed) ws.moved.resize(n_changed);
  if (ws.chunk_offset.size() < chunks + 1) ws.chunk_offset.resize(chunks + 1);
  if (t.transport) {
    transport_positions();
    return;
  }
  const std::function<void(std::size_t, std::size_t)> move_vertices = [&](std::size_t begin,
                                                                          std::size_t end) {
    const auto& changed_union = ws.dq_merged.levels[0].list;
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t v = changed_union[i];
      ws.moved[i] =
          from_local(ws.dq_merged.levels[0].val(v).apply(local.to_local(base.positions[v])));
    }
    count_kept(begin, end);
  };
  blend_and_reconstruct<DqOps>(links, level_count, std::span(ws.dq_users.data(), users),
                               ws.dq_merged, t.node_blend, ws.pool, &move_vertices);
}

/// `full`: each diff's displacements carried in the frames the others give the surface.
void Merger::Pass::transport_positions() {
  const auto& changed_union = ws.dq_merged.levels[0].list;
  const std::size_t n_changed = changed_union.size();
  ws.transport_inputs.resize(users);
  for (std::uint32_t u = 0; u < users; ++u) {
    const auto& level0 = ws.dq_users[u].levels[0];
    ws.transport_inputs[u] = {level0.values.data(), level0.bits.data(), ws.lookups[u].slot.data(),
                              ws.lookups[u].changed.words.data(), positions_of(u).values.data()};
  }
  const detail::CarryingFields carriers =
      [&](std::span<const bool> carries, std::span<const std::uint8_t> reads_level,
          const std::function<void()>& beside) { carrying_fields(carries, reads_level, beside); };
  detail::transport_positions(
      hierarchy.topology(), base.positions, changed_union, ws.transport_inputs, t.same_once,
      t.hedge ? jacobian_samples() : detail::JacobianSamples{}, ws.transport, ws.pool, kBlendGrain,
      carriers, std::span(ws.moved.data(), n_changed));
  for (std::uint32_t u = 0; u < users; ++u) ws.lookups[u].changed.clear(positions_of(u).indices);
  repair_folds(changed_union, std::span(ws.moved.data(), n_changed));
  ws.pool.for_chunks(n_changed, kBlendGrain,
                     [&](std::size_t begin, std::size_t end) { count_kept(begin, end); });
}

/// Where the carriers' regional Jacobians are fitted: the representatives of the finest
/// hierarchy level of at most kJacobianSamples nodes (about as many samples whatever the
/// mesh's resolution), within kJacobianRadius of the samples' bounding box diagonal.
detail::JacobianSamples Merger::Pass::jacobian_samples() const {
  const auto levels = hierarchy.levels();
  std::size_t level = 0;
  while (level + 1 < levels.size() && levels[level].node_count > kJacobianSamples) ++level;
  const std::span<const std::uint32_t> samples = levels[level].representative;
  if (samples.empty()) return {};
  Vec3f lo = base.positions[samples[0]], hi = lo;
  for (const std::uint32_t v : samples) {
    const Vec3f& p = base.positions[v];
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  return {samples, kJacobianRadius * length(sub(widen(hi), widen(lo)))};
}

/// The carrying levels of each diff that carries another: one task per such diff and level,
/// each writing only its own field and scratch; `beside` runs as one more task beside the
/// averages (detail::CarryingFields).
void Merger::Pass::carrying_fields(std::span<const bool> carries,
                                   std::span<const std::uint8_t> reads_level,
                                   const std::function<void()>& beside) {
  const std::size_t levels = level_count - 1;
  if (levels == 0) {  // a hierarchy of one level: the vertices' own rotations
    beside();
    return;
  }
  if (ws.carrying.size() < std::size_t{users} * detail::kCarryLevels)
    ws.carrying.resize(std::size_t{users} * detail::kCarryLevels);
  std::array<std::uint32_t, max_merge_diffs> carrier{};
  std::size_t count = 0;
  for (std::uint32_t u = 0; u < users; ++u)
    if (carries[u]) carrier[count++] = u;
  ws.pool.run(count + 1, [&](std::size_t k) {
    if (k == count) return beside();
    decompose<DqOps>(links, level_count, ws.dq_users[carrier[k]]);
  });
  const std::size_t tasks = count * levels;
  if (ws.carrying_scratch.size() < tasks) ws.carrying_scratch.resize(tasks);
  ws.pool.run(tasks, [&](std::size_t task) {
    carrying_rotations(carrier[task / levels], task % levels + 1, reads_level,
                       ws.carrying_scratch[task]);
  });
  for (std::size_t k = 0; k < count; ++k) {
    detail::TransportInput& in = ws.transport_inputs[carrier[k]];
    // Past the hierarchy's coarsest level, the coarsest average.
    for (std::size_t l = 1; l < detail::kCarryLevels; ++l)
      in.smoothed[l] = ws.carrying[carrier[k] * detail::kCarryLevels + std::min(l, levels)].data();
  }
}

/// Diff u's rotations averaged over level `top` (decompose()) and interpolated back down the
/// parent links to the vertices it rotates that read that level (the last level also serves
/// the levels past the hierarchy): a node's value is the weighted average of its parents'
/// offsets from the identity, normalised (absent parents are the identity).
void Merger::Pass::carrying_rotations(std::size_t u, std::size_t top,
                                      std::span<const std::uint8_t> reads_level,
                                      CarryingScratch& scratch) {
  const SparsePyramid<DualQuat>& pyramid = ws.dq_users[u];
  std::vector<Quat>& out = ws.carrying[u * detail::kCarryLevels + top];
  if (out.size() < vertex_count) out.resize(vertex_count);
  list_carrying_needs(pyramid, top, reads_level, scratch);
  for (std::size_t l = top; l-- > 0;) {
    const ParentLinks::Level fine = links.level(l);
    const LevelView<DualQuat> coarse = LevelView<DualQuat>::of(pyramid.levels[l + 1]);
    const Quat* above = l + 1 < top ? scratch.rotation[l + 1].data() : nullptr;
    Quat* here = l == 0 ? out.data() : scratch.rotation[l].data();
    for (const std::uint32_t c : scratch.need[l]) {
      const ParentLinks::Level::Row row = fine.row(c);
      float w = 0, x = 0, y = 0, z = 0, total = 0;
      for (std::uint32_t k = 0; k < row.count; ++k) {
        const std::uint32_t p = row.parents[k];
        const float weight = row.weights[k];
        total += weight;
        if (!coarse.has(p)) continue;
        const Quat q = above ? above[p] : coarse.values[p].real;
        w += weight * (q.w - 1), x += weight * q.x, y += weight * q.y, z += weight * q.z;
      }
      const float scale = total > 0 ? 1 / total : 0.f;
      const Quat q{1 + w * scale, x * scale, y * scale, z * scale};
      const float length = std::sqrt(dot(q, q));
      here[c] = length > 0 ? (1 / length) * q : Quat{};
    }
  }
  for (std::size_t l = 1; l < top; ++l)
    for (const std::uint32_t c : scratch.need[l]) scratch.marked[l][c] = 0;
}

/// The nodes carrying_rotations computes for level `top`: at level 0 the vertices that read
/// it, at each level between the parents of the level below's (present in the pyramid). A
/// node's value depends only on its parents', so the readers' values are those of the whole
/// levels, at a fraction of the work where few vertices are carried.
void Merger::Pass::list_carrying_needs(const SparsePyramid<DualQuat>& pyramid, std::size_t top,
                                       std::span<const std::uint8_t> reads_level,
                                       CarryingScratch& scratch) const {
  const std::uint32_t reads = top + 1 < level_count ? 1u << top : ~0u << top;
  if (scratch.need.size() < top) {
    scratch.rotation.resize(top);
    scratch.need.resize(top);
    scratch.marked.resize(top);
  }
  for (std::size_t l = 1; l < top; ++l) {
    const std::size_t nodes = hierarchy.levels()[l].node_count;
    if (scratch.rotation[l].size() < nodes) scratch.rotation[l].resize(nodes);
    if (scratch.marked[l].size() < nodes) scratch.marked[l].resize(nodes, 0);
  }
  scratch.need[0].clear();
  for (const std::uint32_t c : pyramid.levels[0].list)
    if ((reads_level[c] & reads) != 0) scratch.need[0].push_back(c);
  for (std::size_t l = 0; l + 1 < top; ++l) {
    const ParentLinks::Level fine = links.level(l);
    const LevelView<DualQuat> coarse = LevelView<DualQuat>::of(pyramid.levels[l + 1]);
    std::vector<std::uint32_t>& next = scratch.need[l + 1];
    std::vector<std::uint8_t>& marked = scratch.marked[l + 1];
    next.clear();
    for (const std::uint32_t c : scratch.need[l]) {
      const ParentLinks::Level::Row row = fine.row(c);
      for (std::uint32_t k = 0; k < row.count; ++k) {
        const std::uint32_t p = row.parents[k];
        if (coarse.has(p) && marked[p] == 0) marked[p] = 1, next.push_back(p);
      }
    }
  }
}

void Merger::Pass::repair_folds(std::span<const std::uint32_t> changed, std::span<Vec3f> moved) {
  const auto t0 = Clock::now();
  std::array<const Diff*, max_merge_diffs> ordered{};
  for (std::uint32_t u = 0; u < users; ++u) ordered[u] = diffs[order[u]];
  timings.new_folds_repaired += detail::repair_new_folds(
      hierarchy.topology(), base.positions, changed, std::span(ordered.data(), users),
      ws.transport.seam_of, moved, ws.fold_repair, ws.pool, kBlendGrain, ws.transport.weight,
      ws.transport.sole, ws.transport.framed);
  timings.fold_repair_ms += ms_since(t0);
}

/// How many of the chunk's moved positions differ from the base (at its slot + 1, for the
/// prefix sum).
void Merger::Pass::count_kept(std::size_t begin, std::size_t end) {
  const auto& changed_union = ws.dq_merged.levels[0].list;
  std::size_t kept = 0;
  for (std::size_t i = begin; i < end; ++i)
    kept += !(ws.moved[i] == base.positions[changed_union[i]]);
  ws.chunk_offset[begin / kBlendGrain + 1] = kept;
}

/// Each chunk lists its moved positions that differ from the base at its offset (the prefix
/// sum of the counts): the same order as one serial pass, every write disjoint.
void Merger::Pass::list_moved_positions(AttributeDiff& out, std::size_t chunks) {
  const auto& changed_union = ws.dq_merged.levels[0].list;
  ws.chunk_offset[0] = 0;
  for (std::size_t c = 0; c < chunks; ++c) ws.chunk_offset[c + 1] += ws.chunk_offset[c];
  const std::size_t kept_total = ws.chunk_offset[chunks];
  out.indices.resize(kept_total);
  out.values.resize(3 * kept_total);
  ws.pool.for_chunks(changed_union.size(), kBlendGrain, [&](std::size_t begin, std::size_t end) {
    std::size_t at = ws.chunk_offset[begin / kBlendGrain];
    for (std::size_t i = begin; i < end; ++i) {
      const std::uint32_t v = changed_union[i];
      const Vec3f& p = ws.moved[i];
      if (!(p == base.positions[v])) {
        out.indices[at] = v;
        float* o = out.values.data() + 3 * at;
        o[0] = p.x;
        o[1] = p.y;
        o[2] = p.z;
        ++at;
      }
    }
  });
}

// ---- positions as translations --------------------------------------------------------

template <class Ops>
void Merger::Pass::translation_positions(AttributeDiff& out, Clock::time_point t0) {
  using Value = typename Ops::Value;
  if (ws.vec_users.size() < users) ws.vec_users.resize(users);
  for (std::uint32_t u = 0; u < users; ++u) ws.vec_users[u].begin(hierarchy, level_count);
  ws.vec_merged.begin(hierarchy, level_count);
  for (std::uint32_t u = 0; u < users; ++u) {
    auto& level0 = ws.vec_users[u].levels[0];
    const AttributeDiff& pd = positions_of(u);
    for (std::uint32_t i = 0; i < pd.indices.size(); ++i) {
      const std::uint32_t v = pd.indices[i];
      const float* e = pd.values.data() + 3 * std::size_t{i};
      const Vec3f a = local.to_local(base.positions[v]);
      const Vec3f b = local.to_local({e[0], e[1], e[2]});
      level0.mark(v);
      level0.val(v) = Value{{b.x - a.x, b.y - a.y, b.z - a.z, 0}};
    }
  }
  timings.isometry_ms += ms_since(t0);
  t0 = Clock::now();
  ws.pool.run(users, [&](std::size_t u) { decompose<Ops>(links, level_count, ws.vec_users[u]); });
  timings.decompose_ms += ms_since(t0);
  t0 = Clock::now();
  auto& merged = ws.vec_merged;
  mark_sorted_union(
      merged.levels[0],
      users, [&](std::size_t u) -> const auto& { return positions_of(u).indices; }, ws.sole);
  mark_coarse_union<Value>(std::span(ws.vec_users.data(), users), level_count, merged);
  blend_and_reconstruct<Ops>(links, level_count, std::span(ws.vec_users.data(), users), merged,
                             t.node_blend, ws.pool);
  timings.blend_ms += ms_since(t0);
  count_work(ws.vec_users, ws.vec_merged, level_count, sizeof(Vec4));
  t0 = Clock::now();
  list_translated_positions<Ops>(out);
  timings.apply_ms += ms_since(t0);
}

/// The merged translations applied to the base, listed where they change it.
template <class Ops>
void Merger::Pass::list_translated_positions(AttributeDiff& out) const {
  const auto& level0 = ws.vec_merged.levels[0];
  const auto& list = level0.list;  // increasing
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::uint32_t v = list[i];
    const typename Ops::Value& d = level0.val(v);
    const Vec3f a = local.to_local(base.positions[v]);
    const Vec3f p = from_local({a.x + d.v[0], a.y + d.v[1], a.z + d.v[2]});
    if (!(p == base.positions[v])) {
      out.indices.push_back(v);
      out.values.insert(out.values.end(), {p.x, p.y, p.z});
    }
  }
}

// ---- channels: translations in each channel's linear space ----------------------------

ChannelDiff Merger::Pass::merge_channel(const Channel& channel) {
  ChannelDiff out_diff{channel.desc, {}};
  const auto t0 = Clock::now();
  const std::size_t channel_levels = t.channels_per_vertex ? 1 : level_count;
  with_translation_ops(t.blend, [&](auto ops) {
    using Ops = decltype(ops);
    using Value = typename Ops::Value;
    std::array<const std::vector<std::uint32_t>*, max_merge_diffs> changed_lists{};
    std::array<const float*, max_merge_diffs> changed_values{};
    channel_translations<Ops>(channel, channel_levels, changed_lists, changed_values);
    auto& merged = ws.vec_merged;
    mark_sorted_union(
        merged.levels[0], users, [&](std::size_t u) -> const auto& { return *changed_lists[u]; },
        ws.sole);
    ws.pool.run(users,
                [&](std::size_t u) { decompose<Ops>(links, channel_levels, ws.vec_users[u]); });
    mark_coarse_union<Value>(std::span(ws.vec_users.data(), users), channel_levels, merged);
    // Where two different colours overlap the result is clamped to the channel's range.
    blend_and_reconstruct<Ops>(links, channel_levels, std::span(ws.vec_users.data(), users), merged,
                               t.node_blend, ws.pool);
    list_channel_result<Ops>(channel, channel_levels, changed_values, out_diff);
  });
  timings.blend_ms += ms_since(t0);
  return out_diff;
}

/// Each diff's changes of `channel` as translations in its linear space, on its pyramid's
/// level 0; `changed_lists` / `changed_values` get each diff's changed vertices and values
/// (an empty list where it does not change the channel).
template <class Ops>
void Merger::Pass::channel_translations(const Channel& channel, std::size_t channel_levels,
                                        std::span<const std::vector<std::uint32_t>*> changed_lists,
                                        std::span<const float*> changed_values) {
  using Value = typename Ops::Value;
  const std::uint32_t width = channel.desc.width;
  if (ws.vec_users.size() < users) ws.vec_users.resize(users);
  for (std::uint32_t u = 0; u < users; ++u) ws.vec_users[u].begin(hierarchy, channel_levels);
  ws.vec_merged.begin(hierarchy, channel_levels);
  for (std::uint32_t u = 0; u < users; ++u) {
    auto& level0 = ws.vec_users[u].levels[0];
    changed_lists[u] = &kNoChanges;
    for (const ChannelDiff& cd : diffs[order[u]]->channels) {
      if (cd.desc.name != channel.desc.name) continue;
      changed_lists[u] = &cd.change.indices;
      changed_values[u] = cd.change.values.data();
      for (std::uint32_t i = 0; i < cd.change.indices.size(); ++i) {
        const std::uint32_t v = cd.change.indices[i];
        Value d;
        for (std::uint32_t k = 0; k < width; ++k) {
          const float b =
              to_linear(channel.desc.linearisation, channel.values[std::size_t{v} * width + k]);
          const float e =
              to_linear(channel.desc.linearisation, cd.change.values[std::size_t{i} * width + k]);
          d.v[k] = e - b;
        }
        level0.mark(v);
        level0.val(v) = d;
      }
    }
  }
}

/// The merged channel values, listed where they change the base: one painter's value exactly
/// where it alone changed a vertex (per vertex; average keeps its definition: half of it),
/// else the base plus the merged translation, clamped to the channel's range.
template <class Ops>
void Merger::Pass::list_channel_result(const Channel& channel, std::size_t channel_levels,
                                       std::span<const float* const> changed_values,
                                       ChannelDiff& out_diff) const {
  const std::uint32_t width = channel.desc.width;
  const auto& level0 = ws.vec_merged.levels[0];
  const auto& list = level0.list;  // increasing
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::uint32_t v = list[i];
    const typename Ops::Value& d = level0.val(v);
    bool changed = false;
    float result[4];
    const SoleChange sc = ws.sole[i];
    for (std::uint32_t k = 0; k < width; ++k) {
      const float b = channel.values[std::size_t{v} * width + k];
      if (sc.owner != kNoOwner && channel_levels == 1 && t.blend != TranslationBlend::average) {
        result[k] = changed_values[sc.owner][std::size_t{sc.entry} * width + k];
        changed |= std::memcmp(&result[k], &b, sizeof(float)) != 0;
        continue;
      }
      result[k] = std::clamp(from_linear(channel.desc.linearisation,
                                         to_linear(channel.desc.linearisation, b) + d.v[k]),
                             channel.desc.min_value, channel.desc.max_value);
      changed |= std::memcmp(&result[k], &b, sizeof(float)) != 0;
    }
    if (changed) {
      out_diff.change.indices.push_back(v);
      out_diff.change.values.insert(out_diff.change.values.end(), result, result + width);
    }
  }
}

MergeFrame MergeFrame::fit(std::span<const Vec3f> positions) {
  MergeFrame f;
  if (positions.empty()) return f;
  Vec3f lo = positions[0], hi = positions[0];
  for (const Vec3f& p : positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  f.center = {0.5f * (lo.x + hi.x), 0.5f * (lo.y + hi.y), 0.5f * (lo.z + hi.z)};
  const float dx = hi.x - lo.x, dy = hi.y - lo.y, dz = hi.z - lo.z;
  const float diag = std::sqrt(dx * dx + dy * dy + dz * dz);
  f.scale = diag > 0 && std::isfinite(diag) ? diag : 1.f;
  return f;
}

std::string_view to_string(MergeMethod method) {
  switch (method) {
    case MergeMethod::full:
      return "full";
    case MergeMethod::single_parent:
      return "single-parent";
    case MergeMethod::single_level_isometry:
      return "single-level-isometry";
    case MergeMethod::multiscale_translation:
      return "multiscale-translation";
    case MergeMethod::weighted_translation:
      return "weighted-translation";
    case MergeMethod::average:
      return "average";
    case MergeMethod::sum:
      return "sum";
    case MergeMethod::paper_blend:
      return "paper-blend";
    case MergeMethod::hierarchy_blend:
      return "hierarchy-blend";
    case MergeMethod::frame_transport:
      return "frame-transport";
  }
  return "unknown";
}

MergeMethod merge_method_from_string(std::string_view name) {
  for (MergeMethod m : kMethods)
    if (to_string(m) == name) return m;
  std::string valid;
  for (MergeMethod m : kMethods) valid += (valid.empty() ? "" : ", ") + std::string(to_string(m));
  throw InvalidInput("unknown merge method '" + std::string(name) + "' (valid: " + valid + ")");
}

std::span<const MergeMethod> all_merge_methods() {
  return kMethods;
}

Mesh merge_meshes(const Mesh& base, std::span<const Mesh> edits, MergeMethod method,
                  std::uint32_t max_parents) {
  validate(base, "base");
  std::vector<Diff> diffs;
  diffs.reserve(edits.size());
  for (std::size_t i = 0; i < edits.size(); ++i) {
    validate(edits[i], "edit " + std::to_string(i + 1));
    diffs.push_back(capture_diff(base, edits[i]));
  }
  HierarchyOptions options;
  options.max_parents = max_parents;
  const Hierarchy hierarchy = Hierarchy::build(base, options);
  Merger merger(hierarchy);
  Mesh result = base;
  apply_diff(merger.merge(base, diffs, method), result);
  return result;
}

}  // namespace csculpt
