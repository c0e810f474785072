#!/usr/bin/env python3
"""Remote changes are held back during a real stroke: a windowed Blender (under the Xvfb of
tests/app/run_under_xvfb.sh) shares a sphere in Sculpt Mode with the Grab brush; xdotool
presses the mouse on the sphere's front and drags sideways, as a person would; while the
button is down a Python peer lifts the vertices under the brush and submits. Grab rebuilds
each step from the positions at the stroke's start, so a remote write applied mid-stroke is
lost (the Blender notes: 28 % kept); held back and merged when the stroke ends, the lift and
the drag are both in the converged mesh."""

import glob
import os
import subprocess
import sys
import time

import numpy as np

import blenderkit as kit

exe = kit.blender_or_skip()
if not os.environ.get("DISPLAY") or not kit.shutil.which("xdotool"):
    print("no X display or no xdotool (run under tests/app/run_under_xvfb.sh): skipped")
    raise SystemExit(kit.SKIP)
work = kit.Workdir("holdback")
log = work.file("host.log")
env = work.user_dirs("host")
blender = kit.start(exe, "hold_peer.py", [], env, background=False, log=log,
                    extra=("-p", "0", "0", "640", "480"))
sys.path.insert(0, glob.glob(os.path.join(work.path, "host", "scripts", "addons", "*"))[0])
import csculpt  # noqa: E402  (the add-on's own binding and bundled library)


def xdo(*args):
    return subprocess.run(["xdotool", *args], check=True, capture_output=True, text=True).stdout


LIFT = 0.15
try:
    end = time.monotonic() + 90
    while (kit.read_json(work.file("state-host.json")) is None or
           not os.path.exists(work.file("target"))):
        assert time.monotonic() < end and blender.poll() is None, "Blender did not get ready"
        time.sleep(0.2)
    x, y = (int(v) for v in open(work.file("target")).read().split())
    window = xdo("search", "--sync", "--onlyvisible", "--class", "Blender").split()[0]
    # A clean user directory shows the splash (Quick Setup) over the viewport: Escape closes it,
    # as a person would. (Blender then ends with status 1 when it quits; observed, not this
    # test's subject: the log is checked for Python errors instead.)
    xdo("mousemove", "--window", window, "320", "240")
    xdo("key", "Escape")
    time.sleep(0.5)
    with csculpt.Session.join(open(work.file("invite")).read(), name="python",
                              join_timeout_ms=10000, sync_ms=50) as s:
        with s.base() as base:
            pos = base.positions.ravel().copy()
            ch = {n: c.values.copy() for n, c in base.channels.items()}
        p = pos.reshape(-1, 3)
        p0 = p.copy()
        under = (p[:, 1] < -0.9) & (np.abs(p[:, 0]) < 0.25) & (np.abs(p[:, 2]) < 0.25)
        assert under.sum() >= 3, under.sum()
        xdo("mousemove", "--window", window, str(x), str(y))
        time.sleep(0.3)
        xdo("mousedown", "1")
        for i in range(1, 6):
            xdo("mousemove", "--window", window, str(x + 8 * i), str(y))
            time.sleep(0.1)
        # Mid-stroke: the lift goes to the merger and comes back to Blender as a version.
        p[under, 2] += LIFT
        assert s.submit(pos, ch, strokes=1)
        held = time.monotonic() + 2.0
        while time.monotonic() < held:
            s.update(pos, ch)
            s.submit(pos, ch)
            time.sleep(0.05)
        for i in range(6, 11):
            xdo("mousemove", "--window", window, str(x + 8 * i), str(y))
            time.sleep(0.1)
        xdo("mouseup", "1")
        # Blender's stroke eats the release: the add-on sees the stroke's end at the next event
        # (a hand on a mouse never stays still).
        time.sleep(0.2)
        xdo("mousemove", "--window", window, str(x + 90), str(y + 10))
        end = time.monotonic() + 30
        host = {}
        while True:
            assert time.monotonic() < end, f"no convergence within 30 s: {s.version} {host}"
            s.update(pos, ch)
            s.submit(pos, ch)
            host = kit.read_json(work.file("state-host.json")) or {"version": -1}
            if (s.version >= 2 and host["version"] == s.version and host["acked"] >= 1 and
                    s.stats.strokes_acknowledged >= 1):
                break
            time.sleep(0.05)
        final = pos.reshape(-1, 3).copy()
finally:
    open(work.file("stop"), "w").close()
    codes = kit.wait_all([blender], [], 60)
assert "Traceback" not in open(log, errors="replace").read(), "a Python error in Blender"
shown = np.load(work.file("final-host.npz"))["co"].reshape(-1, 3)
assert np.array_equal(shown.view(np.uint32), final.view(np.uint32)), "Blender and the peer differ"
lift = final[under, 2] - p0[under, 2]
drag = final[under, 0] - p0[under, 0]
print(f"under the brush: lift {lift.mean():.3f} (remote {LIFT}), drag {drag.mean():.3f}")
assert drag.mean() > 0.02, "the Grab stroke did not move the vertices"
# Lost, the lift would be ~0 where Grab rebuilt the vertices from the stroke's start; merged
# after the stroke it stays, turned a little with the surface the drag tilted (measured 0.65
# of it on average under the brush).
assert lift.mean() > 0.5 * LIFT, "the remote lift was lost during the stroke"
print("holdback: the remote change made mid-stroke and the stroke both kept")
assert codes in ([0], [1]), codes
work.cleanup()
