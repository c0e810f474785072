#!/usr/bin/env python3
"""Three hosts of the C ABI in one session: a Blender artist (`blender -b` with the add-on,
driven by csculpt.sync_now; interop_blender.py) hosts an icosphere, csculpt-app joins under
the Xvfb display this test runs in (tests/app/run_under_xvfb.sh) and replays a Draw and a Paint
stroke, and a `csculpt peer` process joins and makes scripted strokes for two seconds; Blender
moves and paints once both are in. After the app has left, they all end with the same mesh bit
for bit: the session's mesh digest (peer/src/session.cpp's mesh_digest, meshdigest.py) of the
app's saved PLY, of the add-on's session-side arrays (albedo as the session holds it, sRGB, not
Blender's linear colours) and the peer's own, and the PLY's arrays equal Blender's. Blender
listens on every interface (the add-on's default), and the others join through the address its
invite names, as a colleague's machine would.

Needs blender, csculpt-app (CSCULPT_APP), csculpt (CSCULPT_CLI) and an X display; skipped
(77) without blender or a display."""

import os
import subprocess
import sys
import time

import numpy as np

import blenderkit as kit
import meshdigest

# The app's replay files and `csculpt peer`'s JSON lines, as the app and session tests use them.
sys.path.insert(0, os.path.join(kit.HERE, "..", "app"))
sys.path.insert(0, os.path.join(kit.HERE, "..", "session"))
from applib import Replay, machine_ipv4s  # noqa: E402
from sessionlib import Peer  # noqa: E402

exe = kit.blender_or_skip()
if not os.environ.get("DISPLAY"):
    print("no X display (run under tests/app/run_under_xvfb.sh): skipped")
    raise SystemExit(kit.SKIP)
APP = os.environ.get("CSCULPT_APP", "csculpt-app")
CLI = os.environ.get("CSCULPT_CLI", "csculpt")
work = kit.Workdir("interop")
t0 = time.monotonic()


def read_text(name):
    try:
        with open(work.file(name)) as f:
            return f.read()
    except OSError:
        return None


def wait_for(what, predicate, timeout, alive=()):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        for name, p in alive:
            if p.poll() is not None:
                raise AssertionError(f"{name} ended early (exit {p.poll()}) waiting for {what}")
        time.sleep(0.1)
    raise AssertionError(f"no {what} within {timeout} s")


log = work.file("blender.log")
blender = kit.start(exe, "interop_blender.py", [], work.user_dirs("blender"), log=log)
app = peer = None
app_out = work.file("app.out")
app_ply = work.file("app.ply")
try:
    invite = wait_for("the invite from Blender", lambda: read_text("invite"), 40,
                      [("Blender", blender)])
    # The add-on listens on every interface by default, so its invite names an address a
    # colleague's machine reaches; the app and the peer join through it.
    address = invite.rsplit("@tcp://", 1)[1].rsplit(":", 1)[0]
    assert address in (machine_ipv4s() or {"127.0.0.1"}), f"the invite names {address}"
    # The app joins, waits for the session's mesh, then a Draw stroke across the sphere's
    # middle and a Paint stroke down through it. It leaves after 10 s (the peer's strokes
    # end 2 s after it joins, Blender's once both are in), settling its own first.
    replay = (Replay().wait("session").wait(5).key("d").drag((540, 400), (740, 400))
              .key("b").drag((640, 300), (640, 500)).write(work.path, "app.replay"))
    # Default membership thresholds, like Blender's and the app's; the session's creator
    # (Blender) merges for everyone while it is in.
    peer = Peer(13, join=invite, seconds=2, rate=5, linger=40, extra=("--name", "cli"),
                timing=("--sync-ms", "50"))
    app = subprocess.Popen([APP, "--sphere-faces", "20000", "--join", invite, "--replay",
                            replay, "--exit-after", "10", "--save", app_ply],
                           stdout=open(app_out, "w"), stderr=subprocess.STDOUT)
    app.wait(45)
    app_text = open(app_out, errors="replace").read()
    print("---- app\n" + app_text[-3000:])
    assert app.returncode == 0, f"csculpt-app exited {app.returncode}"
    session_line = next((x for x in app_text.splitlines() if x.startswith("SESSION ")), None)
    assert session_line, "the app printed no SESSION line (it never joined?)"
    app_session = dict(w.split("=") for w in session_line.split()[1:])
    print(f"app left at {time.monotonic() - t0:.1f} s")

    # Blender and the peer settle: same version and digest, every stroke acknowledged.
    def settled():
        b = kit.read_json(work.file("state-blender.json"))
        s = peer.last("state")
        if not (b and s and b["edited"] and b["acked"] >= b["strokes"] >= 1 and
                not s["editing"] and s["strokes"] >= 1 and s["unacknowledged"] == 0 and
                b["version"] == s["version"] and b["digest"] == s["digest"] and
                b["digest"] == b["base_digest"]):
            return None
        return b, s
    blender_state, peer_state = wait_for("agreement of Blender and the peer", settled, 20,
                                         [("Blender", blender), ("the peer", peer.proc)])
    open(work.file("stop"), "w").close()
    wait_for("Blender's final arrays", lambda: kit.read_json(work.file("state-blender.json"))
             and os.path.exists(work.file("done-blender")), 30, [("Blender", blender)])
    peer.quit()
    summary = wait_for("the peer's summary", lambda: peer.last("summary"), 20)
finally:
    open(work.file("stop"), "w").close()
    for p in (app, peer.proc if peer else None):
        if p is not None and p.poll() is None:
            p.kill()
    codes = kit.wait_all([blender], [log], 30)
    if peer:
        peer.proc.wait(10)
        peer.err_reader.join(5)
        print("---- peer stderr\n" + peer.stderr[-2000:])
print("Blender exit", codes, f"{time.monotonic() - t0:.1f} s")
assert codes == [0], f"Blender failed: {codes}"
assert "Traceback" not in open(log, errors="replace").read(), "a Python error in Blender"

final_blender = kit.read_json(work.file("state-blender.json"))
digests = {"blender": final_blender["digest"], "peer": summary["digest"],
           "app": meshdigest.ply_digest(app_ply)}
print("app", app_session)
print("peer summary", {k: summary[k] for k in ("version", "digest", "strokes", "acknowledged",
                                                 "lost_edits", "merges", "members")})
print("blender", final_blender)
print("digests", digests)

# Everyone took part and nothing was lost.
assert app_session["members"] == "3", f"the app did not see all three: {session_line}"
assert int(app_session["submitted"]) >= 2, f"the app's strokes were not sent: {session_line}"
assert app_session["acknowledged"] == app_session["submitted"], session_line
assert summary["strokes"] >= 5 and summary["lost_edits"] == 0, summary
assert summary["acknowledged"] == summary["strokes_submitted"], summary
assert final_blender["acked"] >= final_blender["strokes"] >= 1, final_blender
original = open(work.file("original-digest")).read()
assert digests["blender"] != original, "the session's mesh did not change"

# The same mesh on all three, bit for bit: the arrays of the app's PLY against Blender's
# session-side arrays (which channel differs, if any), then the digests.
positions, channels = meshdigest.read_ply(app_ply)
arrays = np.load(work.file("final-blender.npz"))
order = [str(x) for x in arrays["order"]]
assert [name for name, _ in channels] == order, (channels, order)
assert np.array_equal(positions.ravel().view(np.uint32),
                      arrays["positions"].ravel().view(np.uint32)), "positions differ (app/Blender)"
for name, values in channels:
    assert np.array_equal(values.ravel().view(np.uint32),
                          arrays[f"channel_{name}"].ravel().view(np.uint32)), \
        f"channel {name} differs (app/Blender)"
assert len(set(digests.values())) == 1, f"the three hosts ended with different meshes: {digests}"
assert final_blender["version"] == summary["version"] == int(app_session["version"]), \
    (final_blender["version"], summary["version"], app_session["version"])

# Blender's edits are in the final mesh (the peer's strokes may have gone over parts of them):
# its raised north cap, its south cap painted metallic and in linear (0.2, 0.5, 0.8), which the
# session holds sRGB-encoded.
p = positions
assert p[:, 2].max() > 1.2, p[:, 2].max()
south = p[:, 2] < -0.6
srgb = np.where(np.array([0.2, 0.5, 0.8]) <= 0.0031308, 12.92 * np.array([0.2, 0.5, 0.8]),
                1.055 * np.array([0.2, 0.5, 0.8]) ** (1 / 2.4) - 0.055)
painted = np.all(np.abs(dict(channels)["albedo"][south] - srgb) < 2e-3, axis=1)
assert painted.mean() > 0.2, f"Blender's albedo paint is missing ({painted.mean():.2f})"
assert (dict(channels)["metallic"][south] == 1.0).mean() > 0.2, "Blender's metallic is missing"
print(f"interop: Blender, csculpt-app and csculpt peer ended bit-identical at version "
      f"{summary['version']} (digest {digests['peer']}), {time.monotonic() - t0:.1f} s")
work.cleanup()
