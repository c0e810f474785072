#!/usr/bin/python3
"""Renders a cSculpt PLY (binary little-endian, as csculpt writes it) to a PNG: shaded
geometry coloured by a channel (attribution or albedo). Used for the README picture.

usage: render_ply.py MESH.ply OUT.png [--channel attribution|albedo] [--size 640]
Needs only numpy (Debian's python3-numpy)."""
import struct, sys, zlib
import numpy as np


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    if "format binary_little_endian 1.0" not in header:
        raise SystemExit(f"{path}: only binary little-endian PLY is supported")
    nv = nf = 0
    props, cur = [], None
    for line in header:
        p = line.split()
        if p[:2] == ["element", "vertex"]:
            nv, cur = int(p[2]), "v"
        elif p[:2] == ["element", "face"]:
            nf, cur = int(p[2]), "f"
        elif p[:1] == ["property"] and cur == "v":
            props.append(p[2])
    v = np.frombuffer(data, dtype="<f4", count=nv * len(props), offset=end).reshape(nv, len(props))
    off = end + nv * len(props) * 4
    f = np.frombuffer(data, dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]), count=nf, offset=off)["i"]
    return {name: v[:, k] for k, name in enumerate(props)}, f


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        raise SystemExit(__doc__)
    channel = args[args.index("--channel") + 1] if "--channel" in args else "attribution"
    size = int(args[args.index("--size") + 1]) if "--size" in args else 640
    v, f = read_ply(args[0])
    p = np.stack([v["x"], v["y"], v["z"]], 1).astype(np.float64)
    cols = [f"{channel}_r", f"{channel}_g", f"{channel}_b"]
    c = np.stack([v[k] for k in cols], 1) if all(k in v for k in cols) else np.full((len(p), 3), 0.8)
    if channel == "attribution":
        c = np.where(c.sum(1, keepdims=True) > 0, 0.25 + 0.75 * c, 0.85)
    # vertex normals
    n = np.zeros_like(p)
    fn = np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    # view: rotate a little so the sphere reads as 3D
    a, b = 0.5, -0.35
    ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    r = rx @ ry
    q, nq = p @ r.T, n @ r.T
    lo, hi = q.min(0), q.max(0)
    s = 0.9 * size / max(hi[0] - lo[0], hi[1] - lo[1])
    x = ((q[:, 0] - (lo[0] + hi[0]) / 2) * s + size / 2).astype(int)
    y = (size / 2 - (q[:, 1] - (lo[1] + hi[1]) / 2) * s).astype(int)
    light = np.array([0.4, 0.6, 0.7]) / np.linalg.norm([0.4, 0.6, 0.7])
    shade = 0.2 + 0.8 * np.clip(nq @ light, 0, 1)
    rgb = np.clip(c * shade[:, None], 0, 1)
    img = np.full((size, size, 3), 0.12)
    depth = np.full((size, size), -np.inf)
    order = np.argsort(q[:, 2])  # far to near: later (nearer) splats overwrite
    for dx in (0, 1, 2):
        for dy in (0, 1, 2):
            xx, yy = np.clip(x[order] + dx - 1, 0, size - 1), np.clip(y[order] + dy - 1, 0, size - 1)
            zz = q[order, 2]
            nearer = zz >= depth[yy, xx]
            img[yy[nearer], xx[nearer]] = rgb[order][nearer]
            depth[yy[nearer], xx[nearer]] = zz[nearer]
    write_png(args[1], (img * 255).astype(np.uint8))


if __name__ == "__main__":
    main()
