#!/usr/bin/python3
"""Where a merge's error sits, by how the coarsest edit turns the surface there.

usage: error_by_turn.py CSCULPT_BIN CASE_DIR

Over the finest edit's support (as score_merge.py scores it), splits `full`'s and `sum`'s
error against the stacked ideal (ideal.ply) and the frame ideal (ideal_frame.ply, when the
case has it) by two measures of the coarsest edit at each vertex:
  - the largest turn of its faces' normals around the vertex (past 90 degrees: a fold);
  - how well those faces agree on the turn: the length of the mean of their turns as unit
    quaternions (1 when they turn as one, cos(s/2) for turns s apart), what `full`'s frame
    transport trusts a carrier by.
Each row's share is sqrt(sum of squared errors in the row / support size) / the edit's RMS
size, so the rows add up in squares to the case's rel_err. A last line says how far the
coarsest edit stretches the faces of the support (largest |singular value - 1| of each face's
map, median and largest) beside the stretch a shear tilting them by their median turn would
make (1 / cos - 1): how little a surface shows whether a coarse edit turned or sheared it."""
import os
import sys

import numpy as np

import artists


def read_faces(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii", "replace").splitlines()
    nv = int([l for l in header if l.startswith("element vertex")][0].split()[2])
    nf = int([l for l in header if l.startswith("element face")][0].split()[2])
    rec = np.frombuffer(data, dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]), count=nf,
                        offset=end + 12 * nv)
    assert (rec["n"] == 3).all(), "triangles only"
    return rec["i"].astype(np.int64)


def face_normals(p, faces):
    n = np.cross(p[faces[:, 1]] - p[faces[:, 0]], p[faces[:, 2]] - p[faces[:, 0]])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return n / np.where(length > 0, length, 1)


def turn_measures(base, edited, faces):
    """Per vertex: the largest turn (degrees) of its faces, and their agreement."""
    n0, n1 = face_normals(base, faces), face_normals(edited, faces)
    cos = np.clip((n0 * n1).sum(1), -1, 1)
    turn = np.degrees(np.arccos(cos))
    q = np.concatenate([(1 + cos)[:, None], np.cross(n0, n1)], 1)
    q /= np.maximum(np.linalg.norm(q, axis=1, keepdims=True), 1e-12)
    nv = len(base)
    largest, total, count = np.zeros(nv), np.zeros((nv, 4)), np.zeros(nv)
    first = np.full(nv, -1)
    for corner in range(3):
        np.maximum.at(largest, faces[:, corner], turn)
    for f, corners in enumerate(faces):
        for v in corners:
            if first[v] < 0:
                first[v] = f
            total[v] += q[f] if q[f] @ q[first[v]] >= 0 else -q[f]
            count[v] += 1
    return largest, np.linalg.norm(total, axis=1) / np.maximum(count, 1)


def face_stretch(base, edited, faces):
    """Per face: the largest |singular value - 1| of its map from base to edited."""
    def metric(p):
        e1, e2 = p[faces[:, 1]] - p[faces[:, 0]], p[faces[:, 2]] - p[faces[:, 0]]
        dot = lambda a, b: (a * b).sum(1)  # noqa: E731
        return np.stack([np.stack([dot(e1, e1), dot(e1, e2)], 1),
                         np.stack([dot(e2, e1), dot(e2, e2)], 1)], 1)
    before, after = metric(base), metric(edited)
    ok = np.abs(np.linalg.det(before)) > 1e-30
    squares = np.linalg.eigvals(np.linalg.solve(before[ok], after[ok])).real
    stretch = np.zeros(len(faces))
    stretch[ok] = np.abs(np.sqrt(np.abs(squares)) - 1).max(1)
    return stretch


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    binary, case = sys.argv[1], sys.argv[2]
    names = [n for n in artists.ARTISTS if os.path.exists(os.path.join(case, n + ".ply"))]
    base = artists.read_ply(os.path.join(case, "base.ply"))
    edits = [artists.read_ply(os.path.join(case, n + ".ply")) for n in names]
    ds = [e - base for e in edits]
    rms = [np.sqrt((np.linalg.norm(d, axis=1) ** 2).mean()) for d in ds]
    finest, coarsest = ds[int(np.argmin(rms))], int(np.argmax(rms))
    faces = read_faces(os.path.join(case, "base.ply"))
    largest, agreement = turn_measures(base, edits[coarsest], faces)
    size = np.linalg.norm(finest, axis=1)
    support = artists.support(finest)
    scale = np.sqrt((size[support] ** 2).mean())
    results = {"full": artists.merge(binary, case, names, "full"), "sum": base + sum(ds)}
    ideals = [i for i in ("ideal", "ideal_frame") if os.path.exists(os.path.join(case, i + ".ply"))]
    errors = {(m, i): np.linalg.norm(x - artists.read_ply(os.path.join(case, i + ".ply")), axis=1)
              for m, x in results.items() for i in ideals}
    rows = [("turn %3d-%3d deg" % (lo, hi), (largest >= lo) & (largest < hi))
            for lo, hi in ((0, 10), (10, 30), (30, 60), (60, 90), (90, 181))]
    rows += [("agreement %.2f-%.2f" % (lo, hi), (agreement >= lo) & (agreement < hi))
             for lo, hi in ((0, 0.8), (0.8, 0.95), (0.95, 0.99), (0.99, 1.01))]
    print("%s: finest edit's support %d vertices, RMS size %.4g" % (os.path.basename(case),
                                                                    support.sum(), scale))
    for label, where in rows:
        m = support & where
        shares = "  ".join("%s vs %s %.4f" % (method, ideal,
                                             np.sqrt((errors[(method, ideal)][m] ** 2).sum()
                                                     / support.sum()) / scale)
                           for ideal in ideals for method in results)
        print("%-20s %5d vertices  %s" % (label, m.sum(), shares))
    inside = support[faces].all(1)
    stretch = face_stretch(base, edits[coarsest], faces[inside])
    turn = np.degrees(np.arccos(np.clip((face_normals(base, faces[inside]) *
                                         face_normals(edits[coarsest], faces[inside])).sum(1), -1, 1)))
    print("coarsest edit on the support's %d faces: stretch median %.3f, largest %.3f; turn "
          "median %.1f deg, where a shear would stretch by %.3f" % (
              inside.sum(), np.median(stretch), stretch.max(), np.median(turn),
              1 / np.cos(np.radians(np.median(turn))) - 1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
