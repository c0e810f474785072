// Internal: the merge's hottest loop, the intent blend of dual quaternions at the nodes of
// one hierarchy level (merge.cpp: blend_and_reconstruct with DqOps and NodeBlend::intent),
// written once over the register width and compiled twice: SSE2 (4 nodes per register, in
// simd_dispatch.cpp) and AVX2 (8 nodes, in blend_avx2.cpp, used when the CPU has it). Every lane
// performs the scalar code's IEEE operations in the same order, so both give bit-identical
// merges and peers with different CPUs agree (tests/sdk/simd/test_simd_dispatch.cpp).
#pragma once

#include <cstddef>
#include <cstdint>

#include "csculpt/dual_quat.h"
#include "csculpt/merge.h"

namespace csculpt::detail {

/// Largest number of diffs merged at once (the per-node scratch lives on the stack): the
/// SDK's public limit.
constexpr std::size_t kMaxDiffs = max_merge_diffs;

/// One level of the blend as plain arrays: the interface between merge.cpp and each
/// instruction set's kernel (an aggregate with no functions, so nothing of it is compiled
/// per instruction set).
struct BlendLevelArgs {
  const std::uint32_t* list = nullptr;  ///< the nodes to compute
  // parent links of this level's nodes (ParentLinks::Level)
  const std::uint32_t* parent = nullptr;
  const float* weight = nullptr;
  const std::uint8_t* parent_count = nullptr;
  std::size_t stride = 0;
  bool tree = false;         ///< only the first parent, weight 1 (single-parent variant)
  bool has_parents = false;  ///< false at the coarsest level
  std::size_t users = 0;
  /// every diff's values and bitmap at this level ...
  const DualQuat* here_values[kMaxDiffs] = {};
  const std::uint64_t* here_bits[kMaxDiffs] = {};
  /// ... and at the next coarser one, the merged result's last
  const DualQuat* coarse_values[kMaxDiffs + 1] = {};
  const std::uint64_t* coarse_bits[kMaxDiffs + 1] = {};
  DualQuat* out_values = nullptr;
};

using BlendChunkFn = void (*)(const BlendLevelArgs&, std::size_t begin, std::size_t end);

/// The AVX2 kernel (blend_avx2.cpp); null where it is not built.
BlendChunkFn blend_chunk_avx2();
/// The kernel merges use (simd_dispatch.cpp): AVX2 where built and supported, unless the
/// environment says CSCULPT_SIMD=sse2 or set_simd_baseline_only(true) was called.
BlendChunkFn blend_chunk_kernel();
/// For tests: force the SSE2 kernel (true) or return to the automatic choice (false).
void set_simd_baseline_only(bool on);

}  // namespace csculpt::detail

#if defined(__SSE2__)

#include <algorithm>

#include "dq_soa.h"
#include "simd_isa.h"

// Register types as template arguments: GCC notes that it drops their may_alias attribute
// there, which changes nothing for values held in registers and arrays of them.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wignored-attributes"
namespace csculpt::detail {
CSCULPT_ISA_BEGIN

/// Array-of-structures access for the SSE2 width: a dual quaternion in two registers.
struct IsaSse2 {
  using V = __m128;
  using A = DQv;
  static A zero() { return dq_zero(); }
  static A identity() { return dq_identity(); }
  static A load(const DualQuat& q) { return dq_load(q); }
  static void store(DualQuat& q, const A& a) { dq_store(q, a); }
  static void add_scaled_offset(A& acc, float w, const A& q) { dq_add_scaled_offset(acc, w, q); }
};
#if defined(__AVX2__)
/// ... and for AVX2: a dual quaternion in one register.
struct IsaAvx2 {
  using V = __m256;
  using A = DQy;
  static A zero() { return dqy_zero(); }
  static A identity() { return dqy_identity(); }
  static A load(const DualQuat& q) { return dqy_load(q); }
  static void store(DualQuat& q, const A& a) { dqy_store(q, a); }
  static void add_scaled_offset(A& acc, float w, const A& q) { dqy_add_scaled_offset(acc, w, q); }
};
#endif

inline bool bit_set(const std::uint64_t* bits, std::uint32_t node) {
  return (bits[node >> 6] >> (node & 63) & 1) != 0;
}

/// The intent blend for the nodes list[begin, end) of one level, N nodes at a time in
/// structure-of-arrays registers: the parent sums are gathered per node, the rest of the
/// arithmetic runs one node per lane.
template <class Isa>
void blend_chunk_dq_intent(const BlendLevelArgs& a, std::size_t begin, std::size_t end) {
  using V = typename Isa::V;
  using A = typename Isa::A;
  using L = Lanes<V>;
  constexpr std::size_t N = static_cast<std::size_t>(L::kCount);
  const std::size_t n_users = a.users;
  const std::uint32_t* list = a.list;
  const V zero = L::zero();
  const V one = L::set1(1.f);
  A acc[kMaxDiffs + 1][N];
  A q[kMaxDiffs][N];
  std::uint32_t any_bits[kMaxDiffs + 1];   // lanes with a parent that differs from the identity
  std::uint32_t here_bits[kMaxDiffs + 1];  // lanes whose node differs from the identity
  int active_bits[kMaxDiffs];              // lanes whose residual differs from the identity
  DQN<V> res[kMaxDiffs];
  V mag[kMaxDiffs];
  static constexpr float kOne[1] = {1.f};
  constexpr std::size_t kAhead = 8;  // nodes
  for (std::size_t g = begin; g < end; g += N) {
    const std::size_t lanes = std::min<std::size_t>(N, end - g);
    for (std::size_t i = g + kAhead; i < std::min(end, g + kAhead + N); ++i)
      for (std::size_t j = 0; j < n_users; ++j) __builtin_prefetch(&a.here_values[j][list[i]]);
    alignas(32) float weight_total[N];
    for (std::size_t j = 0; j <= n_users; ++j) any_bits[j] = here_bits[j] = 0;
    for (std::size_t lane = 0; lane < N; ++lane) {
      // lanes past the end repeat the first node; their results are not stored
      const std::uint32_t c = list[g + (lane < lanes ? lane : 0)];
      for (std::size_t j = 0; j <= n_users; ++j) acc[j][lane] = Isa::zero();
      float wt = 0;
      if (a.has_parents) {
        const std::size_t row = std::size_t{c} * a.stride;
        const std::uint32_t* parents = a.parent + row;
        const float* weights = a.tree ? kOne : a.weight + row;
        const std::uint32_t count = a.tree ? 1u : a.parent_count[c];
        for (std::uint32_t k = 0; k < count; ++k) {
          const std::uint32_t p = parents[k];
          const float w = weights[k];
          wt += w;
          for (std::size_t j = 0; j <= n_users; ++j) {
            if (bit_set(a.coarse_bits[j], p)) {
              Isa::add_scaled_offset(acc[j][lane], w, Isa::load(a.coarse_values[j][p]));
              any_bits[j] |= 1u << lane;
            }
          }
        }
      }
      weight_total[lane] = wt;
      for (std::size_t j = 0; j < n_users; ++j) {
        if (bit_set(a.here_bits[j], c)) {
          q[j][lane] = Isa::load(a.here_values[j][c]);
          here_bits[j] |= 1u << lane;
        } else {
          q[j][lane] = Isa::identity();
        }
      }
    }
    const V wt_lanes = L::load(weight_total);
    // finish_average: real w += total weight, normalised, canonical
    auto parent_blend = [&](std::size_t j) {
      DQN<V> s = dqn_from(acc[j]);
      s.c[0] = v_add(s.c[0], wt_lanes);
      return dqn_canonical(dqn_normalized(s));
    };
    for (std::size_t j = 0; j < n_users; ++j) {
      if ((any_bits[j] | here_bits[j]) == 0) {  // the identity in every lane: magnitude 0
        res[j] = dqn_identity<V>();
        mag[j] = zero;
        active_bits[j] = 0;
        continue;
      }
      const DQN<V> qj = dqn_from(q[j]);
      if (any_bits[j] != 0) {
        const DQN<V> r = dqn_canonical(dqn_mul(dqn_inverse(parent_blend(j)), qj));
        res[j] = dqn_select(L::mask(any_bits[j]), r, qj);
      } else {
        res[j] = qj;
      }
      // residuals and stored values are canonical already
      mag[j] = dqn_magnitude_of_canonical(res[j]);
      active_bits[j] = v_bits(v_gt(mag[j], zero));
    }
    // intent: acc = sum_j c_j (r_j - 1), c_j = m_j / sum_k s_jk m_k over active j, k
    DQN<V> sum;
    for (V& x : sum.c) x = zero;
    V magnitude_sum = zero;
    for (std::size_t j = 0; j < n_users; ++j) {
      if (active_bits[j] == 0) continue;
      const V active_j = v_gt(mag[j], zero);
      V same = zero;
      for (std::size_t k = 0; k < n_users; ++k) {
        if (active_bits[k] == 0) continue;  // it would add + 0 in every lane
        const V active_k = v_gt(mag[k], zero);
        V term;
        if (k == j) {
          term = mag[k];  // closeness 1: s m_k = m_k exactly
        } else {
          const V larger = v_max(mag[k], mag[j]);  // std::max(m_j, m_k)
          const V closeness =                      // std::max(0.f, x)
              v_max(v_sub(one, v_div(dqn_distance(res[j], res[k]), larger)), zero);
          term = v_mul(v_mul(closeness, closeness), mag[k]);
        }
        same = v_add(same, v_and(active_k, term));  // + 0 where inactive: exact
      }
      const V w = v_div(mag[j], same);
      sum.c[0] = v_add(sum.c[0], v_and(active_j, v_mul(w, v_sub(res[j].c[0], one))));
#pragma GCC unroll 8
      for (int i = 1; i < 8; ++i)
        sum.c[i] = v_add(sum.c[i], v_and(active_j, v_mul(w, res[j].c[i])));
      magnitude_sum = v_add(magnitude_sum, v_and(active_j, mag[j]));
    }
    sum.c[0] = v_add(sum.c[0], one);
    DQN<V> blended = dqn_select(v_gt(magnitude_sum, zero), dqn_canonical(dqn_normalized(sum)),
                                dqn_identity<V>());
    if (any_bits[n_users] != 0)
      blended = dqn_select(L::mask(any_bits[n_users]),
                           dqn_canonical(dqn_mul(parent_blend(n_users), blended)), blended);
    A out[N];
    dqn_to(blended, out);
    for (std::size_t lane = 0; lane < lanes; ++lane)
      Isa::store(a.out_values[list[g + lane]], out[lane]);
  }
}

CSCULPT_ISA_END
}  // namespace csculpt::detail

#pragma GCC diagnostic pop

#endif  // __SSE2__
