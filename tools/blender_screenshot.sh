#!/usr/bin/env bash
# Blender in a cSculpt session, photographed as a person would see it:
#   tools/blender_screenshot.sh ZIP CSCULPT OUT.png
# A windowed Blender (the add-on installed from ZIP into a clean user directory) shares an
# icosphere in Sculpt Mode with the cSculpt sidebar tab open (tools/blender_screenshot.py); a
# `csculpt peer` (the CSCULPT program) joins with the invite and makes scripted sculpt and paint
# strokes, which Blender shows merged. Runs under its own Xvfb; needs blender, xvfb-run
# and ImageMagick (`import`, `convert`).
set -euo pipefail
if [ "${1:-}" != --inside ]; then
  exec xvfb-run -a -s "-screen 0 1600x900x24 -nolisten tcp" "$0" --inside "$@"
fi
zip=$(realpath "$2") cli=$(realpath "$3") out=$4
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'touch "$work/quit"; kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT

mkdir -p "$work/config" "$work/scripts/addons"
python3 -m zipfile -e "$zip" "$work/scripts/addons"
chmod -R u+rwX,go+rX "$work/scripts/addons"
find "$work/scripts/addons" -name '*.so*' -exec chmod 755 {} +
BLENDER_USER_CONFIG=$work/config BLENDER_USER_SCRIPTS=$work/scripts \
  blender --factory-startup --enable-event-simulate -p 0 0 1600 900 \
  --python "$here/blender_screenshot.py" -- "$work" > "$work/blender.log" 2>&1 &
for _ in $(seq 600); do [ -s "$work/invite" ] && break; sleep 0.1; done
[ -s "$work/invite" ] || { cat "$work/blender.log" >&2; echo "Blender wrote no invite" >&2; exit 1; }
"$cli" peer --join "$(cat "$work/invite")" --name "artist-2" --seed 5 --seconds 3 \
  --strokes-per-second 3 --linger 60 --sync-ms 100 --ignore-stdin > "$work/peer.out" &
for _ in $(seq 600); do [ -s "$work/ready" ] && break; sleep 0.1; done
[ -s "$work/ready" ] || { cat "$work/blender.log" >&2; echo "Blender never showed the merged strokes" >&2; exit 1; }
sleep 1
import -window root "$work/shot.png"
convert "$work/shot.png" -resize 1200x -colors 256 -strip "$out"
echo "wrote $out ($(( $(stat -c %s "$out") / 1024 )) KB, version $(cat "$work/ready"))"
