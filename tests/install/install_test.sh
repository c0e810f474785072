#!/usr/bin/env bash
# Installs the built libcsculpt into a fresh prefix and builds hosts against that prefix alone:
# a CMake project (find_package(csculpt 0.5) -> csculpt::csculpt), a plain cc build through
# pkg-config, and the example of docs/c-api.md (also through pkg-config). Also checks what the install tree holds (only the public header; the
# library with its SONAME; no path back into the build tree).
#
# usage: install_test.sh BUILD_DIR SOURCE_DIR WORK_DIR VERSION [EXTRA_C_FLAGS]
#   EXTRA_C_FLAGS: sanitizer flags the consumers need when the library is instrumented.
set -euo pipefail

build_dir=$1
source_dir=$2
work=$3
version=$4
extra_flags=${5:-}
cmake=${CMAKE_COMMAND:-cmake}
cc=${CC:-cc}

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

rm -rf "$work"
mkdir -p "$work"
prefix=$work/prefix
"$cmake" --install "$build_dir" --prefix "$prefix" >"$work/install.log"

# --- what the install tree holds ---------------------------------------------------------
headers=$(cd "$prefix" && find . -name '*.h' -o -name '*.hpp' -o -name '*.hh' | sort)
[[ $headers == "./include/csculpt.h" ]] ||
  fail "the install tree must hold exactly include/csculpt.h as a header, found: $headers"
cmp -s "$prefix/include/csculpt.h" "$source_dir/capi/include/csculpt.h" ||
  fail "installed csculpt.h differs from capi/include/csculpt.h"
[[ -z $(find "$prefix" -name '*.a') ]] || fail "static archives installed: $(find "$prefix" -name '*.a')"

lib=$(find "$prefix" -name libcsculpt.so.0 -type l)
[[ -n $lib && -e $lib ]] || fail "no libcsculpt.so.0 symlink in the install tree"
libdir=$(dirname "$lib")
[[ -f $libdir/libcsculpt.so.$version && ! -L $libdir/libcsculpt.so.$version ]] ||
  fail "no libcsculpt.so.$version file"
[[ $(readlink "$libdir/libcsculpt.so") == libcsculpt.so.0 ]] ||
  fail "libcsculpt.so (the link-time name) must point to libcsculpt.so.0"
dynamic=$(readelf -d "$lib")
grep -q 'Library soname: \[libcsculpt.so.0\]' <<<"$dynamic" ||
  fail "SONAME of the installed library is not libcsculpt.so.0: $(grep SONAME <<<"$dynamic")"
if grep -E 'RPATH|RUNPATH' <<<"$dynamic" | grep -qF "$build_dir"; then
  fail "the installed library keeps a run path into the build tree"
fi
for f in csculptConfig.cmake csculptConfigVersion.cmake csculptTargets.cmake; do
  [[ -f $libdir/cmake/csculpt/$f ]] || fail "missing $libdir/cmake/csculpt/$f"
done
[[ -f $libdir/pkgconfig/csculpt.pc ]] || fail "missing $libdir/pkgconfig/csculpt.pc"
if grep -rqF "$source_dir/capi" "$libdir/cmake" "$libdir/pkgconfig"; then
  fail "the package files refer to the source tree"
fi

# Resolves the library the way the dynamic loader will for this executable.
loaded_from() { ldd "$1" | awk '$1 == "libcsculpt.so.0" { print $3 }'; }

# --- consumer 1: CMake find_package --------------------------------------------------------
# Only the prefix may supply the package: no user or system package registry, no build tree.
"$cmake" -S "$source_dir/tests/install/consumer" -B "$work/cmake-consumer" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER="$cc" \
  -DCMAKE_C_FLAGS="$extra_flags" -DCMAKE_EXE_LINKER_FLAGS="$extra_flags" \
  >"$work/cmake-consumer.log" 2>&1 || { cat "$work/cmake-consumer.log"; fail "consumer configure"; }
found_dir=$(sed -n 's/^csculpt_DIR:PATH=//p' "$work/cmake-consumer/CMakeCache.txt")
[[ $found_dir == "$libdir/cmake/csculpt" ]] ||
  fail "find_package(csculpt) found $found_dir, not the install tree"
"$cmake" --build "$work/cmake-consumer" >"$work/cmake-build.log" 2>&1 ||
  { cat "$work/cmake-build.log"; fail "consumer build"; }
grep -qF -- "$prefix/include" "$work/cmake-consumer/compile_commands.json" ||
  fail "the consumer was not compiled against $prefix/include"
if grep -qF "$source_dir/capi" "$work/cmake-consumer/compile_commands.json"; then
  fail "the consumer was compiled against the source tree"
fi
[[ $(loaded_from "$work/cmake-consumer/consumer") == "$libdir"/* ]] ||
  fail "the CMake consumer loads libcsculpt from $(loaded_from "$work/cmake-consumer/consumer")"
out=$("$work/cmake-consumer/consumer") || fail "the CMake consumer failed: $out"
echo "cmake consumer: $out"
[[ $out == "csculpt $version "* ]] || fail "the CMake consumer printed '$out'"

# --- consumer 2: plain cc with pkg-config ---------------------------------------------------
# PKG_CONFIG_LIBDIR replaces the default search path, so only the prefix's .pc is seen.
export PKG_CONFIG_LIBDIR=$libdir/pkgconfig PKG_CONFIG_PATH=
[[ $(pkg-config --modversion csculpt) == "$version" ]] ||
  fail "pkg-config reports version $(pkg-config --modversion csculpt)"
cflags=$(pkg-config --cflags csculpt)
libs=$(pkg-config --libs csculpt)
main=$source_dir/tests/install/consumer/main.c
# shellcheck disable=SC2086 # the flags are word lists
header=$("$cc" -std=c99 $cflags -M "$main" | tr -s ' ' '\n' | grep 'csculpt\.h$')
[[ $(realpath "$header") == "$(realpath "$prefix/include/csculpt.h")" ]] ||
  fail "pkg-config's flags find csculpt.h at $header"
# shellcheck disable=SC2086
"$cc" -std=c99 -Wall -Wextra -pedantic -Werror $extra_flags $cflags "$main" -o "$work/pc-consumer" \
  $libs
export LD_LIBRARY_PATH=$libdir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
[[ $(realpath "$(loaded_from "$work/pc-consumer")") == "$(realpath "$libdir")"/* ]] ||
  fail "the pkg-config consumer loads libcsculpt from $(loaded_from "$work/pc-consumer")"
out=$("$work/pc-consumer") || fail "the pkg-config consumer failed: $out"
echo "pkg-config consumer: $out"
[[ $out == "csculpt $version "* ]] || fail "the pkg-config consumer printed '$out'"

# --- consumer 3: the host example of docs/c-api.md ----------------------------------------
# The guide's example is compiled and run here so that it cannot drift from the header.
awk '/<!-- example:/ { marked = 1; next }
     marked && /^```c/ { inside = 1; next }
     inside && /^```/ { exit }
     inside { print }' "$source_dir/docs/c-api.md" >"$work/doc_example.c"
grep -q 'int main(void)' "$work/doc_example.c" || fail "no example block found in docs/c-api.md"
# shellcheck disable=SC2086
"$cc" -std=c99 -Wall -Wextra -pedantic -Werror $extra_flags $cflags "$work/doc_example.c" \
  -o "$work/doc-example" $libs
out=$("$work/doc-example") || fail "the docs/c-api.md example failed: $out"
echo "docs/c-api.md example: ${out//$'\n'/ | }"
[[ $out == *"scene is version 2" ]] || fail "the docs/c-api.md example printed '$out'"
echo "install test passed"
