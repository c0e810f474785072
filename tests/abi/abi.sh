#!/usr/bin/env bash
# The ABI checks of libcsculpt (docs/api-stability.md):
#
#   abi.sh dump LIB HEADERS_DIR OUT         write LIB's ABI (abidw) to OUT: how capi/abi/ is made
#   abi.sh check BASELINE LIB HEADERS_DIR   fail if LIB breaks the ABI recorded in BASELINE
#   abi.sh selfcheck BASELINE HEADERS_DIR WORK_DIR
#                                           prove `check` catches breaks: libraries stubbed from
#                                           altered copies of csculpt.h must fail it, the
#                                           unaltered header and an added function must pass
#   abi.sh symbols LIB HEADER               the dynamic symbols are exactly HEADER's functions
#
# Why `check` does not rely on abidiff's "incompatible" bit alone: libabigail sets it (8) only
# for removed symbols. A changed signature, a moved struct member or a renumbered enumerator
# set only the "ABI changed" bit (4), which an added function sets too. So bit 4 leads to a
# second run with --no-added-syms: if that still reports a change, the change is more than
# additions and the check fails.
set -uo pipefail

cxx=${CXX:-c++}

# Without DWARF abidw sees symbols only, and a changed type would go unnoticed.
require_debug_info() {
  if ! readelf -S "$1" | grep -q '\.debug_info'; then
    echo "$1 has no debug information (build with RelWithDebInfo or Debug)"
    return 77
  fi
}

dump() {
  local lib=$1 headers=$2 out=$3
  require_debug_info "$lib" || return
  # Short locations, no corpus, compilation-directory or DT_NEEDED paths, hashed type ids:
  # the baseline is the same whichever directory the tree was checked out and built in.
  abidw --headers-dir "$headers" --exported-interfaces-only --drop-private-types \
    --no-corpus-path --no-comp-dir-path --short-locs --no-elf-needed --type-id-style hash \
    --out-file "$out" "$lib"
}

# Compares; prints abidiff's report. Returns 0 (compatible: no change, or only additions),
# 1 (incompatible) or 2 (abidiff could not compare).
compare() {
  local baseline=$1 lib=$2 headers=$3 rc rc2
  # Types the public header takes from the C library and the compiler (uint32_t, size_t) count
  # as public too: without them abidiff filters out a change like uint32_t -> uint64_t as a
  # change of a "private" type.
  local args=(--hd2 "$headers" --hd2 /usr/include --hd2 "$("$cxx" -print-file-name=include)"
    --exported-interfaces-only --fail-no-debug-info)
  abidiff "${args[@]}" "$baseline" "$lib"
  rc=$?
  if ((rc & 3)); then
    echo "abidiff failed to compare (exit $rc)"
    return 2
  fi
  if ((rc & 8)); then
    echo "=> incompatible: a symbol was removed (abidiff exit $rc)"
    return 1
  fi
  if ((rc & 4)); then
    abidiff --no-added-syms "${args[@]}" "$baseline" "$lib" >/dev/null
    rc2=$?
    if ((rc2 & 3)); then
      echo "abidiff --no-added-syms failed to compare (exit $rc2)"
      return 2
    fi
    if ((rc2 != 0)); then
      echo "=> incompatible: an existing function or a type it uses changed (abidiff exit $rc)"
      return 1
    fi
    echo "=> compatible: functions or variables were only added"
  fi
  return 0
}

check() {
  local baseline=$1 lib=$2 headers=$3
  require_debug_info "$lib" || return
  compare "$baseline" "$lib" "$headers"
  case $? in
    0) echo "ABI check passed: $lib keeps the ABI of $baseline" ;;
    1)
      echo "ABI check FAILED. If the change is intended and compatible (a struct_size struct grown"
      echo "at its end, see docs/api-stability.md), review the report above and bump the baseline."
      return 1
      ;;
    *) return 2 ;;
  esac
}

# Turns every declaration of a header into a stub definition (void: {}; else: return {}).
stub_definitions() {
  awk '
    /^CSC_API/ { decl = ""; collecting = 1 }
    collecting {
      decl = decl (decl == "" ? "" : " ") $0
      if ($0 ~ /;[[:space:]]*$/) {
        collecting = 0
        sub(/;[[:space:]]*$/, "", decl)
        print decl (decl ~ /^CSC_API void / ? " {}" : " { return {}; }")
      }
    }' "$1"
}

# A shared library named like the real one exposing the functions of `dir/csculpt.h`, with
# the header's types in its debug information: enough for abidiff to compare.
build_variant() {
  local dir=$1 extra=${2:-}
  {
    echo '#include "csculpt.h"'
    stub_definitions "$dir/csculpt.h"
    echo "$extra"
  } >"$dir/stub.cpp"
  "$cxx" -std=c++17 -g -O0 -shared -fPIC -fvisibility=hidden -Wl,-soname,libcsculpt.so.0 \
    -I"$dir" "$dir/stub.cpp" -o "$dir/libcsculpt.so.0"
}

selfcheck() {
  local baseline=$1 headers=$2 work=$3 failures=0
  rm -rf "$work"
  mkdir -p "$work"
  # name | expected | sed program applied to a copy of csculpt.h | extra stub code
  local cases=(
    'unchanged|pass||'
    'added-function|pass||extern "C" CSC_API int csc_added_function(int x) { return x; }'
    'removed-function|fail|/^CSC_API csc_status csc_mesh_clone(/d|'
    'changed-return-type|fail|s/^CSC_API uint32_t csc_mesh_vertex_count(/CSC_API uint64_t csc_mesh_vertex_count(/|'
    'added-parameter|fail|s/^CSC_API csc_status csc_mesh_read(csc_mesh\*\* out, const char\* path);/CSC_API csc_status csc_mesh_read(csc_mesh** out, const char* path, int flags);/|'
    'member-inserted|fail|s/^  uint32_t use_frame;/  uint32_t use_frame;\n  uint32_t inserted;/|'
    'member-appended-without-review|fail|s/^  double channel_tolerance;/  double channel_tolerance;\n  double appended;/|'
    'enumerator-renumbered|fail|s/CSC_ERROR_IO = 3,/CSC_ERROR_IO = 9,/|'
    'enum-widened|fail|s/CSC_STATUS_MAX_ENUM = 0x7FFFFFFF/CSC_STATUS_MAX_ENUM = 0x7FFFFFFFFFLL/|'
  )
  local entry name expected program extra dir verdict
  for entry in "${cases[@]}"; do
    IFS='|' read -r name expected program extra <<<"$entry"
    dir=$work/$name
    mkdir -p "$dir"
    cp "$headers/csculpt.h" "$dir/csculpt.h"
    if [[ -n $program ]]; then
      sed -i -e "$program" "$dir/csculpt.h"
      if cmp -s "$headers/csculpt.h" "$dir/csculpt.h"; then
        echo "selfcheck $name: the alteration no longer applies to csculpt.h; update abi.sh"
        failures=$((failures + 1))
        continue
      fi
    fi
    if ! build_variant "$dir" "$extra" 2>"$dir/build.log"; then
      echo "selfcheck $name: the stub does not build:"
      cat "$dir/build.log"
      failures=$((failures + 1))
      continue
    fi
    compare "$baseline" "$dir/libcsculpt.so.0" "$dir" >"$dir/report.txt" 2>&1
    case $? in
      0) verdict=pass ;;
      1) verdict=fail ;;
      *) verdict=error ;;
    esac
    if [[ $verdict == "$expected" ]]; then
      echo "selfcheck $name: check says $verdict, as it must"
    else
      echo "selfcheck $name: check says $verdict, expected $expected; report:"
      cat "$dir/report.txt"
      failures=$((failures + 1))
    fi
  done
  echo "$((${#cases[@]} - failures)) passed, $failures failed"
  ((failures == 0))
}

symbols() {
  local lib=$1 header=$2 exported declared
  # Anything but a defined function (T) called csc_* is a leak: C++ (mangled _Z*) symbols,
  # weak or unique template instantiations, data, or a function the header does not declare.
  exported=$(nm -D --defined-only "$lib" | awk '{ print $2, $3 }' | sort)
  declared=$(stub_definitions "$header" | grep -oE 'csc_[a-z0-9_]+\(' | tr -d '(' |
    sed 's/^/T /' | sort)
  if [[ $exported != "$declared" ]]; then
    echo "exported dynamic symbols differ from csculpt.h's functions (< exported, > declared):"
    diff <(echo "$exported") <(echo "$declared")
    return 1
  fi
  echo "$(wc -l <<<"$exported") exported symbols, all csc_* functions declared in csculpt.h"
}

for tool in abidw abidiff nm readelf; do
  command -v "$tool" >/dev/null || {
    echo "$tool is missing: install abigail-tools and binutils (.ci/install-deps does)"
    exit 1
  }
done

cmd=${1:-}
shift || true
case $cmd in
  dump | check | selfcheck | symbols) "$cmd" "$@" ;;
  *)
    sed -n '2,13p' "$0"
    exit 2
    ;;
esac
