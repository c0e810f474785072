#!/usr/bin/python3
"""Checks the merge against Blender-authored cases (shared/eval/README.md, issue rules).

usage: check_eval.py SCORER CSCULPT_BIN CASES_DIR [CASES_DIR ...]

Runs SCORER (shared/eval/score_merge.py) on every case directory with the methods below,
prints its table, and asserts on `full`:
  - disjoint and identical cases: rel_err <= 0.01 against every ideal the case has;
  - every case where a detail and a coarse edit meet (it has ideal_frame.ply): against the
    frame ideal below both "(sum)" and "(weighted-translation)"; against the stacked ideal
    never worse than 1.5 x "(sum)" (a miss prints how far apart the two ideals are), and
    where that misses, no farther from the stacked ideal than the frame ideal is;
  - new_folds (faces flipped by the merge but by no edit) no more than "(sum)"'s;
  - every artist scored (artists.py): against the frame ideal, on each artist's own support,
    full keeps no less of that artist's edit than "(sum)" does (within ARTIST_SLACK, the
    ideals' own rounding at the rim of a support); on disjoint and identical cases every
    artist's support within 0.01 of every ideal;
  - roughness <= 1.2 where there is no ideal;
  - every method the scorer ran produced a result.
KNOWN_LIMITS lists the rule violations that are understood and documented in
docs/merge-quality.md: they are printed on every run, and a known limit that no longer
occurs is reported so the list stays true; so is a miss of the stack rule where the stacked
ideal is sum itself and the frame ideal is not (STACK_IS_SUM), where no merge can meet both.
KNOWN_BOUNDS holds some cases to a tighter factor of sum than the rules. Exits 0 when every
other rule holds, 1 with one message per violation otherwise, 77 (SKIP) when a cases directory
or numpy is missing.
"""
import os
import re
import subprocess
import sys

import artists
import ideal_conflict

SKIP = 77
METHODS = ["full", "frame-transport", "hierarchy-blend"]
EXACT_LIMIT = 0.01
STACK_FACTOR = 1.5
ROUGHNESS_LIMIT = 1.2
ARTIST_SLACK = 0.005
# Where sum is this close to the stacked ideal, that ideal is sum itself (a Hook by a vertex
# group, a bend about the detail's own direction): if the frame ideal is not, the stack rule
# (within 1.5 x 0) and the frame rule (below sum) exclude each other, and the stack rule is
# reported as a known limit, the sanity bound below still asserted.
STACK_IS_SUM = 0.001
ROW = re.compile(r"^(\S+)\s+(\S+)\s+(rel_err|roughness|new_folds)=(\S+)$")

# (case, rule) -> why. Rules: "frame", "stack", "artist", "folds", ... See
# docs/merge-quality.md, "Limits". Empty: every rule holds on every committed case, but for
# the stack rule where it cannot (STACK_IS_SUM).
KNOWN_LIMITS = {}
# Cases that must hold a tighter factor of sum than the rules': none now.
KNOWN_BOUNDS = {}


def case_names(cases_dir):
    """The case directories of cases_dir (those holding a base.ply), sorted."""
    return sorted(c for c in os.listdir(cases_dir)
                  if os.path.isfile(os.path.join(cases_dir, c, "base.ply")))


def exact_case(case):
    """Disjoint and identical cases: their edits must come back whole."""
    return "disjoint" in case or "identical" in case


def parse(table):
    """{case: {method: {kind: value}}}; kind "error" holds a message."""
    results = {}
    for line in table.splitlines():
        m = ROW.match(line.strip())
        if m:
            case, method, kind, value = m.groups()
            results.setdefault(case, {}).setdefault(method, {})[kind] = float(value)
        elif "FAILED" in line or "WRONG SHAPE" in line:
            parts = line.split(None, 2)
            results.setdefault(parts[0], {}).setdefault(parts[1], {})["error"] = parts[2]
    return results


def ideals_apart(case_dir):
    """How far apart the case's two ideals are, scored as rel_err is (over the finest edit's
    support, relative to its size)."""
    finest, stack, frame, _ = ideal_conflict.load(case_dir)
    return ideal_conflict.rel_err(frame, stack, finest)


def check(results, cases, apart=lambda case: 0.0):
    """Returns [(case, rule, message)] for every violated rule. apart(case): the distance
    between its ideals, printed with a stack-rule miss."""
    problems = []

    def value(case, method, kind):
        return results.get(case, {}).get(method, {}).get(kind)

    def bounded(case, rule, v, s):
        """A case's own bound (KNOWN_BOUNDS): full's v within bound x sum's s."""
        bound = KNOWN_BOUNDS.get((case, rule))
        if v is not None and s is not None and bound and not v <= bound * s:
            problems.append((case, rule + " bound", "%s ideal: full %.4f > %.1f x sum %.4f"
                             % (rule, v, bound, s)))

    for case in cases:
        for method in METHODS:
            err = value(case, method, "error")
            if err is not None or method not in results.get(case, {}):
                problems.append((case, "result", "%s gave no result: %s" % (method, err)))
        exact = exact_case(case)
        rows = [case, case + "/frame"]
        if exact:
            for row in rows:
                v = value(row, "full", "rel_err")
                if v is not None and not v <= EXACT_LIMIT:
                    problems.append((case, "exact", "%s: full rel_err=%.4f > %.2f"
                                     % (row, v, EXACT_LIMIT)))
        elif case + "/frame" in results:
            v = value(case + "/frame", "full", "rel_err")
            for baseline in ("(sum)", "(weighted-translation)"):
                b = value(case + "/frame", baseline, "rel_err")
                if v is not None and b is not None and not v < b:
                    problems.append((case, "frame", "frame ideal: full %.4f is not below %s %.4f"
                                     % (v, baseline, b)))
            bounded(case, "frame", v, value(case + "/frame", "(sum)", "rel_err"))
            v, s = value(case, "full", "rel_err"), value(case, "(sum)", "rel_err")
            if v is not None and s is not None and not v <= STACK_FACTOR * s:
                gap = apart(case)
                rule = "stack is sum" if s <= STACK_IS_SUM and gap > EXACT_LIMIT else "stack"
                problems.append((case, rule, "stacked ideal: full %.4f > %.1f x sum %.4f; "
                                 "the ideals are %.4f apart" % (v, STACK_FACTOR, s, gap)))
                # Even where the rule cannot be met, full is no farther from the stack
                # than the frame ideal is: the stacked ideal as a sanity check.
                if not v <= gap:
                    problems.append((case, "stack sanity", "stacked ideal: full %.4f is "
                                     "farther from it than the frame ideal (%.4f)" % (v, gap)))
            bounded(case, "stack", v, s)
        v = value(case, "full", "roughness")
        if v is not None and not v <= ROUGHNESS_LIMIT:
            problems.append((case, "roughness", "full roughness=%.3f > %.1f" % (v, ROUGHNESS_LIMIT)))
        f, s = value(case + "/folds", "full", "new_folds"), value(case + "/folds", "(sum)", "new_folds")
        if f is not None and s is not None and f > s:
            problems.append((case, "folds", "full adds %d folds, sum %d" % (f, s)))
    return problems


def check_artists(binary, cases_dir, case):
    """Rule violations of the per-artist scores of one case, as (case, rule, message)."""
    problems = []
    exact = exact_case(case)
    for ideal, artist, e in artists.score_case(binary, os.path.join(cases_dir, case)):
        where = "artist %s against %s" % (artist, ideal)
        if exact and not e["full"] <= EXACT_LIMIT:
            problems.append((case, "exact", "%s: full %.4f > %.2f" % (where, e["full"], EXACT_LIMIT)))
        elif not exact and ideal == "ideal_frame" and not e["full"] <= e["(sum)"] + ARTIST_SLACK:
            problems.append((case, "artist", "%s: full %.4f keeps less than sum %.4f"
                             % (where, e["full"], e["(sum)"])))
    return problems


def score(scorer, binary, cases_dir, echo=True):
    run = subprocess.run([sys.executable, scorer, cases_dir, binary] + METHODS,
                         capture_output=True, text=True)
    if echo:
        sys.stdout.write(run.stdout)
    if run.returncode != 0:
        sys.stdout.write(run.stderr)
        return None
    return run.stdout


def main():
    if len(sys.argv) < 4:
        print("usage: check_eval.py SCORER CSCULPT_BIN CASES_DIR [CASES_DIR ...]", file=sys.stderr)
        return 2
    scorer, binary, dirs = sys.argv[1], sys.argv[2], sys.argv[3:]
    for path in [scorer] + dirs:
        if not os.path.exists(path):
            print("SKIP: %s is missing" % path)
            return SKIP
    if subprocess.run([sys.executable, "-c", "import numpy"], capture_output=True).returncode:
        print("SKIP: %s has no numpy (Debian: python3-numpy)" % sys.executable)
        return SKIP
    problems, cases = [], []
    for d in dirs:
        here = case_names(d)
        table = score(scorer, binary, d)
        if table is None:
            print("FAIL: the scorer failed on %s" % d)
            return 1
        problems += check(parse(table), here, lambda case, d=d: ideals_apart(os.path.join(d, case)))
        for case in here:
            problems += check_artists(binary, d, case)
        cases += here
    limits = dict(KNOWN_LIMITS)
    limits.update({(p[0], p[1]): "the stacked ideal is sum itself, the frame ideal is not: "
                   "no merge meets both rules" for p in problems if p[1] == "stack is sum"})
    known = [p for p in problems if (p[0], p[1]) in limits]
    new = [p for p in problems if (p[0], p[1]) not in limits]
    for case, rule, message in known:
        print("known limit: %s: %s (%s)" % (case, message, limits[(case, rule)]))
    gone = set(KNOWN_LIMITS) - {(p[0], p[1]) for p in known}
    for case, rule in sorted(gone):
        if case in cases:
            print("known limit no longer occurs: %s %s (remove it from KNOWN_LIMITS)" % (case, rule))
    if new:
        print("FAIL: %d rule(s) violated:" % len(new))
        for case, rule, message in new:
            print("  - %s: %s" % (case, message))
        return 1
    print("OK: all rules hold on %d cases, %d known limits" % (len(cases), len(known)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
