"""The windowed Blender of test_holdback.py: shares an icosphere in Sculpt Mode with the Grab
brush, looks at it from the front and says where (in window pixels) the sphere's front is, so
the test can drag there with xdotool as a person would; its timer syncs as usual; it publishes
its state every tick and dumps what it shows when told to stop."""

import math
import os
import sys

import bpy
from mathutils import Euler, Vector
from bpy_extras import view3d_utils

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside  # noqa: E402
from drive import drive  # noqa: E402

st = inside.enable_addon("host")
drawn = []
handle = bpy.types.SpaceView3D.draw_handler_add(lambda: drawn.append(1), (), 'WINDOW', 'POST_PIXEL')


def view3d():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == 'VIEW_3D')
    return dict(window=win, screen=win.screen, area=area,
                region=next(r for r in area.regions if r.type == 'WINDOW'))


def script():
    while len(drawn) < 2:
        yield
    ctx = view3d()
    inside.clear_scene()
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=4, radius=1.0)
    obj = bpy.context.active_object
    with bpy.context.temp_override(**ctx):
        inside.check(bpy.ops.csculpt.host() == {'FINISHED'}, "csculpt.host failed")
        bpy.ops.object.mode_set(mode='SCULPT')
        bpy.ops.wm.tool_set_by_id(name="builtin_brush.Grab")
    ts = bpy.context.scene.tool_settings
    ts.unified_paint_settings.size = ts.sculpt.brush.size = 60
    inside.write("invite", st.invite)
    rv3d = ctx["area"].spaces.active.region_3d
    rv3d.view_perspective = 'ORTHO'
    rv3d.view_rotation = Euler((math.pi / 2, 0, 0)).to_quaternion()  # front: looking along +Y
    rv3d.view_location = (0, 0, 0)
    rv3d.view_distance = 3.0
    for _ in range(5):
        yield
    region, win = ctx["region"], ctx["window"]
    mx, my = view3d_utils.location_3d_to_region_2d(region, rv3d, obj.matrix_world @ Vector((0, -1, 0)))
    # xdotool counts from the window's top left, Blender from the region's bottom left.
    inside.write("target", f"{region.x + mx:.0f} {win.height - (region.y + my):.0f}")
    while inside.read("stop") is None:
        inside.publish("host", obj)
        yield
    inside.dump("host", obj)


drive(script(), 0.05, handle)
