#!/usr/bin/python3
"""Checks that `csculpt merge --explain` scores as shared/eval/score_merge.py does.

usage: check_explain.py CASES_DIR CSCULPT_BIN

For every case and the methods below, runs `CSCULPT merge ... --explain --ideal ...` and
recomputes, with the scorer's own functions on the merged file, the case's new_folds (its
`flipped`) and rel_err against each ideal (its `rel_rms`). The SDK's fold count
(csculpt/folds.h) and the explain report claim to be the scorer's numbers: they must be equal
(folds exactly, rel_err to the 6 digits the report prints). Exits 0 when all agree, 1 listing each
disagreement, SKIP (77) without the cases or numpy.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

SKIP = 77  # the test's SKIP_RETURN_CODE
METHODS = ["full", "sum", "weighted-translation"]  # sum and weighted-translation do fold
IDEALS = ["ideal.ply", "ideal_frame.ply"]


def explain(binary, case_dir, names, ideals, method, out):
    args = [binary, "merge", os.path.join(case_dir, "base.ply")]
    args += [os.path.join(case_dir, n + ".ply") for n in names]
    args += ["-o", out, "--method", method, "--explain"]
    for i in ideals:
        args += ["--ideal", os.path.join(case_dir, i)]
    r = subprocess.run(args, capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise RuntimeError("%s failed: %s" % (" ".join(args), r.stderr.strip()[-300:]))
    return json.loads(r.stdout)


def check_case(scorer, binary, case_dir, case):
    """Disagreements between the report and the scorer on one case, as messages."""
    names = [n for n in "abcdefgh" if os.path.exists(os.path.join(case_dir, n + ".ply"))]
    ideals = [i for i in IDEALS if os.path.exists(os.path.join(case_dir, i))]
    base = scorer.read_ply(os.path.join(case_dir, "base.ply"))
    edits = [scorer.read_ply(os.path.join(case_dir, n + ".ply")) for n in names]
    faces = scorer.read_faces(os.path.join(case_dir, "base.ply"))
    problems = []
    for method in METHODS:
        with tempfile.TemporaryDirectory() as t:
            out = os.path.join(t, "out.ply")
            report = explain(binary, case_dir, names, ideals, method, out)
            x = scorer.read_ply(out)
        where = "%s --method %s" % (case, method)
        if faces is not None:
            made = sum(scorer.flipped(base, e, faces) for e in edits) > 0
            folds = int((scorer.flipped(base, x, faces) & ~made).sum())
            if report["new_folds"] != folds:
                problems.append("%s: new_folds %d, the scorer's %d" % (where, report["new_folds"], folds))
        for k, name in enumerate(ideals):
            expected = scorer.rel_rms(x, scorer.read_ply(os.path.join(case_dir, name)), base,
                                      [e - base for e in edits])
            got = report["ideals"][k]["rel_err"]
            if not math.isclose(got, expected, rel_tol=1e-5, abs_tol=1e-12):
                problems.append("%s: rel_err against %s %r, the scorer's %r" % (where, name, got, expected))
        print("%-30s %-22s new_folds=%d" % (case, method, report["new_folds"]))
    return problems


def main():
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    cases_dir, binary = sys.argv[1], sys.argv[2]
    if not os.path.isdir(cases_dir):
        print("SKIP: no Blender-authored cases at %s" % cases_dir)
        return SKIP
    try:
        import numpy  # noqa: F401  (the scorer needs it)
    except ImportError:
        print("SKIP: %s has no numpy (Debian: python3-numpy)" % sys.executable)
        return SKIP
    sys.path.insert(0, os.path.dirname(os.path.abspath(cases_dir)))
    import score_merge as scorer
    problems = []
    for case in sorted(os.listdir(cases_dir)):
        problems += check_case(scorer, binary, os.path.join(cases_dir, case), case)
    for p in problems:
        print("MISMATCH: " + p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
