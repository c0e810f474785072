"""Shared by the scripts Blender runs in the tests (imported from tests/blender): files passed
between processes, the digest of what Blender shows, mesh edits."""

import hashlib
import json
import os
import sys
import time

import bpy
import numpy as np

WORK = os.environ["CSCULPT_TEST_DIR"]


def args():
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []


def path(name):
    return os.path.join(WORK, name)


def write(name, text):
    tmp = path(name + ".tmp")
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path(name))


def read(name):
    try:
        with open(path(name)) as f:
            return f.read()
    except OSError:
        return None


def wait_file(name, timeout=60.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        text = read(name)
        if text is not None:
            return text
        time.sleep(0.05)
    raise AssertionError(f"{name} did not come within {timeout} s")


def enable_addon(name=None):
    """Enables the add-on (unpacked in BLENDER_USER_SCRIPTS); with `name`, as that artist
    with a 50 ms merge interval. Returns window_manager.csculpt."""
    bpy.ops.preferences.addon_enable(module="csculpt_blender")
    if name:
        prefs = bpy.context.preferences.addons["csculpt_blender"].preferences
        prefs.artist_name = name
        prefs.sync_ms = 50
    return bpy.context.window_manager.csculpt


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)


def shown(obj):
    """What Blender holds for the object: positions and the synced attributes, as arrays."""
    mesh = obj.data
    n = len(mesh.vertices)
    out = {"co": np.empty(3 * n, dtype=np.float32)}
    mesh.vertices.foreach_get("co", out["co"])
    colour = mesh.color_attributes.active_color
    out["albedo"] = np.empty(4 * n, dtype=np.float32)
    colour.data.foreach_get("color", out["albedo"])
    for name in ("metallic", "roughness"):
        out[name] = np.empty(n, dtype=np.float32)
        mesh.attributes[name].data.foreach_get("value", out[name])
    return out


def digest(arrays):
    h = hashlib.sha256()
    for key in sorted(arrays):
        h.update(key.encode())
        h.update(arrays[key].tobytes())
    return h.hexdigest()


def publish(who, obj, extra=None):
    """state-<who>.json: what the harness waits on (version, digest, strokes acknowledged)."""
    import csculpt_blender
    st = bpy.context.window_manager.csculpt
    stats = csculpt_blender._host.session.stats if csculpt_blender._host else None
    state = {"version": st.version, "digest": digest(shown(obj)), "peers": st.peers,
             "strokes": st.strokes, "acked": stats.strokes_acknowledged if stats else -1,
             "refused": st.refused, "errors": st.errors, **(extra or {})}
    write(f"state-{who}.json", json.dumps(state))


def dump(who, obj):
    np.savez(path(f"final-{who}.npz"), **shown(obj))


def move(obj, mask_fn, offset):
    """Moves the vertices where mask_fn(positions (N, 3)) holds by `offset` (Blender data)."""
    mesh = obj.data
    n = len(mesh.vertices)
    co = np.empty(3 * n, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    p = co.reshape(n, 3)
    m = mask_fn(p)
    p[m] += np.asarray(offset, dtype=np.float32)
    mesh.vertices.foreach_set("co", co)
    mesh.update()
    return m


def paint(obj, mask_fn, rgb=None, **floats):
    """Paints the active colour attribute (linear RGB) and float attributes where mask_fn."""
    mesh = obj.data
    n = len(mesh.vertices)
    co = np.empty(3 * n, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    m = mask_fn(co.reshape(n, 3))
    if rgb is not None:
        attr = mesh.color_attributes.active_color
        c = np.empty(4 * n, dtype=np.float32)
        attr.data.foreach_get("color", c)
        c.reshape(n, 4)[m, :3] = rgb
        attr.data.foreach_set("color", c)
    for name, value in floats.items():
        v = np.empty(n, dtype=np.float32)
        mesh.attributes[name].data.foreach_get("value", v)
        v[m] = value
        mesh.attributes[name].data.foreach_set("value", v)
    mesh.update()
    return m


def check(condition, message):
    if not condition:
        raise AssertionError(message)

