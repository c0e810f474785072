#!/usr/bin/env bash
# csculpt-app's frame times while merges arrive (issue 11: "3 csculpt peer processes on the
# same machine"): the app hosts a session on a 320K-face sphere, three simulated artists join
# and sculpt, and the app's --bench-frames JSON lines report the frames meanwhile. While the
# frames are measured a fourth artist joins late (a snapshot is sent, the newcomer's edits
# rebased) and two of the first three are killed (whichever merged: a failover), so the
# frame_ms_max figures cover "a merge, a rebase, a late join or a failover".
# With APART as the last argument, the control: the same peers and faults in a session of
# their own (hosted by a fourth csculpt peer on a mesh of the same size), the app alone
# beside them. Its frames then carry the machine's load and none of the session's work, so
# the two runs tell which of a slow frame is the session's.
#   tools/app_bench_session.sh APP CSCULPT [FRAMES] [FACES] [APART]
set -euo pipefail
. "$(dirname "$0")/under_xvfb.sh" 1280x800x24 "$@"
app=$2 cli=$3 frames=${4:-200} faces=${5:-320000} apart=${6:-}
mkfifo "$work/out"
# The first seconds untimed: the three joins (snapshots of the mesh) land first.
if [ "$apart" = APART ]; then
  mkfifo "$work/host"
  "$cli" peer --faces "$faces" --seconds 0 --linger 120 --ignore-stdin > "$work/host" 2>/dev/null &
  exec 4< "$work/host"
  read -r line <&4
  invite=$(printf '%s' "$line" | sed -n 's/.*"invite":"\([^"]*\)".*/\1/p')
  "$app" --sphere-faces "$faces" --bench-frames "$frames" --bench-warmup 4 > "$work/out" &
  exec 3< "$work/out"
else
  "$app" --host --sphere-faces "$faces" --bench-frames "$frames" --bench-warmup 4 > "$work/out" &
  exec 3< "$work/out"
  read -r line <&3
  invite=${line#INVITE }
fi
pids=()
for seed in 1 2 3; do
  "$cli" peer --join "$invite" --seed "$seed" --seconds 60 --linger 1 --ignore-stdin > /dev/null 2>&1 &
  pids+=($!)
done
# The faults, timed from the end of the app's 4 s warm-up.
(
  sleep 6
  "$cli" peer --join "$invite" --seed 4 --seconds 60 --linger 1 --ignore-stdin > /dev/null 2>&1 &
  sleep 3
  kill -9 "${pids[0]}" 2>/dev/null || true
  sleep 3
  kill -9 "${pids[1]}" 2>/dev/null || true
) &
cat <&3
