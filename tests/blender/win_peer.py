"""Runs in a windowed Blender under Xvfb: the add-on's own timer drives the sync; real
`sculpt.brush_stroke` strokes (a stroke path over the surface, with a window/area/region
override, from a timer after the first draw).
  win_peer.py -- host   shares an icosphere, draws a horizontal Draw stroke
  win_peer.py -- join   joins, paints a vertical Paint stroke across the host's stroke
Both publish state-<role>.json; on `undo` the host undoes its stroke with csculpt.undo; on
`mid`/`stop` each dumps what Blender shows (mid-/final-<role>.npz) and, on `stop`, quits."""

import json
import math
import os
import sys
import time

import bpy
import numpy as np
from bpy_extras import view3d_utils
from mathutils import Euler, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside  # noqa: E402
from drive import drive  # noqa: E402

role = inside.args()[0]
st = inside.enable_addon(role)
drawn = []


def on_draw():
    drawn.append(1)


handle = bpy.types.SpaceView3D.draw_handler_add(on_draw, (), 'WINDOW', 'POST_PIXEL')


def view3d():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == 'VIEW_3D')
    region = next(r for r in area.regions if r.type == 'WINDOW')
    return dict(window=win, screen=win.screen, area=area, region=region)


def stroke(ctx, obj, points3d, brush_name, tool, colour=None):
    """One brush_stroke along surface points (object space on a unit sphere)."""
    with bpy.context.temp_override(**ctx):
        bpy.ops.wm.tool_set_by_id(name=tool)
    ts = bpy.context.scene.tool_settings
    brush = ts.sculpt.brush
    inside.check(brush is not None and brush.name == brush_name, f"brush {brush}")
    ups = ts.unified_paint_settings
    ups.size = brush.size = 30
    brush.strength = 0.6
    if colour is not None:
        brush.color = colour
        ups.color = colour
    region, rv3d = ctx["region"], ctx["area"].spaces.active.region_3d
    path = []
    for i, p in enumerate(points3d):
        world = obj.matrix_world @ Vector(p)
        mouse = view3d_utils.location_3d_to_region_2d(region, rv3d, world)
        path.append({"name": "", "location": world, "mouse": mouse, "mouse_event": mouse,
                     "pressure": 1.0, "size": 30.0, "pen_flip": False, "x_tilt": 0.0,
                     "y_tilt": 0.0, "time": i * 0.02, "is_start": i == 0})
    with bpy.context.temp_override(**ctx):
        # An undo step, as a stroke by hand pushes (Blender's own undo is tested below).
        result = bpy.ops.sculpt.brush_stroke('EXEC_DEFAULT', True, stroke=path, mode='NORMAL')
    inside.check(result == {'FINISHED'}, f"brush_stroke: {result}")


def front(x, z):
    return (x, -math.sqrt(max(1.0 - x * x - z * z, 0.0)), z)


def script():
    while len(drawn) < 2:
        yield
    ctx = view3d()
    km = bpy.context.window_manager.keyconfigs.addon.keymaps["Sculpt"]
    keys = {(k.idname, k.type, k.ctrl, k.shift) for k in km.keymap_items}
    inside.check({("csculpt.undo", 'Z', True, False), ("csculpt.redo", 'Z', True, True)} <= keys,
                 f"Ctrl+Z / Ctrl+Shift+Z not bound in Sculpt Mode: {keys}")
    inside.clear_scene()
    if role == "host":
        with bpy.context.temp_override(**ctx):
            bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
            obj = bpy.context.active_object
            inside.check(bpy.ops.csculpt.host() == {'FINISHED'}, "csculpt.host failed")
        inside.write("invite", st.invite)
    else:
        while inside.read("invite") is None:
            yield
        with bpy.context.temp_override(**ctx):
            inside.check(bpy.ops.csculpt.join(invite=inside.read("invite")) == {'FINISHED'},
                         "csculpt.join failed")
        obj = bpy.context.active_object
    np.savez(inside.path(f"orig-{role}.npz"), **inside.shown(obj))
    with bpy.context.temp_override(**ctx):
        bpy.ops.ed.undo_push(message="before Sculpt Mode")
        bpy.ops.object.mode_set('EXEC_DEFAULT', True, mode='SCULPT')
    rv3d = ctx["area"].spaces.active.region_3d
    rv3d.view_perspective = 'ORTHO'
    rv3d.view_rotation = Euler((math.pi / 2, 0, 0)).to_quaternion()  # front: looking along +Y
    rv3d.view_location = (0, 0, 0)
    rv3d.view_distance = 3.0
    inside.write(f"ready-{role}", "1")
    other = "join" if role == "host" else "host"
    while inside.read(f"ready-{other}") is None:
        yield
    for _ in range(5):  # a few redraws with the new view
        yield
    import csculpt_blender
    if role == "host":
        stroke(ctx, obj, [front(x, 0.3) for x in np.linspace(-0.5, 0.5, 24)], "SculptDraw",
               "builtin_brush.Draw")
        csculpt_blender._host.set_presence(front(0.0, 0.3), 0.1, False)
    else:
        stroke(ctx, obj, [front(0.0, z) for z in np.linspace(-0.2, 0.7, 24)], "Paint",
               "builtin_brush.Paint", colour=(0.0, 0.0, 1.0))
        csculpt_blender._host.set_presence(front(0.0, -0.2), 0.1, False)
    undone = False
    mid = False
    native = False
    name = obj.name
    while inside.read("stop") is None:
        if not native and inside.read("native") is not None:
            # Both peers agree here (the test waited): keep that state for the checks, then the
            # host runs Blender's own undo back past the switch into Sculpt Mode, which reloads
            # the file state and kills every stored reference.
            np.savez(inside.path(f"undone-{role}.npz"), **inside.shown(obj))
            if role == "host":
                steps = 0
                with bpy.context.temp_override(**ctx):
                    # Back through the strokes until the object is in Object Mode again.
                    while steps < 6 and bpy.data.objects[name].mode != 'OBJECT':
                        if bpy.ops.ed.undo() != {'FINISHED'}:
                            break
                        steps += 1
                print(f"blender undo: {steps} steps, now in {bpy.data.objects[name].mode} mode",
                      flush=True)
                inside.write("native-steps", f"{steps} {bpy.data.objects[name].mode}")
            native = True
            for _ in range(3):
                yield
            obj = bpy.data.objects[name]
        if role == "host" and not undone and inside.read("undo") is not None:
            np.savez(inside.path(f"mid-{role}.npz"), **inside.shown(obj))
            mid = True
            with bpy.context.temp_override(**ctx):
                inside.check(bpy.ops.csculpt.undo() == {'FINISHED'}, "csculpt.undo failed")
            undone = True
        if role == "join" and not mid and inside.read("undo") is not None:
            np.savez(inside.path(f"mid-{role}.npz"), **inside.shown(obj))
            mid = True
        inside.publish(role, obj, {"undone": undone, "mid": mid, "native": native,
                                   "presence": len(csculpt_blender._presence),
                                   "undo_depth": st.undo_depth})
        yield
    inside.dump(role, obj)


drive(script(), 0.1, handle)
