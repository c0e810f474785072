#!/bin/bash
# Two `csculpt peer` processes on one machine, the creator journaling with a compaction every
# 4 versions, both making 4 strokes a second for 20 s: how often each took the other for gone
# (peer_left "expired") while the creator compacted, and the creator's journal timings.
# Usage: tools/journal_compaction_run.sh CSCULPT FACES OUTDIR   (e.g. build/cli/csculpt 2000000 /tmp/jrun)
set -euo pipefail
csculpt=$1 faces=$2 out=$3
rm -rf "$out"
mkdir -p "$out"
"$csculpt" peer --id 1 --faces "$faces" --journal "$out/journal" --journal-max-versions 4 \
  --seconds 20 --linger 3 --strokes-per-second 4 --ignore-stdin >"$out/creator.out" 2>"$out/creator.err" &
creator=$!
invite=""
for _ in $(seq 1 600); do
  invite=$(grep -o '"invite":"[^"]*"' "$out/creator.out" | head -1 | cut -d'"' -f4 || true)
  [ -n "$invite" ] && break
  sleep 0.1
done
[ -n "$invite" ] || { echo "no invite from the creator" >&2; exit 1; }
"$csculpt" peer --id 2 --join "$invite" --seconds 20 --linger 3 --strokes-per-second 4 \
  --ignore-stdin >"$out/joiner.out" 2>"$out/joiner.err" &
wait "$creator" $!
expired() { grep '"event":"peer_left"' "$1" | grep -c '"detail":"expired"' || true; }
echo "{\"faces\":$faces,\"creator_expired_joiner\":$(expired "$out/creator.out"),\"joiner_expired_creator\":$(expired "$out/joiner.out")}"
grep -o '"journal_[a-z_]*":[0-9.]*' "$out/creator.out" | tail -4 | paste -sd' '
