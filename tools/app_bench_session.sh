#!/usr/bin/env bash
# csculpt-app's frame times while merges arrive (issue 11: "3 csculpt peer processes on the
# same machine"): the app hosts a session on a 320K-face sphere, three simulated artists join
# and sculpt, and the app's --bench-frames JSON lines report the frames meanwhile.
#   tools/app_bench_session.sh APP CSCULPT [FRAMES] [FACES]
set -euo pipefail
if [ "${1:-}" != --inside ]; then
  exec xvfb-run -a -s "-screen 0 1280x800x24 -nolisten tcp" "$0" --inside "$@"
fi
app=$2 cli=$3 frames=${4:-200} faces=${5:-320000}
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
mkfifo "$work/out"
# The first seconds untimed: the three joins (snapshots of the mesh) land first.
"$app" --host --sphere-faces "$faces" --bench-frames "$frames" --bench-warmup 4 > "$work/out" &
exec 3< "$work/out"
read -r line <&3
invite=${line#INVITE }
for seed in 1 2 3; do
  "$cli" peer --join "$invite" --seed "$seed" --seconds 60 --linger 1 --ignore-stdin > /dev/null 2>&1 &
done
cat <&3
