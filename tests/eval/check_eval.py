#!/usr/bin/python3
"""Checks the merge against the Blender-authored cases (shared/eval/README.md).

usage: check_eval.py CASES_DIR CSCULPT_BIN

Runs CASES_DIR/../score_merge.py on every case with the methods below, prints its table, and
asserts the README's "what good looks like" rules:
  - `full`: rel_err < 0.05 on disjoint_sphere and identical_capsule;
  - on every case whose name contains "bend" or "twist": full's rel_err below both the
    "(sum)" and the "(weighted-translation)" baselines (the detail must turn with the edit);
  - grab_vs_smooth_monkey: full's roughness <= 1.0 (no seams or spikes);
  - every method the scorer ran produced a result (no FAILED / WRONG SHAPE rows).
Exits 0 when all hold, 1 with one message per violated rule otherwise, and SKIP (77) when
the cases directory or numpy (which the scorer needs) is missing.
"""
import os
import re
import subprocess
import sys

SKIP = 77  # the test's SKIP_RETURN_CODE
METHODS = ["full", "paper-blend", "single-parent", "single-level-isometry",
           "multiscale-translation"]
NEAR_ZERO_CASES = ["disjoint_sphere", "identical_capsule"]
NEAR_ZERO_LIMIT = 0.05
ROUGHNESS_CASE = "grab_vs_smooth"
ROUGHNESS_LIMIT = 1.0
BASELINES = ["(sum)", "(weighted-translation)"]

ROW = re.compile(r"^(\S+)\s+(\S+)\s+(.*)$")


def parse(table):
    """{case: {method: ("rel_err" | "roughness" | "error", value or message)}}"""
    results = {}
    for line in table.splitlines():
        m = ROW.match(line.strip())
        if not m or line.startswith("case "):
            continue
        case, method, score = m.groups()
        entry = results.setdefault(case, {})
        s = re.match(r"^(rel_err|roughness)=(\S+)$", score)
        if s:
            entry[method] = (s.group(1), float(s.group(2)))
        else:
            entry[method] = ("error", score)
    return results


def check(results, cases):
    problems = []

    def score(case, method, kind):
        r = results.get(case, {}).get(method)
        if r is None:
            problems.append("%s: no score for %s in the scorer's output" % (case, method))
            return None
        if r[0] == "error":
            problems.append("%s: %s did not produce a result: %s" % (case, method, r[1]))
            return None
        if r[0] != kind:
            problems.append("%s: %s has %s, expected %s" % (case, method, r[0], kind))
            return None
        if r[1] != r[1]:  # NaN
            problems.append("%s: %s %s is NaN" % (case, method, kind))
            return None
        return r[1]

    for case in cases:
        for method in METHODS:
            r = results.get(case, {}).get(method)
            if r is None or r[0] == "error":
                score(case, method, "rel_err")  # records the problem

    for case in NEAR_ZERO_CASES:
        if case not in cases:
            problems.append("%s: case missing from the cases directory" % case)
            continue
        v = score(case, "full", "rel_err")
        if v is not None and not v < NEAR_ZERO_LIMIT:
            problems.append("%s: full rel_err=%.4f, must be < %.2f (the edits must survive "
                            "whole)" % (case, v, NEAR_ZERO_LIMIT))

    rotational = [c for c in cases if "bend" in c or "twist" in c]
    if not rotational:
        problems.append("no case whose name contains 'bend' or 'twist'")
    for case in rotational:
        v = score(case, "full", "rel_err")
        for baseline in BASELINES:
            b = score(case, baseline, "rel_err")
            if v is not None and b is not None and not v < b:
                problems.append("%s: full rel_err=%.4f is not below %s rel_err=%.4f (the detail "
                                "must turn with the coarse rotation)" % (case, v, baseline, b))

    rough_cases = [c for c in cases if ROUGHNESS_CASE in c]
    if not rough_cases:
        problems.append("no case whose name contains '%s'" % ROUGHNESS_CASE)
    for case in rough_cases:
        v = score(case, "full", "roughness")
        if v is not None and not v <= ROUGHNESS_LIMIT:
            problems.append("%s: full roughness=%.3f, must be <= %.1f (seams or spikes)"
                            % (case, v, ROUGHNESS_LIMIT))
    return problems


def main():
    if len(sys.argv) != 3:
        print("usage: check_eval.py CASES_DIR CSCULPT_BIN", file=sys.stderr)
        return 2
    cases_dir, binary = sys.argv[1], sys.argv[2]
    if not os.path.isdir(cases_dir):
        print("SKIP: no Blender-authored cases at %s" % cases_dir)
        return SKIP
    scorer = os.path.join(os.path.dirname(os.path.abspath(cases_dir)), "score_merge.py")
    if not os.path.isfile(scorer):
        print("FAIL: the cases exist but the scorer %s does not" % scorer)
        return 1
    if not os.access(binary, os.X_OK):
        print("FAIL: %s is not an executable csculpt" % binary)
        return 1
    probe = subprocess.run([sys.executable, "-c", "import numpy"], capture_output=True)
    if probe.returncode != 0:
        print("SKIP: %s has no numpy (Debian: python3-numpy), which %s needs"
              % (sys.executable, scorer))
        return SKIP
    cases = sorted(c for c in os.listdir(cases_dir)
                   if os.path.isfile(os.path.join(cases_dir, c, "base.ply")))
    run = subprocess.run([sys.executable, scorer, cases_dir, binary] + METHODS,
                         capture_output=True, text=True)
    sys.stdout.write(run.stdout)
    if run.returncode != 0:
        sys.stdout.write(run.stderr)
        print("FAIL: %s exited with %d" % (scorer, run.returncode))
        return 1
    problems = check(parse(run.stdout), cases)
    if problems:
        print("FAIL: %d rule(s) of shared/eval/README.md violated:" % len(problems))
        for p in problems:
            print("  - " + p)
        return 1
    print("OK: all rules hold on %d cases (%s)" % (len(cases), ", ".join(cases)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
