"""Runs in `blender -b` with a clean user directory: installs the add-on zip the way
Preferences > Add-ons > Install does, enables it, checks it runs from the installed copy with
its bundled library, shares an icosphere and syncs until the harness writes `stop`."""

import json
import os
import sys
import time

import addon_utils
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside  # noqa: E402

zip_path = inside.args()[0]
scripts = os.environ["BLENDER_USER_SCRIPTS"]
inside.check(not os.path.exists(os.path.join(scripts, "addons", "csculpt_blender")),
             "the user directory is not clean")
inside.check(bpy.ops.preferences.addon_install(filepath=zip_path) == {'FINISHED'}, "install")
installed = os.path.join(scripts, "addons", "csculpt_blender")
inside.check(os.path.isfile(os.path.join(installed, "lib", "libzmq.so.5")),
             f"the install has no bundled libzmq: {os.listdir(installed)}")
inside.check(bpy.ops.preferences.addon_enable(module="csculpt_blender") == {'FINISHED'}, "enable")
inside.check(addon_utils.check("csculpt_blender") == (True, True), "the add-on is not enabled")
import csculpt_blender  # noqa: E402
inside.check(csculpt_blender._import_error is None, f"library: {csculpt_blender._import_error}")
lib = csculpt_blender.csculpt.library_path
inside.check(os.path.realpath(lib).startswith(os.path.realpath(installed)),
             f"libcsculpt loaded from {lib}, not from the installed add-on")
with open("/proc/self/maps") as f:
    mapped = sorted({line.split()[-1] for line in f if ".so" in line and
                     any(k in line for k in ("libcsculpt", "libzmq", "libsodium"))})
print("mapped:", *mapped, sep="\n  ")

for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.0)
obj = bpy.context.active_object
inside.check(bpy.ops.csculpt.host() == {'FINISHED'}, "host")
st = bpy.context.window_manager.csculpt
inside.write("install.json", json.dumps({"invite": st.invite, "installed": installed,
                                         "mapped": mapped}))
end = time.monotonic() + 90
while inside.read("stop") is None:
    inside.check(time.monotonic() < end, "no stop within 90 s")
    bpy.ops.csculpt.sync_now()
    inside.write("state-host.json", json.dumps({"version": st.version, "peers": st.peers}))
    time.sleep(0.02)
bpy.ops.csculpt.sync_now()
inside.dump("host", obj)
print("installed add-on: session ran")
