#!/usr/bin/python3
"""The README's and docs/merge-quality.md's case table, as Markdown.

usage: table.py SCORER CSCULPT_BIN CASES_DIR [CASES_DIR ...]
Runs the scorer as check_eval.py does and prints one row per case: rel_err against the frame
ideal and the stacked one for full, frame-transport (full before the hedge toward the stacked
reading), hierarchy-blend (full before frame transport), sum and weighted-translation, and the
new folds of full / frame-transport / hierarchy-blend / sum."""
import os
import sys

import check_eval

COLUMNS = ["full", "frame-transport", "hierarchy-blend", "(sum)", "(weighted-translation)"]
STACKED = 4  # the first columns, also scored against the stacked ideal and for folds


def cell(results, row, method, kind):
    v = results.get(row, {}).get(method, {}).get(kind)
    return "–" if v is None else ("%d" % v if kind == "new_folds" else "%.4f" % v)


def main():
    scorer, binary, dirs = sys.argv[1], sys.argv[2], sys.argv[3:]
    results, cases = {}, []
    for d in dirs:
        table = check_eval.score(scorer, binary, d, echo=False)
        results.update(check_eval.parse(table))
        cases += sorted(c for c in os.listdir(d) if os.path.isfile(os.path.join(d, c, "base.ply")))
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
