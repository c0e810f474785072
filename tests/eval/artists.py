"""Every artist scored: the merge's error on each artist's own support, not only the finest's.

shared/eval/score_merge.py measures the finest edit's support; a coarse artist, or a second
detail, can lose its edit unseen there. For each case and each artist k this measures
RMS |x - ideal| over the vertices k moved, relative to k's RMS displacement, for `full` and
the scorer's baselines (sum, weighted-translation), against every ideal the case has.

usage (standalone): artists.py CSCULPT_BIN CASES_DIR [CASES_DIR ...]   prints one row per
case, ideal and artist."""
import os
import subprocess
import sys
import tempfile

import numpy as np

ARTISTS = "abcdefgh"
IDEALS = ("ideal", "ideal_frame")


def read_ply(path):
    """Vertex positions of a binary little-endian PLY as the cases store them."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii", "replace").splitlines()
    assert "format binary_little_endian 1.0" in header, path
    nv = int([l for l in header if l.startswith("element vertex")][0].split()[2])
    return np.frombuffer(data, dtype="<f4", count=3 * nv, offset=end).reshape(nv, 3).astype(np.float64)


def support(d):
    """The vertices displacement d moves, as score_merge.py counts them."""
    n = np.linalg.norm(d, axis=1)
    return n > 1e-6 * max(1e-12, n.max()) + 1e-9


def support_error(x, ideal, d):
    """RMS distance to the ideal over d's support, relative to d's RMS size."""
    n = np.linalg.norm(d, axis=1)
    sup = support(d)
    if not sup.any():
        return 0.0
    err = np.linalg.norm(x - ideal, axis=1)[sup]
    return float(np.sqrt((err ** 2).mean()) / np.sqrt((n[sup] ** 2).mean()))


def merge(binary, case_dir, names, method):
    with tempfile.TemporaryDirectory() as t:
        out = os.path.join(t, "out.ply")
        subprocess.run([binary, "merge", os.path.join(case_dir, "base.ply")] +
                       [os.path.join(case_dir, n + ".ply") for n in names] +
                       ["-o", out, "--method", method], check=True, capture_output=True, timeout=300)
        return read_ply(out)


def score_case(binary, case_dir):
    """[(ideal, artist, {method: error})] for one case directory."""
    names = [n for n in ARTISTS if os.path.exists(os.path.join(case_dir, n + ".ply"))]
    base = read_ply(os.path.join(case_dir, "base.ply"))
    ds = [read_ply(os.path.join(case_dir, n + ".ply")) - base for n in names]
    sizes = [np.linalg.norm(d, axis=1, keepdims=True) for d in ds]
    total = sum(sizes)
    results = {"full": merge(binary, case_dir, names, "full"), "(sum)": base + sum(ds),
               "(weighted-translation)":
                   base + sum(s * d for s, d in zip(sizes, ds)) / np.where(total > 0, total, 1)}
    rows = []
    for ideal_name in IDEALS:
        path = os.path.join(case_dir, ideal_name + ".ply")
        if not os.path.exists(path):
            continue
        ideal = read_ply(path)
        for name, d in zip(names, ds):
            rows.append((ideal_name, name, {m: support_error(x, ideal, d) for m, x in results.items()}))
    return rows


def main():
    binary, dirs = sys.argv[1], sys.argv[2:]
    for d in dirs:
        for case in sorted(os.listdir(d)):
            if not os.path.isfile(os.path.join(d, case, "base.ply")):
                continue
            for ideal, artist, e in score_case(binary, os.path.join(d, case)):
                print("%-34s %-12s artist %s  " % (case, ideal, artist) +
                      "  ".join("%s %.4f" % (m, v) for m, v in e.items()))


if __name__ == "__main__":
    main()
