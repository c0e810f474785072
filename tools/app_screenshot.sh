#!/usr/bin/env bash
# Two csculpt-app windows side by side in one session, photographed as a person would see them:
#   tools/app_screenshot.sh APP OUT.png
# The host sculpts and paints, the other artist joins with the printed invite and sculpts the
# same sphere, then shows who edited where (the attribution view). Runs under its own Xvfb;
# needs xvfb-run, xdotool and ImageMagick's `import` (.ci/install-deps installs them).
set -euo pipefail
. "$(dirname "$0")/under_xvfb.sh" 2000x720x24 "$@"
app=$2 out=$3

drag() {  # drag X0 Y0 X1 Y1: sixteen cursor steps, one per frame
  echo "move $1 $2"; echo "wait 1"; echo "press left"
  for i in $(seq 1 16); do
    echo "move $(( $1 + ($3 - $1) * i / 16 )) $(( $2 + ($4 - $2) * i / 16 ))"; echo "wait 2"
  done
  echo "release left"; echo "wait 2"
}
{ echo "wait session"; echo "wait 10"; echo "key d"; echo "key ]"
  drag 420 420 580 420; drag 430 300 570 300
  echo "key b"; drag 440 470 560 470
} > "$work/host.replay"
{ echo "wait session"; echo "wait 5"; echo "key i"
  drag 460 250 540 250; echo "key c"; drag 500 330 500 520
  echo "key m"; drag 420 360 420 480; echo "wait 20"; echo "key a"
} > "$work/join.replay"

"$app" --size 1000x720 --host --replay "$work/host.replay" --exit-after 30 > "$work/host.out" &
host=$!
for _ in $(seq 300); do grep -q '^INVITE ' "$work/host.out" && break; sleep 0.1; done
invite=$(sed -n 's/^INVITE //p' "$work/host.out")
[ -n "$invite" ] || { echo "the host printed no invite" >&2; exit 1; }
"$app" --size 1000x720 --join "$invite" --replay "$work/join.replay" --exit-after 28 > "$work/join.out" &
joiner=$!
# Without a window manager both windows open at (0, 0): put the joiner's on the right.
window=$(xdotool search --sync --onlyvisible --pid "$joiner" | head -1)
xdotool windowmove "$window" 1000 0
sleep 18  # both replays done, a few merges later
import -window root "$out"
wait "$host" "$joiner"
echo "wrote $out"
