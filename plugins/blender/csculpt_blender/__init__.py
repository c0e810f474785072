"""cSculpt for Blender: several artists sculpt and paint one mesh together, each in their own
Blender, over a serverless cSculpt session (libcsculpt, the C ABI, through csculpt.py).

Operators (F3 or the sidebar's cSculpt tab): csculpt.host, csculpt.join, csculpt.leave,
csculpt.sync_now, csculpt.undo, csculpt.redo. Scripts read the state from
bpy.context.window_manager.csculpt. See README.md beside this package's source.
"""

bl_info = {
    "name": "cSculpt collaborative sculpting",
    "author": "cSculpt",
    "version": (0, 3, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > cSculpt",
    "description": "Sculpt and paint one mesh together with other artists, live",
    "category": "Sculpt",
}

import getpass
import math
import time

import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty, StringProperty

try:
    from . import csculpt
    from . import host as host_module
    _import_error = None
except ImportError as e:  # the bundled library would not load: say so in the panel
    csculpt = host_module = None
    _import_error = str(e)

_host = None          # the session of this Blender process (one at a time)
_draw_handle = None
_presence = []        # the other artists' cursors, refreshed on each step
_watching = False


def prefs(context=None):
    context = context or bpy.context
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


# Every peer of a session is connected to by every other, so a host and its joiners alike
# must listen where a colleague's machine reaches them.
LISTEN_EVERYWHERE = "tcp://*:*"


def _pref(name, default):
    p = prefs()
    return getattr(p, name, default) if p else default


# ---- State shown to the artist and to scripts ---------------------------------------------


def _attribution_changed(self, context):
    if _host is None:
        return
    _host.show_attribution = self.show_attribution
    mat = bpy.data.materials.get(host_module.MATERIAL_NAME)
    if mat and mat.node_tree:
        mix = mat.node_tree.nodes.get("csculpt attribution view")
        if mix:
            mix.inputs["Fac"].default_value = 1.0 if self.show_attribution else 0.0
    obj = _host.check()  # None (and the refusal in words) when the mesh cannot sync
    if self.show_attribution and obj is not None:
        _host.write_attribution(obj.data)


class CsculptState(bpy.types.PropertyGroup):
    active: BoolProperty(name="In a session", default=False)
    invite: StringProperty(name="Invite", description="What other artists join with (it "
                           "carries the session's keys: share it only with them)")
    join_invite: StringProperty(name="Invite to join", description="Paste an invite here")
    object_name: StringProperty(name="Object")
    version: IntProperty(name="Version", description="The agreed version shown")
    peers: IntProperty(name="Peers", description="Other artists in the session")
    peer_lines: StringProperty(name="Peer list")
    merger: StringProperty(name="Merger", description="Who merges everyone's strokes")
    latency_ms: FloatProperty(name="Latency (ms)", default=-1.0)
    dropped: IntProperty(name="Dropped messages")
    status: StringProperty(name="Status")
    errors: StringProperty(name="Errors")
    events: StringProperty(name="Events", description="Peers joining, leaving, merging")
    refused: StringProperty(name="Refused", description="Why the object does not sync now")
    undo_depth: IntProperty(name="Undo depth")
    redo_depth: IntProperty(name="Redo depth")
    strokes: IntProperty(name="Strokes recorded")
    show_attribution: BoolProperty(name="Attribution view", default=False,
                                   description="Colour the mesh by who changed what (material "
                                   "preview / render)", update=_attribution_changed)


def _state(context=None):
    return (context or bpy.context).window_manager.csculpt


def _refresh_state():
    """Copies the session's state into window_manager.csculpt (panel and scripts read it)."""
    global _presence
    st = _state()
    if _host is None:
        st.active = False
        return
    s = _host.session
    stats = s.stats
    peers = s.peers()
    st.active = True
    st.version = int(s.version)
    live = [p for p in peers if p.state != csculpt.PeerState.LEFT]
    st.peers = len(live)
    names = {stats.id: "you"}
    names.update({p.id: p.name or f"{p.id:x}" for p in peers})
    st.merger = names.get(stats.merger, f"{stats.merger:x}")
    lat = [p.latency_ms for p in live if p.latency_ms >= 0]
    st.latency_ms = max(lat) if lat else -1.0
    st.peer_lines = "\n".join(
        f"{p.name or format(p.id, 'x')}: {p.state.name.lower() if hasattr(p.state, 'name') else p.state}"
        f"{', merges' if p.merger else ''}"
        f"{f', {p.latency_ms:.0f} ms' if p.latency_ms >= 0 else ''}" for p in peers)
    st.dropped = int(stats.messages_dropped)
    st.errors = "\n".join(_host.errors)
    st.events = "\n".join(_host.log)
    st.refused = _host.refused or ""
    undo, redo = s.undo_depth
    st.undo_depth, st.redo_depth = undo, redo
    st.strokes = _host.strokes
    held = " (held: stroke under way)" if _host.stroke_active else ""
    deferred = " (remote changes wait for the update limit)" if _host.deferred else ""
    st.status = ("Refused: " + _host.refused) if _host.refused else \
        f"Synced at version {s.version} with {len(live)} other artist(s){held}{deferred}"
    try:
        _presence = s.presence()
    except csculpt.CsculptError:
        _presence = []


def _redraw():
    wm = bpy.context.window_manager
    for window in wm.windows:
        for area in window.screen.areas:
            if area.type == 'VIEW_3D':
                area.tag_redraw()


def _step():
    """One sync step with its errors put into words; returns whether it ran cleanly."""
    if _host is None:
        return False
    try:
        _host.step()
        ok = True
    except csculpt.CsculptError as e:
        _host.errors.append(f"{type(e).__name__}: {e}")
        ok = False
    _refresh_state()
    return ok


def _timer():
    if _host is None:
        return None
    _step()
    try:
        _redraw()
    except Exception:
        pass
    return max(_pref("interval_ms", 50), 10) / 1000.0


# ---- Presence: others' cursors drawn, this artist's sent ------------------------------------


def _draw_cursors():
    if _host is None or not _presence:
        return
    import gpu
    from gpu_extras.batch import batch_for_shader
    from mathutils import Vector
    obj = _host.object()
    rv3d = bpy.context.region_data
    if obj is None or rv3d is None:
        return
    mw = obj.matrix_world
    scale = sum(mw.to_scale()) / 3.0
    rot = rv3d.view_rotation
    right, up = rot @ Vector((1, 0, 0)), rot @ Vector((0, 1, 0))
    try:
        shader = gpu.shader.from_builtin('3D_UNIFORM_COLOR')
    except ValueError:
        shader = gpu.shader.from_builtin('UNIFORM_COLOR')
    gpu.state.blend_set('ALPHA')
    for p in _presence:
        if not p.visible:
            continue
        centre = mw @ Vector(p.position)
        r = max(p.radius * scale, 1e-4)
        points = [centre + r * (math.cos(a) * right + math.sin(a) * up)
                  for a in (2 * math.pi * i / 40 for i in range(41))]
        gpu.state.line_width_set(3.0 if p.active else 1.5)
        batch = batch_for_shader(shader, 'LINE_STRIP', {"pos": points})
        shader.bind()
        shader.uniform_float("color", (*p.colour, 1.0 if p.active else 0.7))
        batch.draw(shader)
    gpu.state.line_width_set(1.0)
    gpu.state.blend_set('NONE')


def _cursor_under(context, event):
    """(position in mesh coordinates, radius in mesh units) of the brush under the mouse, or
    None when it is not over the session's object."""
    from bpy_extras import view3d_utils
    obj = _host.object() if _host else None
    if obj is None or obj.type != 'MESH':
        return None
    x, y = event.mouse_x, event.mouse_y
    for area in context.window.screen.areas:
        if area.type != 'VIEW_3D':
            continue
        for region in area.regions:
            if region.type != 'WINDOW' or not (region.x <= x < region.x + region.width and
                                               region.y <= y < region.y + region.height):
                continue
            rv3d = region.data
            coord = (x - region.x, y - region.y)
            origin = view3d_utils.region_2d_to_origin_3d(region, rv3d, coord)
            direction = view3d_utils.region_2d_to_vector_3d(region, rv3d, coord)
            inv = obj.matrix_world.inverted()
            hit, loc, _normal, _index = obj.ray_cast(inv @ origin,
                                                     (inv.to_3x3() @ direction).normalized())
            if not hit:
                return None
            brush = context.tool_settings.sculpt.brush if context.tool_settings.sculpt else None
            scale = sum(obj.matrix_world.to_scale()) / 3.0 or 1.0
            radius = 0.1
            if brush is not None:
                if brush.use_locked_size == 'SCENE':
                    radius = brush.unprojected_radius / scale
                else:
                    ups = context.tool_settings.unified_paint_settings
                    pixels = ups.size if ups.use_unified_size else brush.size
                    world = obj.matrix_world @ loc
                    edge = view3d_utils.region_2d_to_location_3d(
                        region, rv3d, (coord[0] + pixels, coord[1]), world)
                    radius = (edge - world).length / scale
            return tuple(loc), radius
    return None


class CSCULPT_OT_watch(bpy.types.Operator):
    """Watches the artist's input (never consumes it): a stroke's start and end, so remote
    changes wait until it ends, and the brush position sent as this artist's presence"""
    bl_idname = "csculpt.watch"
    bl_label = "cSculpt input watcher"
    bl_options = {'INTERNAL'}

    def invoke(self, context, event):
        global _watching
        if _watching or context.window is None:
            return {'CANCELLED'}
        _watching = True
        self._last = 0.0
        context.window_manager.modal_handler_add(self)
        return {'RUNNING_MODAL'}

    def modal(self, context, event):
        global _watching
        if _host is None:
            _watching = False
            return {'CANCELLED', 'PASS_THROUGH'}
        kind = event.type
        if kind.startswith('TIMER') or kind == 'NONE':
            return {'PASS_THROUGH'}
        # A stroke consumes the events until it ends: the next one we see means it has.
        _host.stroke_active = False
        if kind == 'LEFTMOUSE' and event.value == 'PRESS' and context.mode == 'SCULPT':
            _host.stroke_active = True
        now = time.monotonic()
        if kind in ('MOUSEMOVE', 'LEFTMOUSE') and now - self._last > 0.03:
            self._last = now
            try:
                hit = _cursor_under(context, event)
                if hit is None:
                    _host.set_presence((0.0, 0.0, 0.0), 0.0, False, visible=False)
                else:
                    _host.set_presence(hit[0], hit[1], _host.stroke_active)
            except Exception:  # presence is best effort: never break the artist's input
                pass
        return {'PASS_THROUGH'}


def _start_watching():
    global _watching
    wm = bpy.context.window_manager
    if _watching or not wm.windows:
        return
    window = wm.windows[0]
    try:
        with bpy.context.temp_override(window=window, screen=window.screen):
            bpy.ops.csculpt.watch('INVOKE_DEFAULT')
    except Exception:
        pass


# ---- Session lifecycle --------------------------------------------------------------------


def _session_options():
    options = {"name": _pref("artist_name", "") or getpass.getuser(),
               "sync_ms": _pref("sync_ms", 250)}
    bind = _pref("bind", LISTEN_EVERYWHERE)
    if bind:
        options["bind"] = bind
    return options


def _begin(session, obj, context):
    """Shows the session on `obj` and starts the timer, watcher and cursor drawing."""
    global _host, _draw_handle
    name = host_module.albedo_attribute_name(obj.data)
    h = host_module.Host(session, obj.name, name, big_mesh=_pref("big_mesh", 200_000),
                         min_update_s=_pref("min_update_s", 0.5))
    h.start()
    _host = h
    host_module.ensure_material(obj)
    st = _state(context)
    st.invite = session.invite
    st.object_name = obj.name
    st.errors = st.refused = ""
    st.show_attribution = False
    _refresh_state()
    if not bpy.app.timers.is_registered(_timer):
        bpy.app.timers.register(_timer, first_interval=0.05, persistent=True)
    if _draw_handle is None and not bpy.app.background:
        _draw_handle = bpy.types.SpaceView3D.draw_handler_add(_draw_cursors, (), 'WINDOW',
                                                              'POST_VIEW')
    if not bpy.app.background:
        _start_watching()


def _end():
    global _host, _draw_handle, _presence
    h, _host = _host, None
    _presence = []
    if bpy.app.timers.is_registered(_timer):
        bpy.app.timers.unregister(_timer)
    if _draw_handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_draw_handle, 'WINDOW')
        _draw_handle = None
    if h is not None:
        try:
            h.session.leave()
        finally:
            h.session.close()


def _library_ok(op):
    if _import_error:
        op.report({'ERROR'}, f"cSculpt cannot load its library: {_import_error}")
        return False
    return True


class CSCULPT_OT_host(bpy.types.Operator):
    """Share the active mesh object in a new session; the invite is shown and copied to the
    clipboard"""
    bl_idname = "csculpt.host"
    bl_label = "Share Mesh"
    bl_options = {'REGISTER'}

    @classmethod
    def poll(cls, context):
        return _host is None and context.active_object is not None

    def execute(self, context):
        if not _library_ok(self):
            return {'CANCELLED'}
        obj = context.active_object
        why = host_module.refusal(obj)
        if why:
            _state(context).refused = why
            _state(context).status = "Not shared: " + why
            self.report({'ERROR'}, why)
            return {'CANCELLED'}
        try:
            with host_module.session_mesh_from_blender(obj.data) as mesh:
                session = csculpt.Session.create(mesh, **_session_options())
            _begin(session, obj, context)
        except (csculpt.CsculptError, host_module.Refused) as e:
            _state(context).status = f"Could not share: {e}"
            self.report({'ERROR'}, f"Could not share '{obj.name}': {e}")
            return {'CANCELLED'}
        context.window_manager.clipboard = session.invite
        self.report({'INFO'}, f"Sharing '{obj.name}'; invite copied to the clipboard")
        return {'FINISHED'}


class CSCULPT_OT_join(bpy.types.Operator):
    """Join a session from its invite: a new object holds the session's mesh, material and
    attribution, and becomes the active object"""
    bl_idname = "csculpt.join"
    bl_label = "Join Session"
    bl_options = {'REGISTER'}

    invite: StringProperty(name="Invite", description="The invite (empty: the panel's field, "
                           "else the clipboard)")

    @classmethod
    def poll(cls, context):
        return _host is None

    def execute(self, context):
        if not _library_ok(self):
            return {'CANCELLED'}
        st = _state(context)
        invite = (self.invite or st.join_invite or context.window_manager.clipboard).strip()
        try:
            session = csculpt.Session.join(
                invite, join_timeout_ms=int(_pref("join_timeout_s", 10) * 1000),
                **_session_options())
        except csculpt.CsculptError as e:
            kind = ("That is not a cSculpt invite" if isinstance(e, csculpt.InvalidInput)
                    else "No answer from the session" if isinstance(e, csculpt.IoError)
                    else "Could not join")
            st.status = f"{kind}: {e}"
            self.report({'ERROR'}, f"{kind}: {e}")
            return {'CANCELLED'}
        try:
            with session.base() as base:
                mesh = host_module.new_blender_mesh("cSculpt session", base)
            obj = bpy.data.objects.new("cSculpt session", mesh)
            (context.collection or context.scene.collection).objects.link(obj)
            for other in context.view_layer.objects:
                other.select_set(False)
            obj.select_set(True)
            context.view_layer.objects.active = obj
            _begin(session, obj, context)
        except Exception as e:
            session.close()
            st.status = f"Could not show the session's mesh: {e}"
            self.report({'ERROR'}, st.status)
            return {'CANCELLED'}
        self.report({'INFO'}, f"Joined: '{obj.name}' holds the session's mesh")
        return {'FINISHED'}


class _InSession:
    @classmethod
    def poll(cls, context):
        return _host is not None


class CSCULPT_OT_leave(_InSession, bpy.types.Operator):
    """Leave the session; the object keeps its current shape and colours"""
    bl_idname = "csculpt.leave"
    bl_label = "Leave Session"

    def execute(self, context):
        _end()
        st = _state(context)
        st.active = False
        st.invite = ""
        st.status = "Left the session"
        st.peers = 0
        return {'FINISHED'}


class CSCULPT_OT_sync_now(_InSession, bpy.types.Operator):
    """One sync step now (scripts and background runs call this: timers do not fire there)"""
    bl_idname = "csculpt.sync_now"
    bl_label = "Sync Now"

    def execute(self, context):
        ok = _step()
        if not ok:
            self.report({'WARNING'}, _host.errors[-1] if _host and _host.errors else "failed")
        return {'FINISHED'}


class _UndoRedo:
    @classmethod
    def poll(cls, context):
        # In Sculpt Mode on the session's object only; elsewhere Ctrl+Z is Blender's undo.
        return (_host is not None and context.mode == 'SCULPT' and
                context.active_object is not None and
                context.active_object.name == _host.object_name)

    def execute(self, context):
        try:
            changed = self.run()
        except host_module.Refused as e:
            self.report({'ERROR'}, str(e))
            return {'CANCELLED'}
        except csculpt.CsculptError as e:
            self.report({'ERROR'}, f"{self.bl_label} failed: {e}")
            return {'CANCELLED'}
        _refresh_state()
        if not changed:
            self.report({'INFO'}, self.nothing)
        return {'FINISHED'}


class CSCULPT_OT_undo(_UndoRedo, bpy.types.Operator):
    """Undo your latest stroke in the session: it goes for everyone, other artists' work
    stays"""
    bl_idname = "csculpt.undo"
    bl_label = "Undo My Stroke"
    nothing = "Nothing of yours to undo in this session"

    def run(self):
        return _host.undo()


class CSCULPT_OT_redo(_UndoRedo, bpy.types.Operator):
    """Redo your latest undone stroke in the session"""
    bl_idname = "csculpt.redo"
    bl_label = "Redo My Stroke"
    nothing = "Nothing of yours to redo in this session"

    def run(self):
        return _host.redo()


# ---- UI -----------------------------------------------------------------------------------


class CSCULPT_PT_panel(bpy.types.Panel):
    bl_label = "cSculpt"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "cSculpt"

    def draw(self, context):
        layout = self.layout
        st = _state(context)
        if _import_error:
            box = layout.box()
            box.alert = True
            for line in _wrap(f"The cSculpt library does not load: {_import_error}"):
                box.label(text=line)
            return
        if _host is None:
            layout.operator("csculpt.host")
            layout.separator()
            layout.prop(st, "join_invite", text="")
            layout.operator("csculpt.join")
            if st.status:
                for line in _wrap(st.status):
                    layout.label(text=line)
            return
        row = layout.row(align=True)
        row.prop(st, "invite", text="Invite")
        col = layout.column(align=True)
        col.label(text=f"Object: {st.object_name}")
        col.label(text=f"Version {st.version}   merger: {st.merger}")
        col.label(text=f"Peers: {st.peers}   latency: "
                  f"{'-' if st.latency_ms < 0 else f'{st.latency_ms:.0f} ms'}")
        col.label(text=f"Dropped messages: {st.dropped}")
        for line in st.peer_lines.splitlines() + st.events.splitlines()[-3:]:
            col.label(text="  " + line)
        if st.refused:
            box = layout.box()
            box.alert = True
            for line in _wrap(st.refused):
                box.label(text=line)
        elif st.status:
            for line in _wrap(st.status):
                layout.label(text=line)
        if st.errors:
            box = layout.box()
            box.alert = True
            for line in st.errors.splitlines():
                for piece in _wrap(line):
                    box.label(text=piece)
        layout.prop(st, "show_attribution")
        row = layout.row(align=True)
        row.operator("csculpt.undo", text=f"Undo ({st.undo_depth})")
        row.operator("csculpt.redo", text=f"Redo ({st.redo_depth})")
        layout.operator("csculpt.sync_now")
        layout.operator("csculpt.leave")


def _wrap(text, width=40):
    words, lines, line = text.split(), [], ""
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            lines.append(line)
            line = w
        else:
            line = f"{line} {w}" if line else w
    return lines + ([line] if line else [])


class CsculptPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    artist_name: StringProperty(name="Your name", description="Shown to the other artists "
                                "(empty: your login name)")
    bind: StringProperty(name="Listen on", default=LISTEN_EVERYWHERE,
                         description="ZeroMQ endpoint others reach you at. tcp://*:* listens on "
                         "every interface, and an invite names this machine's address, so "
                         "artists on other machines can join; tcp://127.0.0.1:* keeps the "
                         "session on this machine; a fixed port (tcp://*:5670) suits a "
                         "firewall. Empty: this machine only")
    sync_ms: IntProperty(name="Merge interval (ms)", default=250, min=10, max=60000)
    interval_ms: IntProperty(name="Sync timer (ms)", default=50, min=10, max=2000)
    join_timeout_s: FloatProperty(name="Join timeout (s)", default=10.0, min=0.5, max=300.0)
    big_mesh: IntProperty(name="Big mesh (vertices)", default=200_000, min=1,
                          description="From this many vertices, remote changes refresh the "
                          "sculpt at most every 'Update limit' seconds")
    min_update_s: FloatProperty(name="Update limit (s)", default=0.5, min=0.0, max=10.0)

    def draw(self, context):
        layout = self.layout
        for name in ("artist_name", "bind", "sync_ms", "interval_ms", "join_timeout_s",
                     "big_mesh", "min_update_s"):
            layout.prop(self, name)
        if _import_error:
            layout.label(text=f"Library: {_import_error}", icon='ERROR')
        else:
            layout.label(text=f"libcsculpt {csculpt.version_string()} from "
                         f"{csculpt.library_path}")


# ---- Registration -------------------------------------------------------------------------

_classes = (CsculptState, CsculptPreferences, CSCULPT_OT_watch, CSCULPT_OT_host,
            CSCULPT_OT_join, CSCULPT_OT_leave, CSCULPT_OT_sync_now, CSCULPT_OT_undo,
            CSCULPT_OT_redo, CSCULPT_PT_panel)
_keymaps = []


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.WindowManager.csculpt = bpy.props.PointerProperty(type=CsculptState)
    kc = bpy.context.window_manager.keyconfigs.addon
    if kc is not None:
        # In Sculpt Mode, on the session's object, Ctrl+Z / Ctrl+Shift+Z are the artist's undo
        # in the session; elsewhere the operators' poll fails and Blender's own undo runs.
        km = kc.keymaps.new(name="Sculpt", space_type='EMPTY')
        _keymaps.append((km, km.keymap_items.new("csculpt.undo", 'Z', 'PRESS', ctrl=True)))
        _keymaps.append((km, km.keymap_items.new("csculpt.redo", 'Z', 'PRESS', ctrl=True,
                                                 shift=True)))


def unregister():
    global _watching
    _end()
    _watching = False
    for km, kmi in _keymaps:
        try:
            km.keymap_items.remove(kmi)
        except (ReferenceError, RuntimeError):
            pass
    _keymaps.clear()
    del bpy.types.WindowManager.csculpt
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
