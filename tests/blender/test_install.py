#!/usr/bin/env python3
"""The add-on zip installs into a clean Blender user directory (BLENDER_USER_CONFIG and
BLENDER_USER_SCRIPTS in a temporary directory; addon_install + addon_enable), loads
libcsculpt from the installed copy with LD_LIBRARY_PATH unset, and a session works from it:
Blender shares, a plain python3 peer using the installed csculpt.py and bundled libraries
(which must be the ones mapped: libzmq, libsodium, ...) joins and edits, and Blender shows
its edit bit for bit."""

import os
import subprocess
import sys
import time

import numpy as np

import blenderkit as kit

exe = kit.blender_or_skip()
zip_path = kit.addon_zip()
work = kit.Workdir("install")
t0 = time.monotonic()
log = work.file("host.log")
env = work.user_dirs("host", unpack_addon=False)
host = kit.start(exe, "install_peer.py", [zip_path], env, log=log)
try:
    end = time.monotonic() + 60
    while not os.path.exists(work.file("install.json")):
        assert host.poll() is None and time.monotonic() < end, "Blender did not share"
        time.sleep(0.1)
    peer = subprocess.run([sys.executable, os.path.join(kit.HERE, "python_peer.py")], env=env,
                          timeout=120)
finally:
    open(work.file("stop"), "w").close()
    codes = kit.wait_all([host], [log], 60)
print("exit codes", codes, peer.returncode, f"{time.monotonic() - t0:.1f} s")
assert codes == [0] and peer.returncode == 0, (codes, peer.returncode)
shown = np.load(work.file("final-host.npz"))
python = np.load(work.file("final-python.npz"))
assert np.array_equal(shown["co"].view(np.uint32), python["co"].view(np.uint32)), "positions"
rgba = shown["albedo"].reshape(-1, 4)
cap = python["albedo"][:, 1] == 0.0
assert cap.sum() > 10 and np.all(rgba[cap, 0] == 1.0) and np.all(rgba[cap, 1] == 0.0)
print("installed add-on: Blender shows the python peer's edit bit for bit")
work.cleanup()
