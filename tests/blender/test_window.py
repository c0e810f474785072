#!/usr/bin/env python3
"""Two windowed Blenders under one Xvfb display (run by tests/app/run_under_xvfb.sh), each
with the add-on unpacked from the zip and its timer driving the sync: the host makes a real
Draw stroke (sculpt.brush_stroke), the joiner a real Paint stroke across it. Both end
bit-identical with both strokes and see each other's presence. Then the host undoes its stroke
with csculpt.undo: its displacement goes on both, the joiner's paint stays (also where the two
strokes overlap), and both are bit-identical again."""

import os
import time

import numpy as np

import blenderkit as kit

exe = kit.blender_or_skip()
if not os.environ.get("DISPLAY"):
    print("no X display (run under tests/app/run_under_xvfb.sh): skipped")
    raise SystemExit(kit.SKIP)
work = kit.Workdir("window")
t0 = time.monotonic()
logs = {r: work.file(f"{r}.log") for r in ("host", "join")}
procs = {}
for i, r in enumerate(logs):
    procs[r] = kit.start(exe, "win_peer.py", [r], work.user_dirs(r), background=False,
                         log=logs[r], extra=("-p", str(40 + 660 * i), "40", "640", "480"))
try:
    states = kit.wait_converged(work, list(logs), 150, procs=list(procs.values()),
                                extra=lambda s: all(x["presence"] >= 1 for x in s.values()))
    t1 = time.monotonic()
    print(f"strokes converged at version {states['host']['version']} "
          f"({t1 - t0:.1f} s from start)")
    open(work.file("undo"), "w").close()
    before = states["host"]["version"]
    states = kit.wait_converged(
        work, list(logs), 60, procs=list(procs.values()),
        extra=lambda s: s["host"]["undone"] and s["join"]["mid"] and
        s["host"]["version"] > before)
    print(f"undo converged at version {states['host']['version']} ({time.monotonic() - t1:.1f} s)")
    # Blender's own Ctrl+Z, pressed past the mode switch: nothing crashes, the session goes on
    # and both peers converge again on whatever Blender's undo left.
    t2 = time.monotonic()
    open(work.file("native"), "w").close()
    states = kit.wait_converged(work, list(logs), 60, procs=list(procs.values()),
                                extra=lambda s: s["host"]["native"] and s["join"]["native"])
    print(f"Blender's own undo past the mode switch converged at version "
          f"{states['host']['version']} ({time.monotonic() - t2:.1f} s)")
    steps, mode = open(work.file("native-steps")).read().split()
    assert int(steps) >= 1 and mode == "OBJECT", f"Blender's undo did not cross: {steps} {mode}"
finally:
    open(work.file("stop"), "w").close()
    codes = kit.wait_all(procs.values(), logs.values(), 60)
print("exit codes", codes, f"{time.monotonic() - t0:.1f} s")
assert codes == [0, 0], codes
for r, log in logs.items():
    text = open(log, errors="replace").read()
    assert "Traceback" not in text, f"a Python error in {r}'s Blender"
load = lambda name: np.load(work.file(name))
orig, mid_h, mid_j, und_h, und_j, fin_h, fin_j = (
    load(f) for f in ("orig-host.npz", "mid-host.npz", "mid-join.npz", "undone-host.npz",
                      "undone-join.npz", "final-host.npz", "final-join.npz"))
for key in ("co", "albedo", "metallic", "roughness"):
    assert np.array_equal(mid_h[key].view(np.uint32), mid_j[key].view(np.uint32)), f"mid {key}"
    assert np.array_equal(und_h[key].view(np.uint32), und_j[key].view(np.uint32)), f"undone {key}"
    assert np.array_equal(fin_h[key].view(np.uint32), fin_j[key].view(np.uint32)), f"final {key}"
moved = np.linalg.norm((mid_h["co"] - orig["co"]).reshape(-1, 3), axis=1) > 1e-3
blue = mid_h["albedo"].reshape(-1, 4)
painted = (blue[:, 2] > 0.6) & (blue[:, 0] < 0.3)
overlap = moved & painted
print(f"Draw stroke moved {moved.sum()} vertices, Paint painted {painted.sum()}, "
      f"overlap {overlap.sum()}")
assert moved.sum() >= 10 and painted.sum() >= 10 and overlap.sum() >= 1
# After the undo: the host's displacement is gone, the joiner's paint stays (overlap too).
rest = np.linalg.norm((und_h["co"] - orig["co"]).reshape(-1, 3), axis=1)
assert rest.max() < 1e-3, f"the undone stroke left {rest.max()}"
assert np.array_equal(und_h["albedo"].reshape(-1, 4)[painted], blue[painted]), "paint lost"
print("window: strokes and undo converged bit for bit")
work.cleanup()
