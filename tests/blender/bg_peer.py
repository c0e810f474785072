"""Runs in `blender -b` (timers do not fire there: csculpt.sync_now drives the sync).
  bg_peer.py -- host   shares an icosphere, moves its north cap, paints metallic on it
  bg_peer.py -- join   joins with the invite file, paints the south cap and moves the equator
  bg_peer.py -- checks a bad invite, an unanswered invite and a dyntopo/non-mesh object are
                       refused with their messages; in a session, shape keys, multires and a
                       changed vertex count are refused while the session stays
Each sharing role publishes state-<role>.json until the harness writes `stop`, then dumps what
Blender shows to final-<role>.npz."""

import os
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside  # noqa: E402

role = inside.args()[0]
st = inside.enable_addon(role)


def sphere(name):
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
    obj = bpy.context.active_object
    obj.name = name
    return obj


def run_until_stop(obj):
    end = time.monotonic() + 120
    last = 0.0
    while inside.read("stop") is None:
        inside.check(time.monotonic() < end, "no stop within 120 s")
        bpy.ops.csculpt.sync_now()
        if time.monotonic() - last > 0.1:
            inside.publish(role, obj)
            last = time.monotonic()
        time.sleep(0.02)
    bpy.ops.csculpt.sync_now()
    inside.dump(role, obj)


if role == "host":
    inside.clear_scene()
    obj = sphere("Shared")
    bpy.ops.object.mode_set(mode='SCULPT')
    inside.check(bpy.ops.csculpt.host() == {'FINISHED'}, "csculpt.host failed")
    inside.check(st.active and st.invite.startswith("csculpt1:"), f"no invite: {st.status}")
    inside.write("invite", st.invite)
    inside.wait_file("joined")
    inside.move(obj, lambda p: p[:, 2] > 0.6, (0.0, 0.0, 0.25))
    inside.paint(obj, lambda p: p[:, 2] > 0.6, metallic=1.0)
    run_until_stop(obj)
elif role == "join":
    inside.clear_scene()
    invite = inside.wait_file("invite")
    inside.check(bpy.ops.csculpt.join(invite=invite) == {'FINISHED'}, "csculpt.join failed")
    obj = bpy.context.active_object
    inside.check(obj is not None and obj.name == st.object_name,
                 f"the joined object is not the active one ({obj} vs {st.object_name!r})")
    inside.check(len(obj.data.vertices) == 642, f"{len(obj.data.vertices)} vertices")
    inside.check(obj.active_material is not None and obj.active_material.name == "cSculpt",
                 "no cSculpt material on the joined object")
    bpy.ops.object.mode_set(mode='SCULPT')
    inside.write("joined", "1")
    inside.paint(obj, lambda p: p[:, 2] < -0.6, rgb=(1.0, 0.0, 0.0), roughness=0.2)
    inside.move(obj, lambda p: (p[:, 0] > 0.9), (0.2, 0.0, 0.0))
    run_until_stop(obj)
elif role == "checks":
    inside.clear_scene()
    bpy.context.preferences.addons["csculpt_blender"].preferences.join_timeout_s = 1.0
    # A malformed invite: the operator reports an error (RuntimeError in a script), Blender runs.
    try:
        bpy.ops.csculpt.join(invite="this is not an invite")
        raise AssertionError("a malformed invite was accepted")
    except RuntimeError as e:
        print("bad invite refused:", e)
        inside.check("not a cSculpt invite" in str(e), f"unclear message: {e}")
    inside.check(not st.active and "not a cSculpt invite" in st.status, st.status)
    # A well-formed invite nobody answers.
    try:
        bpy.ops.csculpt.join(invite="csculpt1:" + "0" * 144 + "@tcp://127.0.0.1:9")
        raise AssertionError("an unanswered invite was accepted")
    except RuntimeError as e:
        print("unanswered invite:", e)
        inside.check("No answer from the session" in str(e), f"unclear message: {e}")
    # Dynamic topology: refused before any session starts.
    obj = sphere("Dyntopo")
    bpy.ops.object.mode_set(mode='SCULPT')
    bpy.ops.sculpt.dynamic_topology_toggle()
    inside.check(obj.use_dynamic_topology_sculpting, "dyntopo did not turn on")
    try:
        bpy.ops.csculpt.host()
        raise AssertionError("a dyntopo object was shared")
    except RuntimeError as e:
        print("dyntopo refused:", e)
        inside.check("Dynamic topology is on" in str(e), f"unclear message: {e}")
    inside.check("Dynamic topology" in st.refused and not st.active, st.refused)
    bpy.ops.sculpt.dynamic_topology_toggle()
    bpy.ops.object.mode_set(mode='OBJECT')
    # A non-mesh object.
    bpy.ops.object.empty_add()
    try:
        bpy.ops.csculpt.host()
        raise AssertionError("an empty was shared")
    except RuntimeError as e:
        inside.check("not a mesh" in str(e), f"unclear message: {e}")
    # In a session: refusals keep the session and lose nothing.
    inside.clear_scene()
    obj = sphere("Refusals")
    bpy.ops.csculpt.host()
    inside.check(st.active, st.status)
    moved = inside.move(obj, lambda p: p[:, 2] > 0.8, (0, 0, 0.1))
    end = time.monotonic() + 20
    while st.version < 1 and time.monotonic() < end:
        bpy.ops.csculpt.sync_now()
        time.sleep(0.02)
    inside.check(st.strokes == 1 and st.version >= 1 and not st.refused,
                 f"stroke not taken and merged: {st.status}")
    # The attribution view: a colour attribute switched into the cSculpt material.
    st.show_attribution = True
    bpy.ops.csculpt.sync_now()
    mix = bpy.data.materials["cSculpt"].node_tree.nodes["csculpt attribution view"]
    inside.check("csculpt_attribution" in obj.data.attributes and
                 mix.inputs["Fac"].default_value == 1.0, "no attribution view")
    inside.check(obj.data.color_attributes.active_color.name != "csculpt_attribution",
                 "the attribution attribute became the one Paint paints")
    for what, on, off, words in (
            ("shape keys", lambda: obj.shape_key_add(name="Basis"),
             lambda: obj.shape_key_clear(), "shape keys"),
            ("multires", lambda: obj.modifiers.new("M", 'MULTIRES'),
             lambda: obj.modifiers.remove(obj.modifiers["M"]), "Multiresolution"),
            ("vertex count", lambda: obj.data.vertices.add(1),
             None, "vertices, the session's has")):
        on()
        bpy.ops.csculpt.sync_now()
        print(f"{what}: {st.refused}")
        inside.check(words in st.refused and st.active and st.status.startswith("Refused"),
                     f"{what} not refused clearly: {st.refused!r} / {st.status!r}")
        if off:
            off()
            bpy.ops.csculpt.sync_now()
            inside.check(not st.refused, f"still refused after undoing {what}: {st.refused}")
    # The session's values are all still there (nothing lost): the stroke is in its base.
    import csculpt_blender
    with csculpt_blender._host.session.base() as base:
        inside.check(np.all(base.positions[moved, 2] > 0.85), "the stroke before the refusals "
                     "is not in the session")
    bpy.ops.csculpt.leave()
    inside.check(not st.active, "still active after leave")
    print("checks: all passed; Blender still running")
else:
    raise SystemExit(f"unknown role {role}")
