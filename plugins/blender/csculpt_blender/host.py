"""The Blender side of a cSculpt session: one mesh object's positions and material attributes
mirrored to a csculpt.Session's host arrays, and back.

No bpy reference is kept across calls: the object is looked up by name on each step, because
Blender's undo past a mode switch reloads the file and kills stored references.

Three copies of the data:
  * Blender's own (mesh.vertices "co", the albedo FLOAT_COLOR point attribute, the "metallic"
    and "roughness" float point attributes);
  * `self.shown`: what Blender held after the last step (read or written by this module), in
    Blender's representation (linear RGBA colours). A value of Blender's that differs from it
    was changed by the artist;
  * the session's host arrays (`self.positions`, `self.channels`, the session's layout: albedo
    sRGB-encoded), which csculpt.Session.update/submit/undo/redo write in place.
"""

import time

import numpy as np

from . import csculpt

ALBEDO_ATTRIBUTE = "Color"          # what Sculpt Mode's Paint brush creates
FALLBACK_ALBEDO = "csculpt_albedo"  # used when "Color" exists with another type or domain
FLOAT_CHANNELS = ("metallic", "roughness")
ATTRIBUTION_ATTRIBUTE = "csculpt_attribution"
MATERIAL_NAME = "cSculpt"


class Refused(Exception):
    """What cannot sync, in words for the artist."""


def srgb_to_linear(c):
    c = np.clip(c, 0.0, 1.0).astype(np.float32)
    return np.where(c <= np.float32(0.04045), c / np.float32(12.92),
                    ((c + np.float32(0.055)) / np.float32(1.055)) ** np.float32(2.4)
                    ).astype(np.float32)


def linear_to_srgb(lin):
    lin = np.clip(lin, 0.0, 1.0).astype(np.float32)
    return np.where(lin <= np.float32(0.0031308), lin * np.float32(12.92),
                    np.float32(1.055) * lin ** np.float32(1 / 2.4) - np.float32(0.055)
                    ).astype(np.float32)


def refusal(obj, vertex_count=None):
    """Why `obj` cannot sync (a sentence), or None."""
    if obj is None:
        return "The session's object is gone (deleted or renamed): nothing is synced."
    if obj.type != 'MESH':
        kind = obj.type.lower().replace("_", " ")
        article = "an" if kind[0] in "aeiou" else "a"
        return f"'{obj.name}' is {article} {kind} object, not a mesh: only meshes sync."
    if obj.mode == 'EDIT':
        return ("Edit Mode: Blender writes the mesh only when you leave it, so remote changes "
                "wait and your edits are sent then (if the vertex count is unchanged).")
    if getattr(obj, "use_dynamic_topology_sculpting", False):
        return ("Dynamic topology is on: it changes the vertices and strokes do not write "
                "mesh vertices. Turn it off (Sculpt Mode header, Dyntopo) to sync.")
    if any(m.type == 'MULTIRES' for m in obj.modifiers):
        return ("A Multiresolution modifier is on this object: its strokes do not write the "
                "mesh vertices. Remove or apply it to sync.")
    if obj.data.shape_keys is not None:
        return ("This mesh has shape keys: strokes write a key, not the mesh. Remove or apply "
                "the shape keys to sync.")
    if vertex_count is not None and len(obj.data.vertices) != vertex_count:
        return (f"The mesh has {len(obj.data.vertices)} vertices, the session's has "
                f"{vertex_count}: a changed vertex count cannot sync. Undo the change (or "
                f"leave and share again).")
    return None


def _float_attribute(mesh, name, kind):
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.domain != 'POINT' or attr.data_type != kind):
        return None
    return attr


def albedo_attribute_name(mesh, create=True):
    """The FLOAT_COLOR point attribute albedo syncs through: the active colour attribute when
    it is one (Paint paints it), else "Color" or FALLBACK_ALBEDO, created and made active."""
    colors = mesh.color_attributes
    active = colors.active_color
    if active is not None and active.domain == 'POINT' and active.data_type == 'FLOAT_COLOR' \
            and active.name != ATTRIBUTION_ATTRIBUTE:
        return active.name
    for name in (ALBEDO_ATTRIBUTE, FALLBACK_ALBEDO):
        if _float_attribute(mesh, name, 'FLOAT_COLOR') is not None:
            break
        if mesh.attributes.get(name) is None:
            if not create:
                return None
            colors.new(name, 'FLOAT_COLOR', 'POINT')
            break
    attr = colors.get(name)
    colors.active_color = attr
    try:
        colors.render_color_index = list(colors).index(attr)
    except (AttributeError, ValueError):
        pass
    return name


def mesh_triangles(mesh):
    mesh.calc_loop_triangles()
    tri = np.empty(3 * len(mesh.loop_triangles), dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tri)
    return tri.astype(np.uint32).reshape(-1, 3)


def mesh_positions(mesh):
    pos = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", pos)
    return pos


def session_mesh_from_blender(mesh):
    """A csculpt.Mesh of `mesh` with the material channels: from its attributes where it has
    them, else the library's defaults."""
    pos = mesh_positions(mesh)
    tri = mesh_triangles(mesh)
    with csculpt.Mesh(pos, tri) as probe:
        probe.add_material_channels()
        channels = probe.channels
    albedo = albedo_attribute_name(mesh, create=False)
    n = len(mesh.vertices)
    if albedo is not None:
        rgba = np.empty(4 * n, dtype=np.float32)
        mesh.attributes[albedo].data.foreach_get("color", rgba)
        channels["albedo"].values = linear_to_srgb(rgba.reshape(n, 4)[:, :3])
    for name in FLOAT_CHANNELS:
        attr = _float_attribute(mesh, name, 'FLOAT')
        if attr is not None:
            values = np.empty(n, dtype=np.float32)
            attr.data.foreach_get("value", values)
            channels[name].values = values
    return csculpt.Mesh(pos, tri, channels)


def new_blender_mesh(name, session_mesh):
    """A new bpy mesh with the session mesh's vertices (same order) and triangles."""
    import bpy
    pos = session_mesh.positions.ravel()
    tri = session_mesh.triangles.astype(np.int32).ravel()
    n, m = session_mesh.vertex_count, session_mesh.triangle_count
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(n)
    mesh.vertices.foreach_set("co", pos)
    mesh.loops.add(3 * m)
    mesh.loops.foreach_set("vertex_index", tri)
    mesh.polygons.add(m)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * m, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(m, 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    return mesh


def ensure_material(obj):
    """The add-on's material (Attribute nodes into a Principled BSDF, with a switch to the
    attribution colours) on `obj`: added when the object has no material; returns it."""
    import bpy
    mat = bpy.data.materials.get(MATERIAL_NAME)
    if mat is None:
        mat = bpy.data.materials.new(MATERIAL_NAME)
        mat.use_nodes = True
        nodes, links = mat.node_tree.nodes, mat.node_tree.links
        bsdf = next(n for n in nodes if n.type == 'BSDF_PRINCIPLED')
        y = 300
        sockets = {}
        for name, attr, socket in (("albedo", ALBEDO_ATTRIBUTE, "Color"),
                                   ("attribution", ATTRIBUTION_ATTRIBUTE, "Color"),
                                   ("metallic", "metallic", "Fac"),
                                   ("roughness", "roughness", "Fac")):
            node = nodes.new("ShaderNodeAttribute")
            node.name = node.label = f"csculpt {name}"
            node.attribute_name = attr
            node.location = (-700, y)
            y -= 200
            sockets[name] = node.outputs[socket]
        mix = nodes.new("ShaderNodeMixRGB")
        mix.name = mix.label = "csculpt attribution view"
        mix.location = (-400, 300)
        mix.inputs["Fac"].default_value = 0.0
        links.new(sockets["albedo"], mix.inputs["Color1"])
        links.new(sockets["attribution"], mix.inputs["Color2"])
        links.new(mix.outputs["Color"], bsdf.inputs["Base Color"])
        links.new(sockets["metallic"], bsdf.inputs["Metallic"])
        links.new(sockets["roughness"], bsdf.inputs["Roughness"])
    if obj.data.materials and len(obj.data.materials):
        return mat
    obj.data.materials.append(mat)
    return mat


class Host:
    """One Blender process's share of a session: the session and the object it mirrors."""

    def __init__(self, session, object_name, albedo_name, big_mesh=200_000,
                 min_update_s=0.5):
        self.session = session
        self.object_name = object_name
        self.albedo_name = albedo_name
        self.n = session.vertex_count
        self.big_mesh, self.min_update_s = big_mesh, min_update_s
        with session.base() as base:
            self.positions = base.positions.ravel().copy()
            self.channels = {name: np.ascontiguousarray(ch.values.copy())
                             for name, ch in base.channels.items()}
        self.layout = [(name, 1 if v.ndim == 1 else v.shape[1]) for name, v in
                       self.channels.items()]
        self.shown = None          # Blender's values after the last step
        self.pending_strokes = 0   # strokes made since the last submit
        self.strokes = 0           # strokes recorded
        self.stroke_active = False  # the artist's stroke is under way: hold remote changes
        self.refused = None        # why the object cannot sync now (words), or None
        self.errors = []           # the session's error and drop events, in words (latest last)
        self.log = []              # peers joining and leaving
        self.last_update = 0.0
        self.deferred = False      # remote changes waiting for the rate limit
        self.show_attribution = False
        self.attribution_version = -1

    # ---- Blender data -------------------------------------------------------------------

    def object(self):
        import bpy
        return bpy.data.objects.get(self.object_name)

    def _read(self, mesh):
        n = self.n
        out = {"co": np.empty(3 * n, dtype=np.float32)}
        mesh.vertices.foreach_get("co", out["co"])
        if "albedo" in self.channels:
            attr = mesh.attributes.get(self.albedo_name)
            if attr is None or attr.data_type != 'FLOAT_COLOR' or attr.domain != 'POINT':
                # Deleted or replaced: shown again from the session (nothing lost).
                self.albedo_name = albedo_attribute_name(mesh)
                self._write_one(mesh, "albedo", self._to_blender("albedo"))
                attr = mesh.attributes[self.albedo_name]
            out["albedo"] = np.empty(4 * n, dtype=np.float32)
            attr.data.foreach_get("color", out["albedo"])
        for name in FLOAT_CHANNELS:
            if name in self.channels:
                attr = _float_attribute(mesh, name, 'FLOAT')
                if attr is None:
                    if name in mesh.attributes:
                        mesh.attributes.remove(mesh.attributes[name])
                    mesh.attributes.new(name, 'FLOAT', 'POINT')
                    self._write_one(mesh, name, self._to_blender(name))
                    attr = mesh.attributes[name]
                out[name] = np.empty(n, dtype=np.float32)
                attr.data.foreach_get("value", out[name])
        return out

    def _to_blender(self, key):
        if key == "co":
            return self.positions.copy()
        if key == "albedo":
            rgba = np.ones((self.n, 4), dtype=np.float32)
            rgba[:, :3] = srgb_to_linear(self.channels["albedo"])
            return rgba.ravel()
        return self.channels[key].ravel().copy()

    def _write_one(self, mesh, key, values):
        if key == "co":
            mesh.vertices.foreach_set("co", values)
        elif key == "albedo":
            mesh.attributes[self.albedo_name].data.foreach_set("color", values)
        else:
            mesh.attributes[key].data.foreach_set("value", values)

    def keys(self):
        return ["co"] + [k for k in ("albedo",) + FLOAT_CHANNELS if k in self.channels]

    def _stride_values(self, vertices):
        """Per vertex: position then every session channel, in the session's order."""
        parts = [self.positions.reshape(-1, 3)[vertices]]
        for name, width in self.layout:
            parts.append(self.channels[name].reshape(self.n, width)[vertices])
        return np.concatenate(parts, axis=1).astype(np.float32)

    # ---- Steps ---------------------------------------------------------------------------

    def check(self):
        """The object, or None with self.refused set to why it cannot sync."""
        obj = self.object()
        self.refused = refusal(obj, self.n)
        return None if self.refused else obj

    def start(self):
        """Shows the session's values in Blender (after join, or on share to settle them)."""
        obj = self.check()
        if obj is None:
            raise Refused(self.refused)
        self._write_all(obj.data)

    def _write_all(self, mesh):
        shown = {}
        for key in self.keys():
            shown[key] = self._to_blender(key)
            if key == "albedo":
                self.albedo_name = albedo_attribute_name(mesh)
            elif key in FLOAT_CHANNELS and _float_attribute(mesh, key, 'FLOAT') is None:
                if key in mesh.attributes:
                    mesh.attributes.remove(mesh.attributes[key])
                mesh.attributes.new(key, 'FLOAT', 'POINT')
            self._write_one(mesh, key, shown[key])
        mesh.update()
        self.shown = shown
        self.last_update = time.monotonic()
        self.deferred = False

    def take_local(self, mesh):
        """Records what the artist changed since the last step as one stroke. Returns whether
        there was a change."""
        cur = self._read(mesh)
        n = self.n
        masks = {}
        for key, values in cur.items():
            width = values.size // n
            diff = (values.view(np.uint32) != self.shown[key].view(np.uint32)).reshape(n, width)
            if key == "albedo":
                diff = diff[:, :3]
            masks[key] = diff.any(axis=1)
        union = np.zeros(n, dtype=bool)
        for m in masks.values():
            union |= m
        if not union.any():
            return False
        vertices = np.flatnonzero(union).astype(np.uint32)
        before = self._stride_values(vertices)
        for key, m in masks.items():
            if not m.any():
                continue
            if key == "co":
                self.positions.reshape(n, 3)[m] = cur["co"].reshape(n, 3)[m]
            elif key == "albedo":
                self.channels["albedo"][m] = linear_to_srgb(cur["albedo"].reshape(n, 4)[m, :3])
            else:
                self.channels[key][m] = cur[key][m]
        self.session.record_stroke(self.positions, vertices, before, self.channels)
        self.shown = cur
        self.pending_strokes += 1
        self.strokes += 1
        return True

    def write_changes(self, mesh, force=False):
        """Writes the session's values that Blender does not show yet; mesh.update() only when
        something changed, at most every min_update_s on meshes of big_mesh vertices or more
        (unless `force`). Returns whether it wrote."""
        targets = {key: self._to_blender(key) for key in self.keys()}
        changed = [key for key in targets if
                   not np.array_equal(targets[key].view(np.uint32),
                                      self.shown[key].view(np.uint32))]
        if not changed:
            self.deferred = False
            return False
        now = time.monotonic()
        if not force and self.n >= self.big_mesh and now - self.last_update < self.min_update_s:
            self.deferred = True
            return False
        for key in changed:
            self._write_one(mesh, key, targets[key])
            self.shown[key] = targets[key]
        mesh.update()
        self.last_update = now
        self.deferred = False
        return True

    def _submit(self):
        # The library counts the strokes whether or not anything was new to send.
        self.session.submit(self.positions, self.channels, strokes=self.pending_strokes)
        self.pending_strokes = 0

    def step(self):
        """One sync step: the artist's changes recorded and sent, merged versions taken in and
        shown (unless a stroke is under way), events read. Returns the versions applied."""
        self.poll_events()
        obj = self.check()
        if obj is None or self.stroke_active:
            return 0
        mesh = obj.data
        if self.shown is None:
            self._write_all(mesh)
        self.take_local(mesh)
        applied = self.session.update(self.positions, self.channels)
        self._submit()
        self.write_changes(mesh)
        if self.show_attribution and self.session.version != self.attribution_version:
            self.write_attribution(mesh)
        return applied

    def _undo_redo(self, function):
        obj = self.check()
        if obj is None:
            raise Refused(self.refused)
        mesh = obj.data
        if self.shown is None:
            self._write_all(mesh)
        self.take_local(mesh)  # the stroke just made is the first to go
        changed = function(self.positions, self.channels)
        if len(changed):
            self.pending_strokes += 1
            self._submit()
            self.write_changes(mesh, force=True)
        return len(changed)

    def undo(self):
        """Undoes this artist's latest stroke in the session (others' work stays). Returns the
        number of vertices changed (0: nothing to undo)."""
        return self._undo_redo(self.session.undo)

    def redo(self):
        return self._undo_redo(self.session.redo)

    # ---- Attribution, events, presence --------------------------------------------------

    def write_attribution(self, mesh):
        rgb = self.session.attribution_colors()
        rgba = np.ones((self.n, 4), dtype=np.float32)
        rgba[:, :3] = srgb_to_linear(rgb)
        attr = _float_attribute(mesh, ATTRIBUTION_ATTRIBUTE, 'FLOAT_COLOR')
        if attr is None:
            attr = mesh.color_attributes.new(ATTRIBUTION_ATTRIBUTE, 'FLOAT_COLOR', 'POINT')
            # Creating a colour attribute can change the active one: Paint must keep albedo.
            active = mesh.color_attributes.get(self.albedo_name)
            if active is not None:
                mesh.color_attributes.active_color = active
        attr.data.foreach_set("color", rgba.ravel())
        self.attribution_version = self.session.version
        mesh.update()

    _EVENT_WORDS = {
        csculpt.EventKind.ERROR: ("errors", "Session error: {}", "unknown"),
        csculpt.EventKind.DROPPED: ("errors", "A message was dropped: {}", "malformed or foreign"),
        csculpt.EventKind.PEER_JOINED: ("log", "peer {peer:x} joined", ""),
        csculpt.EventKind.PEER_LEFT: ("log", "peer {peer:x} left", ""),
        csculpt.EventKind.PEER_EVASIVE: ("log", "peer {peer:x} is silent", ""),
        csculpt.EventKind.MERGER_CHANGED: ("log", "peer {peer:x} merges now", ""),
    }

    def poll_events(self):
        for e in self.session.events():
            words = self._EVENT_WORDS.get(e.kind)
            if words:
                where, text, default = words
                getattr(self, where).append(text.format(e.message or default, peer=e.peer))
        del self.errors[:-5]
        del self.log[:-5]

    def set_presence(self, position, radius, active, visible=True):
        try:
            self.session.set_presence(position, max(float(radius), 0.0), active, visible)
        except csculpt.CsculptError:
            pass

    def summary(self):
        """What the panel and scripts show: (status words, peers text, stats)."""
        stats = self.session.stats
        peers = self.session.peers()
        return stats, peers
