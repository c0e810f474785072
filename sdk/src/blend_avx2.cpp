// The AVX2 build of the blend kernel (blend_kernel.h): this file alone is compiled with
// -mavx2 (no FMA: contraction would change results), and merge.cpp calls it only on CPUs
// that report AVX2. Elsewhere, and in builds for other targets, blend_chunk_avx2() is null.
#include "blend_kernel.h"

namespace csculpt::detail {

#if defined(__AVX2__) && defined(CSCULPT_AVX2_KERNELS)
namespace {
void blend_chunk_avx2_impl(const BlendLevelArgs& a, std::size_t begin, std::size_t end) {
  blend_chunk_dq_intent<IsaAvx2>(a, begin, end);
}
}  // namespace
BlendChunkFn blend_chunk_avx2() {
  return &blend_chunk_avx2_impl;
}
#else
BlendChunkFn blend_chunk_avx2() {
  return nullptr;
}
#endif

}  // namespace csculpt::detail
