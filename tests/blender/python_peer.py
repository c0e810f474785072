"""A plain python3 peer using the *installed* add-on's csculpt.py and bundled libraries (no
LD_LIBRARY_PATH, no CSCULPT_LIBRARY): proves they load from the add-on's directory, joins the
session, moves and paints the north cap, and syncs until Blender shows the same version."""

import json
import os
import sys
import time

import numpy as np

work = os.environ["CSCULPT_TEST_DIR"]
info = json.load(open(os.path.join(work, "install.json")))
installed = info["installed"]
sys.path.insert(0, installed)
import csculpt  # noqa: E402

assert os.path.realpath(csculpt.library_path).startswith(os.path.realpath(installed)), \
    csculpt.library_path
with open("/proc/self/maps") as f:
    maps = {line.split()[-1] for line in f if ".so" in line}
for soname in ("libcsculpt.so.0", "libzmq.so.5", "libsodium.so.23", "libpgm-5.3.so.0",
               "libnorm.so.1", "libgssapi_krb5.so.2"):
    where = [m for m in maps if os.path.basename(m) == soname]
    assert where and all(os.path.realpath(m).startswith(os.path.realpath(installed))
                         for m in where), f"{soname} mapped from {where}"
    print(f"{soname}: {where[0]}")

with csculpt.Session.join(info["invite"], name="python", join_timeout_ms=10000, sync_ms=50) as s:
    with s.base() as base:
        pos = base.positions.ravel().copy()
        ch = {n: c.values.copy() for n, c in base.channels.items()}
    p = pos.reshape(-1, 3)
    cap = p[:, 2] > 0.7
    p[cap, 2] += 0.3
    ch["albedo"][cap] = (1.0, 0.0, 0.0)
    strokes = 1
    end = time.monotonic() + 60
    while True:
        assert time.monotonic() < end, "no convergence within 60 s"
        s.update(pos, ch)
        if s.submit(pos, ch, strokes=strokes):
            strokes = 0
        try:
            host = json.load(open(os.path.join(work, "state-host.json")))
        except (OSError, ValueError):
            host = {"version": -1}
        if s.stats.strokes_acknowledged >= 1 and s.version >= 1 and host["version"] == s.version:
            break
        time.sleep(0.02)
    np.savez(os.path.join(work, "final-python.npz"), co=pos, albedo=ch["albedo"])
    open(os.path.join(work, "stop"), "w").close()
    print("python peer converged at version", s.version)
