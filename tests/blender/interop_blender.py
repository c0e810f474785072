"""Runs in `blender -b` for test_interop.py (timers do not fire there: csculpt.sync_now drives
the sync). Shares an icosphere in Sculpt Mode, writes `invite`, and once two other artists have
joined (csculpt-app and `csculpt peer`) moves its north cap and paints its south cap (albedo
and metallic). Publishes state-blender.json (version, the session-side digest, strokes) until
the harness writes `stop`; then checks that Blender shows the session's values and dumps them
to final-blender.npz."""

import json
import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside  # noqa: E402
import meshdigest  # noqa: E402

st = inside.enable_addon("blender")
inside.clear_scene()
bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=5, radius=1.0)
obj = bpy.context.active_object
obj.name = "Shared"
bpy.ops.object.mode_set(mode='SCULPT')
inside.check(bpy.ops.csculpt.host() == {'FINISHED'}, "csculpt.host failed")
inside.check(st.active and st.invite.startswith("csculpt1:"), f"no invite: {st.status}")

import csculpt_blender  # noqa: E402  (after enabling: the add-on's own module)

host = csculpt_blender._host


def session_arrays():
    """The session-side arrays Blender's add-on holds (albedo sRGB-encoded, as in the session):
    positions, then every channel in the session's order."""
    return host.positions, [(name, host.channels[name]) for name, _width in host.layout]


def publish(edited):
    positions, channels = session_arrays()
    stats = host.session.stats
    with host.session.base() as base:
        base_digest = meshdigest.mesh_digest(
            base.positions.ravel(), [(n, c.values) for n, c in base.channels.items()])
    state = {"version": st.version, "digest": meshdigest.mesh_digest(positions, channels),
             "base_digest": base_digest, "peers": st.peers, "strokes": st.strokes,
             "acked": stats.strokes_acknowledged, "refused": st.refused, "errors": st.errors,
             "edited": edited}
    inside.write("state-blender.json", json.dumps(state))


inside.write("original-digest", meshdigest.mesh_digest(*session_arrays()))
inside.write("invite", st.invite)
end = time.monotonic() + 50
edited = False
last = 0.0
while inside.read("stop") is None:
    inside.check(time.monotonic() < end, "no stop within 50 s")
    bpy.ops.csculpt.sync_now()
    if not edited and st.peers >= 2:
        # Both others are in: this artist's edits, merged with theirs.
        inside.move(obj, lambda p: p[:, 2] > 0.6, (0.0, 0.0, 0.25))
        inside.paint(obj, lambda p: p[:, 2] < -0.6, rgb=(0.2, 0.5, 0.8), metallic=1.0)
        edited = True
    if time.monotonic() - last > 0.1:
        publish(edited)
        last = time.monotonic()
    time.sleep(0.02)
bpy.ops.csculpt.sync_now()
publish(edited)

# What Blender shows is the session's values (albedo converted to linear for Blender).
shown = inside.shown(obj)
for key in host.keys():
    inside.check(np.array_equal(shown[key].view(np.uint32),
                                host._to_blender(key).view(np.uint32)),
                 f"Blender does not show the session's {key}")
positions, channels = session_arrays()
np.savez(inside.path("final-blender.npz"), positions=positions,
         **{f"channel_{name}": values for name, values in channels},
         order=np.array([name for name, _ in channels]))
inside.write("done-blender", "1")
