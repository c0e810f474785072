// Internal: one inline namespace per instruction set. The SIMD headers are compiled into
// more than one translation unit with different -m flags (the baseline and the AVX2 kernels,
// chosen at run time); without distinct names, the linker would keep one copy of each
// inline function, possibly the AVX2 one, for every caller. tests/sdk/simd/isolation.sh checks
// that the AVX2 object defines nothing outside its namespace but its entry points.
#pragma once

#if defined(__AVX2__)
#define CSCULPT_ISA_BEGIN inline namespace isa_avx2 {
#else
#define CSCULPT_ISA_BEGIN inline namespace isa_base {
#endif
#define CSCULPT_ISA_END }
