#!/usr/bin/env bash
# The CTest test `fuzz`: builds the libFuzzer targets (fuzz.mk: clang++ with
# -fsanitize=fuzzer,address,undefined, straight from the sources, incremental) and runs each
# for a short time on a fresh copy of its seed corpus. Fails on any crash, sanitizer report,
# leak, timeout or out-of-memory; the input that caused it is kept in WORK/artifacts/.
# Skips (exit 77) when clang++ or its fuzzer runtime is missing.
#
#   run_fuzz.sh SOURCE_DIR WORK_DIR        CSCULPT_FUZZ_SECONDS (default 20) per fuzzer
set -uo pipefail
src=${1:?usage: run_fuzz.sh SOURCE_DIR WORK_DIR}
work=${2:?usage: run_fuzz.sh SOURCE_DIR WORK_DIR}
seconds=${CSCULPT_FUZZ_SECONDS:-20}
jobs=${CSCULPT_JOBS:-2}
if ! command -v clang++ >/dev/null 2>&1; then
  echo "SKIP: clang++ is not installed (Debian: apt-get install clang libclang-rt-14-dev," \
       "as .ci/install-deps does)"
  exit 77
fi
mkdir -p "$work"
work=$(cd "$work" && pwd)

probe=$work/probe
if ! echo 'extern "C" int LLVMFuzzerTestOneInput(const char*, unsigned long) { return 0; }' |
     clang++ -x c++ -fsanitize=fuzzer,address,undefined - -o "$probe" 2>"$work/probe.log"; then
  echo "SKIP: clang++ cannot link -fsanitize=fuzzer,address,undefined (libclang-rt-14-dev" \
       "missing?):"
  cat "$work/probe.log"
  exit 77
fi
rm -f "$probe"

start=$(date +%s)
if ! make --no-print-directory -f "$src/tests/fuzz/fuzz.mk" SRC="$src" WORK="$work" \
     -j"$jobs" >"$work/build.log" 2>&1; then
  echo "FAIL: building the fuzzers"
  tail -n 40 "$work/build.log"
  exit 1
fi
echo "built the fuzzers in $(($(date +%s) - start)) s (log: $work/build.log)"

failed=0
run() {  # run NAME CORPUS MAX_LEN
  local name=$1 corpus=$2 max_len=$3
  local copy=$work/corpus/$name
  rm -rf "$copy"
  mkdir -p "$copy" "$work/artifacts"
  cp "$src/tests/fuzz/corpus/$corpus"/* "$copy/"
  local log=$work/$name.log
  "$work/$name" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len="$max_len" -print_final_stats=1 -artifact_prefix="$work/artifacts/$name-" \
    "$copy" >"$log" 2>&1
  local status=$?
  local runs
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  if [ "$status" -ne 0 ]; then
    failed=1
    echo "FAIL: $name (exit $status) after ${runs:-?} runs; artifacts in $work/artifacts:"
    grep -E "ERROR|SUMMARY|fuzz_[a-z_]+: |Test unit written" "$log" | head -n 20
    tail -n 30 "$log"
  else
    echo "ok: $name: ${runs:-?} runs in $seconds s, corpus $(ls "$src/tests/fuzz/corpus/$corpus" | wc -l)" \
         "seeds -> $(ls "$copy" | wc -l) inputs"
  fi
}
run fuzz_mesh_readers mesh 4096
run fuzz_wire_decode wire 4096
run fuzz_capi_bytes wire 4096
echo "fuzz test took $(($(date +%s) - start)) s"
exit $failed
