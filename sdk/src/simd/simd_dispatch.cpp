// Which build of the merge's SIMD kernels runs: AVX2 (blend_avx2.cpp) where it is built
// and the CPU and OS support it, else the SSE2 baseline compiled here. Both give the same
// bits (tests/sdk/simd/test_simd_dispatch.cpp), so peers on different CPUs merge alike; the
// environment variable CSCULPT_SIMD=sse2 forces the baseline, e.g. to compare speeds.
#include <atomic>
#include <cstdlib>
#include <string_view>

#include "blend_kernel.h"
#include "face_rotation_lanes.h"

namespace csculpt::detail {
namespace {

std::atomic<bool> g_baseline_only{false};

bool avx2_usable() {
  static const bool usable = [] {
#if defined(__x86_64__) || defined(__i386__)
    if (!__builtin_cpu_supports("avx2")) return false;
#else
    return false;
#endif
    const char* env = std::getenv("CSCULPT_SIMD");
    return env == nullptr || std::string_view(env) != "sse2";
  }();
  return usable && !g_baseline_only.load();
}

#if defined(__SSE2__)
void blend_chunk_sse2(const BlendLevelArgs& a, std::size_t begin, std::size_t end) {
  blend_chunk_dq_intent<IsaSse2>(a, begin, end);
}
std::size_t face_rotations_sse2(const FaceRotationArgs& a) {
  return face_rotations_lanes<__m128>(a);
}
void vertex_finish_sse2(const VertexFinishArgs& a) {
  vertex_finish_lanes<__m128>(a);
}
#endif

/// The AVX2 build where it exists and may run, else the baseline (null without SSE2).
template <class Fn>
Fn choose(Fn avx2, Fn baseline) {
  return avx2 != nullptr && avx2_usable() ? avx2 : baseline;
}

}  // namespace

void set_simd_baseline_only(bool on) {
  g_baseline_only.store(on);
}

#if defined(__SSE2__)
BlendChunkFn blend_chunk_kernel() {
  return choose<BlendChunkFn>(blend_chunk_avx2(), &blend_chunk_sse2);
}
FaceRotationsFn face_rotations_kernel() {
  return choose<FaceRotationsFn>(face_rotations_avx2(), &face_rotations_sse2);
}
VertexFinishFn vertex_finish_kernel() {
  return choose<VertexFinishFn>(vertex_finish_avx2(), &vertex_finish_sse2);
}
#else
BlendChunkFn blend_chunk_kernel() {
  return nullptr;
}
FaceRotationsFn face_rotations_kernel() {
  return nullptr;
}
VertexFinishFn vertex_finish_kernel() {
  return nullptr;
}
#endif

}  // namespace csculpt::detail
