# Sourced by the tools that run csculpt-app under an Xvfb of their own:
#   . "$(dirname "$0")/under_xvfb.sh" 1280x800x24 "$@"
# re-runs the calling script under xvfb-run with that screen (its arguments then start with
# --inside), and, once inside, gives it $work: a directory removed on exit, after the
# script's background jobs are killed.
if [ "${2:-}" != --inside ]; then
  exec xvfb-run -a -s "-screen 0 $1 -nolisten tcp" "$0" --inside "${@:2}"
fi
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$work"' EXIT
