#!/usr/bin/python3
"""The README's and docs/merge-quality.md's case table, as Markdown.

usage: table.py SCORER CSCULPT_BIN CASES_DIR [CASES_DIR ...]
       table.py --methods SCORER CSCULPT_BIN CASES_DIR [CASES_DIR ...]
Runs the scorer as check_eval.py does and prints one row per case: rel_err against the frame
ideal and the stacked one for full, frame-transport (full before the hedge toward the stacked
reading), hierarchy-blend (full before frame transport), sum and weighted-translation, and the
new folds of full / frame-transport / hierarchy-blend / sum.

With --methods, every merge method the CLI has (and the scorer's baselines) instead, one row
per method over all the cases: against each ideal, the median rel_err and on how many cases it
meets the issue's rule (frame: below sum and weighted-translation; stack: within 1.5x sum;
disjoint and identical: within 0.01 of every ideal), and the new folds, in all and on how many
cases more than sum's."""
import os
import statistics
import subprocess
import sys

import check_eval

COLUMNS = ["full", "frame-transport", "hierarchy-blend", "(sum)", "(weighted-translation)"]
STACKED = 4  # the first columns, also scored against the stacked ideal and for folds


def cell(results, row, method, kind):
    v = results.get(row, {}).get(method, {}).get(kind)
    return "–" if v is None else ("%d" % v if kind == "new_folds" else "%.4f" % v)


def all_methods(binary):
    """The methods `csculpt merge --method` accepts, from its help."""
    out = subprocess.run([binary, "merge", "--help"], capture_output=True, text=True).stdout
    line = next(l for l in out.splitlines() if l.strip().startswith("--method"))
    return [m.strip() for m in line.split(None, 2)[2].split(",")]  # "--method TEXT=full  a, b"


def median(values):
    """The median of the values that exist ("–" when none does)."""
    present = [v for v in values if v is not None]
    return "%.3f" % statistics.median(present) if present else "–"


def methods_table(scorer, binary, dirs):
    # The CLI's sum, weighted-translation and average are the scorer's own baselines.
    skip = ("sum", "weighted-translation", "average")
    methods = [m for m in all_methods(binary) if m not in skip]
    results, cases = {}, []
    for d in dirs:
        run = subprocess.run([sys.executable, scorer, d, binary] + methods,
                             capture_output=True, text=True, check=True)
        results.update(check_eval.parse(run.stdout))
        cases += check_eval.case_names(d)
    exact = [c for c in cases if check_eval.exact_case(c)]
    meet = [c for c in cases if c not in exact and c + "/frame" in results]
    value = lambda row, m, k: results.get(row, {}).get(m, {}).get(k)
    # A method without a result on a case misses that case's rule.
    below = lambda x, *bounds: x is not None and all(b is not None and x < b for b in bounds)
    print("| method | frame: median rel_err | frame: below sum and w-t (of %d) | stack: median "
          "rel_err | stack: within 1.5x sum (of %d) | disjoint, identical: within 0.01 (of %d) "
          "| new folds: all | cases with more than sum (of %d) |"
          % (len(meet), len(meet), len(exact), len(cases)))
    print("|---" * 8 + "|")
    for m in methods + ["(sum)", "(weighted-translation)", "(average)"]:
        fr = [value(c + "/frame", m, "rel_err") for c in meet]
        st = [value(c, m, "rel_err") for c in meet]
        frame_ok = sum(below(f, value(c + "/frame", "(sum)", "rel_err"),
                             value(c + "/frame", "(weighted-translation)", "rel_err"))
                       for c, f in zip(meet, fr))
        stack_ok = sum(below(v, 1.5 * value(c, "(sum)", "rel_err") + 1e-12)
                       for c, v in zip(meet, st))
        whole = sum(value(c, m, "rel_err") is not None and
                    all(below(value(r, m, "rel_err"), 0.01 + 1e-12) for r in (c, c + "/frame")
                        if value(r, "(sum)", "rel_err") is not None) for c in exact)
        folds = [value(c + "/folds", m, "new_folds") for c in cases]
        sums = [value(c + "/folds", "(sum)", "new_folds") for c in cases]
        more = sum(f is None or f > s for f, s in zip(folds, sums) if s is not None)
        print("| %s | %s | %d | %s | %d | %d | %d | %d |" % (
            m.strip("()"), median(fr), frame_ok, median(st), stack_ok, whole,
            sum(f for f in folds if f is not None), more))


def main():
    if sys.argv[1] == "--methods":
        return methods_table(sys.argv[2], sys.argv[3], sys.argv[4:])
    scorer, binary, dirs = sys.argv[1], sys.argv[2], sys.argv[3:]
    results, cases = {}, []
    for d in dirs:
        table = check_eval.score(scorer, binary, d, echo=False)
        results.update(check_eval.parse(table))
        cases += check_eval.case_names(d)
    names = [c.strip("()") for c in COLUMNS]
    print("| case | " + " | ".join(n + " (frame)" for n in names) + " | " +
          " | ".join(n + " (stack)" for n in names[:STACKED]) + " | new folds: " +
          " / ".join(names[:STACKED]) + " |")
    print("|---" * (2 + len(COLUMNS) + STACKED) + "|")
    for case in sorted(cases):
        frame = [cell(results, case + "/frame", m, "rel_err") for m in COLUMNS]
        kind = "rel_err" if results.get(case, {}).get("full", {}).get("rel_err") is not None else "roughness"
        stack = [cell(results, case, m, kind) for m in COLUMNS[:STACKED]]
        folds = " / ".join(cell(results, case + "/folds", m, "new_folds") for m in COLUMNS[:STACKED])
        label = case if kind == "rel_err" else case + " (roughness)"
        print("| %s | %s | %s | %s |" % (label, " | ".join(frame), " | ".join(stack), folds))


if __name__ == "__main__":
    main()
