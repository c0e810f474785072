"""Runs inside a windowed Blender for tools/blender_screenshot.sh (not a test):
  blender --factory-startup --enable-event-simulate ... --python tools/blender_screenshot.py -- DIR
Shares a subdivided icosphere in Sculpt Mode with the cSculpt sidebar tab open, writes
DIR/invite, and once another artist's strokes are merged (version >= 3, one peer) and nothing
changed for a second, writes DIR/ready; quits when DIR/quit appears. The add-on's own timer
drives the sync."""

import math
import os
import sys
import time

import bpy
from mathutils import Euler

# The timer driver the windowed Blender tests use (it needs nothing but bpy).
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "blender"))
from drive import drive  # noqa: E402

out = sys.argv[sys.argv.index("--") + 1]
bpy.ops.preferences.addon_enable(module="csculpt_blender")
prefs = bpy.context.preferences.addons["csculpt_blender"].preferences
prefs.artist_name = "blender"
prefs.sync_ms = 100
drawn = []
handle = bpy.types.SpaceView3D.draw_handler_add(lambda: drawn.append(1), (), 'WINDOW',
                                                'POST_PIXEL')


def write(name, text):
    with open(os.path.join(out, name + ".tmp"), "w") as f:
        f.write(text)
    os.replace(os.path.join(out, name + ".tmp"), os.path.join(out, name))


def script():
    while len(drawn) < 2:
        yield
    win = bpy.context.window_manager.windows[0]
    # A clean user directory shows the splash (Quick Setup): Escape closes it.
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=win.width // 2, y=win.height // 2)
    win.event_simulate(type='ESC', value='PRESS')
    win.event_simulate(type='ESC', value='RELEASE')
    yield
    area = next(a for a in win.screen.areas if a.type == 'VIEW_3D')
    region = next(r for r in area.regions if r.type == 'WINDOW')
    ctx = dict(window=win, screen=win.screen, area=area, region=region)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    with bpy.context.temp_override(**ctx):
        bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=6, radius=1.0)
        obj = bpy.context.active_object
        obj.name = "Head"
        bpy.ops.object.shade_smooth()
        bpy.ops.object.mode_set(mode='SCULPT')
        assert bpy.ops.csculpt.host() == {'FINISHED'}
    st = bpy.context.window_manager.csculpt
    write("invite", st.invite)
    space = area.spaces.active
    space.show_region_ui = True          # the sidebar (N)
    space.shading.type = 'SOLID'
    space.shading.color_type = 'VERTEX'  # the colour attribute: the session's albedo
    rv3d = space.region_3d
    rv3d.view_perspective = 'PERSP'
    rv3d.view_rotation = Euler((math.radians(65), 0, math.radians(20))).to_quaternion()
    rv3d.view_location = (0.35, 0, 0)  # the sphere left of the sidebar's middle
    rv3d.view_distance = 5.5
    for _ in range(5):
        yield
    # The sidebar opens on its first tab (Item): a click on the cSculpt tab, the fourth in the
    # tab strip at the sidebar's right edge (Blender 3.4's default theme and font at 1600x900;
    # 3.4 has no Python setter for the active tab).
    ui = next(r for r in area.regions if r.type == 'UI')
    x, y = ui.x + ui.width - 8, ui.y + ui.height - 164
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=x, y=y)
    yield
    win.event_simulate(type='LEFTMOUSE', value='PRESS', x=x, y=y)
    win.event_simulate(type='LEFTMOUSE', value='RELEASE', x=x, y=y)
    yield
    # Away from the sidebar: the cursor over the viewport, as an artist's would be.
    win.event_simulate(type='MOUSEMOVE', value='NOTHING', x=region.x + region.width // 3,
                       y=region.y + region.height // 2)
    last, since = -1, time.monotonic()
    while True:
        if st.version != last:
            last, since = st.version, time.monotonic()
        if st.version >= 3 and st.peers >= 1 and time.monotonic() - since > 1.0:
            break
        yield
    write("ready", str(st.version))
    while not os.path.exists(os.path.join(out, "quit")):
        yield


drive(script(), 0.1)
