#!/bin/sh
# csculpt-app uses cSculpt through csculpt.h and libcsculpt.so only (issue 11): it defines no
# csculpt:: C++ symbol (no SDK code compiled or linked in), needs none from elsewhere, calls
# csc_* functions, and the loader resolves them from libcsculpt.so.
set -eu
app=$1
fail() { echo "FAIL: $*" >&2; exit 1; }
defined=$(nm -C --defined-only "$app" | grep -c 'csculpt::' || true)
[ "$defined" -eq 0 ] || fail "$defined csculpt:: symbols defined in $app: $(nm -C --defined-only "$app" | grep 'csculpt::' | head -3)"
undefined_cxx=$(nm -D -C --undefined-only "$app" | grep -c 'csculpt::' || true)
[ "$undefined_cxx" -eq 0 ] || fail "$app imports csculpt:: C++ symbols"
imported=$(nm -D --undefined-only "$app" | grep -c ' csc_' || true)
[ "$imported" -ge 20 ] || fail "only $imported csc_* functions imported (expected the C ABI)"
ldd "$app" | grep -q 'libcsculpt\.so' || fail "ldd does not show libcsculpt.so"
ldd "$app" | grep 'libcsculpt\.so' | grep -q 'not found' && fail "libcsculpt.so not found by the loader"
echo "ok: no csculpt:: symbols, $imported csc_* imports, $(ldd "$app" | grep -o 'libcsculpt\.so[^ ]*' | head -1)"
