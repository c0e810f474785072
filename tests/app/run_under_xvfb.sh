#!/bin/sh
# Runs one app test script under its own Xvfb display (1280x800, 24 bit), or skips the test
# (exit 77, ctest's SKIP_RETURN_CODE) on a machine without xvfb-run.
command -v xvfb-run >/dev/null 2>&1 || { echo "xvfb-run missing: skipped"; exit 77; }
exec xvfb-run -a -s "-screen 0 1280x800x24 -nolisten tcp" "$@"
