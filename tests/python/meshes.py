"""Shared helpers of the Python binding tests: meshes and edits built in numpy, and the
paths the tests use. Importing this makes `import csculpt` find the module of this source tree
when PYTHONPATH does not (a test run by hand)."""

import importlib.util
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
MODULE_DIR = os.path.join(SOURCE_ROOT, "capi", "python")
HEADER = os.path.join(SOURCE_ROOT, "capi", "include", "csculpt.h")
MODELS = os.environ.get("CSCULPT_TEST_MODELS", "/usr/share/assimp/models")

if importlib.util.find_spec("csculpt") is None:
    sys.path.insert(0, MODULE_DIR)


def icosphere(subdivisions: int):
    """A unit icosphere: (positions (N, 3) float32, triangles (M, 3) uint32), counter-clockwise
    seen from outside. 10 * 4^s + 2 vertices."""
    t = (1.0 + 5.0**0.5) / 2.0
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
             (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(v, dtype=np.float64) / np.linalg.norm(v) for v in verts]
    for _ in range(subdivisions):
        midpoint = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in midpoint:
                m = verts[a] + verts[b]
                verts.append(m / np.linalg.norm(m))
                midpoint[key] = len(verts) - 1
            return midpoint[key]

        refined = []
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            refined += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = refined
    return np.array(verts, dtype=np.float32), np.array(faces, dtype=np.uint32)


def grab(positions, centre, radius, offset):
    """A smooth grab brush: vertices within `radius` of `centre` move by `offset` scaled by a
    smoothstep falloff (what a sculpting stroke does), float32 like the mesh."""
    d = np.linalg.norm(positions - np.asarray(centre, dtype=np.float32), axis=1)
    w = np.clip(1.0 - d / radius, 0.0, 1.0)
    w = w * w * (3.0 - 2.0 * w)
    return (positions + w[:, None] * np.asarray(offset, dtype=np.float32)).astype(np.float32)


def bits(a):
    """The array's bit patterns, for comparisons where -0.0 != 0.0 and NaN == NaN."""
    return np.ascontiguousarray(a).view(np.uint32)
