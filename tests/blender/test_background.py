#!/usr/bin/env python3
"""Two `blender -b` processes host and join one session through the add-on (unpacked from the
zip), driven by csculpt.sync_now; each moves and paints vertices; what both Blenders show
(positions, albedo colour attribute, metallic, roughness) ends bit-identical and holds both
artists' edits. A third process checks the refusals: bad and unanswered invites (Blender keeps
running), dynamic topology, a non-mesh object, and shape keys / multires / a changed vertex
count during a session."""

import os
import sys
import time

import numpy as np

import blenderkit as kit

exe = kit.blender_or_skip()
work = kit.Workdir("bg")
t0 = time.monotonic()
logs = {r: work.file(f"{r}.log") for r in ("host", "join", "checks")}
procs = {r: kit.start(exe, "bg_peer.py", [r], work.user_dirs(r), log=logs[r]) for r in logs}
try:
    states = kit.wait_converged(work, ["host", "join"], 90,
                                procs=[procs["host"], procs["join"]])
    with open(work.file("stop"), "w"):
        pass
finally:
    codes = kit.wait_all(procs.values(), logs.values(), 60)
print("exit codes", codes, f"{time.monotonic() - t0:.1f} s")
assert codes == [0, 0, 0], f"a Blender process failed: {codes}"
for role, log in logs.items():
    # Errors in callbacks (property updates, timers) are printed, not raised: none allowed.
    assert "Traceback" not in open(log, errors="replace").read(), f"a Python error in {role}"

a = np.load(work.file("final-host.npz"))
b = np.load(work.file("final-join.npz"))
for key in ("co", "albedo", "metallic", "roughness"):
    assert np.array_equal(a[key].view(np.uint32), b[key].view(np.uint32)), f"{key} differs"
p = a["co"].reshape(-1, 3)
colour = a["albedo"].reshape(-1, 4)
# Both artists' edits on both: the host's moved north cap and metallic, the joiner's red south
# cap, its roughness and its moved equator.
assert p[:, 2].max() > 1.2, p[:, 2].max()
assert p[:, 0].max() > 1.15, p[:, 0].max()
south = p[:, 2] < -0.6
assert colour[south, 0].min() > 0.99 and colour[south, 1].max() < 0.01, colour[south][:3]
assert np.allclose(a["roughness"][south], 0.2, atol=1e-3)
assert np.allclose(a["metallic"][p[:, 2] > 0.8], 1.0, atol=1e-3)
assert a["metallic"][south].max() == 0.0
print("converged bit for bit at version", states["host"]["version"], "digest",
      states["host"]["digest"][:16])
work.cleanup()
