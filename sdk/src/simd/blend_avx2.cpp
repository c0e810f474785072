// The AVX2 builds of the merge's SIMD kernels (blend_kernel.h, face_rotation_lanes.h): this
// file alone is compiled with -mavx2 (no FMA: contraction would change results), and
// simd_dispatch.cpp calls it only on CPUs that report AVX2. In builds for other targets its
// entry points return null.
#include "blend_kernel.h"
#include "face_rotation_lanes.h"

namespace csculpt::detail {

#if defined(__AVX2__) && defined(CSCULPT_AVX2_KERNELS)
namespace {
void blend_chunk_avx2_impl(const BlendLevelArgs& a, std::size_t begin, std::size_t end) {
  blend_chunk_dq_intent<IsaAvx2>(a, begin, end);
}
std::size_t face_rotations_avx2_impl(const FaceRotationArgs& a) {
  return face_rotations_lanes<__m256>(a);
}
void vertex_finish_avx2_impl(const VertexFinishArgs& a) {
  vertex_finish_lanes<__m256>(a);
}
}  // namespace
BlendChunkFn blend_chunk_avx2() {
  return &blend_chunk_avx2_impl;
}
FaceRotationsFn face_rotations_avx2() {
  return &face_rotations_avx2_impl;
}
VertexFinishFn vertex_finish_avx2() {
  return &vertex_finish_avx2_impl;
}
#else
BlendChunkFn blend_chunk_avx2() {
  return nullptr;
}
FaceRotationsFn face_rotations_avx2() {
  return nullptr;
}
VertexFinishFn vertex_finish_avx2() {
  return nullptr;
}
#endif

}  // namespace csculpt::detail
