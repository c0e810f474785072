#!/bin/sh
# The AVX2 kernels' object must define nothing the baseline code could end up calling: the
# linker keeps one copy of each inline function, and an AVX2-compiled copy of a shared one
# would crash CPUs without AVX2. sdk/src/simd/simd_isa.h gives every SIMD helper an
# instruction-set namespace; this checks that the object's global symbols are only its
# entry points (csculpt::detail::*_avx2()) and names inside isa_avx2.
#   isolation.sh LIBCSCULPT_SDK_A
set -eu
lib=$1
syms=$(nm -A -C --defined-only "$lib" | grep 'blend_avx2\.cpp\.o:' | awk '$2 ~ /^[TWVDBRui]$/ || $3 ~ /^[TWVDBRui]$/' || true)
if [ -z "$syms" ]; then
  echo "isolation: no blend_avx2.cpp.o symbols in $lib (AVX2 kernels not built?)" >&2
  exit 77
fi
# DW.ref.* are the exception-handling personality's data pointers (the same in every
# object; no code).
bad=$(printf '%s\n' "$syms" | grep -v 'isa_avx2' | grep -v -E 'csculpt::detail::[a-z0-9_]+_avx2\(\)$' |
  grep -v ' DW\.ref\.' || true)
if [ -n "$bad" ]; then
  echo "isolation: the AVX2 object defines symbols outside its namespace:" >&2
  printf '%s\n' "$bad" >&2
  exit 1
fi
echo "isolation: $(printf '%s\n' "$syms" | wc -l) global symbols, all entry points or in isa_avx2"
