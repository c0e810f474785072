#!/usr/bin/env bash
# What an idle csculpt-app costs the machine in a session: the app hosts a 320K-face sphere
# and nobody touches it, three simulated artists (`csculpt peer`) join and sculpt on the same
# cores. Prints one JSON line: the app's CPU seconds and frames drawn over the run, the
# session's version when it quit, and the three peers' CPU seconds.
#   tools/app_idle_session.sh APP CSCULPT [SECONDS] [FACES]
set -euo pipefail
. "$(dirname "$0")/under_xvfb.sh" 1280x800x24 "$@"
app=$2 cli=$3 seconds=${4:-20} faces=${5:-320000}
mkfifo "$work/out"
CSCULPT_APP_COUNT_FRAMES=1 /usr/bin/time -f "%U %S" -o "$work/app_time" \
  "$app" --host --sphere-faces "$faces" --exit-after "$seconds" > "$work/out" 2>/dev/null &
exec 3< "$work/out"
read -r line <&3
invite=${line#INVITE }
for seed in 1 2 3; do
  /usr/bin/time -f "%U %S" -o "$work/peer_time_$seed" "$cli" peer --join "$invite" \
    --seed "$seed" --seconds "$((seconds - 3))" --linger 1 --ignore-stdin > /dev/null 2>&1 &
done
cat <&3 > "$work/app_out"
wait
frames=$(sed -n 's/^FRAMES drawn=\([0-9]*\).*/\1/p' "$work/app_out")
version=$(sed -n 's/^SESSION .* version=\([0-9]*\) .*/\1/p' "$work/app_out")
app_cpu=$(awk '{print $1 + $2}' "$work/app_time")
peers_cpu=$(cat "$work"/peer_time_* | awk '{s += $1 + $2} END {print s}')
printf '{"seconds":%s,"faces":%s,"app_cpu_s":%s,"frames_drawn":%s,"version":%s,"peers_cpu_s":%s}\n' \
  "$seconds" "$faces" "$app_cpu" "${frames:-null}" "${version:-null}" "$peers_cpu"
