#!/usr/bin/python3
"""Can any merge meet both ideals' rules at once? An oracle check, no merge involved.

usage: ideal_conflict.py [--pull CSCULPT_BIN | --alpha] CASES_DIR [CASES_DIR ...]

The rules ask, where a detail and a coarse edit meet: against ideal_frame.ply below "sum",
and against ideal.ply within 1.5x "sum". Where the two ideals disagree (tapers, casts, grab
falloffs: a deformer acting on the detail volumetrically), a merge has to pick a point
between them. This takes the best such point a method could ever produce, knowing both
ideals: x(a) = (1 - a) * frame + a * stack, and prints, per case, the interval of a for which
x(a) meets both rules, then the intersection over all cases, then the results off that
segment, pulled toward "sum" by b, that meet both rules everywhere. An empty intersection means
that no method whose result lies between the two ideals meets both rules on every case; a
method must then move toward "sum" and give up part of the frame ideal everywhere the
deformation is not rigid (docs/merge-quality.md, "Limits").

With --pull, it prints instead, for every case where `full` (run by CSCULPT_BIN) misses the
stack rule, the least pull toward "sum", x = full + b (sum - full) in steps of 0.05, that meets
both rules, and what that x keeps of the frame ideal (its error as a share of sum's): what
meeting the rule would cost `full` itself.

With --alpha, it reads each case by what a merge cannot see: how the coarse deformer acts on
the detail off the surface. Over the finest edit's support, the stack's departure from "sum"
is split into a part along the frame ideal's departure, alpha * (frame - sum), and a rest
across it (its size as a share of |frame - sum|). alpha is +1 where the deformer turns the
volume as the surface turns (bends, twists: the ideals agree), about 0 where it shears it
(tapers, a grab pulling along the detail: the stack keeps the detail's direction, as "sum"
does) and negative where its Jacobian is symmetric (a Cast: the stack tilts the detail the
other way). A merge that carries the detail by a share t of the surface's turn,
x = sum + t (frame - sum), meets the frame rule for 0 < t < 2 and the stack rule for t in
alpha -+ sqrt(2.25 alpha^2 + 1.25 across^2), exactly (the scores are RMS over the support, so
both are quadratic in t); the intersection over all cases is what any one t can do."""
import os
import sys

import numpy as np

import artists

STEPS = 100


def rel_err(x, ideal, finest):
    return artists.support_error(x, ideal, finest)


def load(case_dir):
    names = [n for n in artists.ARTISTS if os.path.exists(os.path.join(case_dir, n + ".ply"))]
    base = artists.read_ply(os.path.join(case_dir, "base.ply"))
    ds = [artists.read_ply(os.path.join(case_dir, n + ".ply")) - base for n in names]
    finest = min(ds, key=lambda d: np.sqrt((np.linalg.norm(d, axis=1) ** 2).mean()))
    stack = artists.read_ply(os.path.join(case_dir, "ideal.ply"))
    frame = artists.read_ply(os.path.join(case_dir, "ideal_frame.ply"))
    return finest, stack, frame, base + sum(ds)


def passes(x, finest, stack, frame, plain):
    return (rel_err(x, frame, finest) < rel_err(plain, frame, finest) and
            rel_err(x, stack, finest) <= 1.5 * rel_err(plain, stack, finest))


def toward_sum(cases):
    """(a, b, worst frame error as a share of sum's) for the results
    frame + a (stack - frame) + b (sum - frame) that meet both rules on every case."""
    found = []
    for a in np.arange(0, 1.001, 0.1):
        for b in np.arange(0, 1.001, 0.1):
            ok, share = True, 0.0
            for finest, stack, frame, plain in cases:
                x = frame + a * (stack - frame) + b * (plain - frame)
                if not passes(x, finest, stack, frame, plain):
                    ok = False
                    break
                share = max(share, rel_err(x, frame, finest) / rel_err(plain, frame, finest))
            if ok:
                found.append((a, b, share))
    return found


def interval(case):
    """(lo, hi) of a in [0, 1] meeting both rules for a loaded case, or None when the ideals
    agree."""
    finest, stack, frame, plain = case
    if rel_err(frame, stack, finest) < 0.01:
        return None
    ok = [a / STEPS for a in range(STEPS + 1)
          if passes((1 - a / STEPS) * frame + a / STEPS * stack, finest, stack, frame, plain)]
    return (min(ok), max(ok)) if ok else (1.0, 0.0)


def least_pull(binary, case_dir):
    """(full's stack error over sum's, least b, frame share at b) for a case where full misses
    the stack rule, else None."""
    finest, stack, frame, plain = load(case_dir)
    names = [n for n in artists.ARTISTS if os.path.exists(os.path.join(case_dir, n + ".ply"))]
    full = artists.merge(binary, case_dir, names, "full")
    plain_stack = rel_err(plain, stack, finest)
    if plain_stack == 0:
        return None  # disjoint: the exactness rule applies, not this one
    ratio = rel_err(full, stack, finest) / plain_stack
    if ratio <= 1.5:
        return None
    for b in np.arange(0, 1.001, 0.05):
        x = full + b * (plain - full)
        if passes(x, finest, stack, frame, plain):
            return ratio, b, rel_err(x, frame, finest) / rel_err(plain, frame, finest)
    return ratio, None, None


def alpha_reading(case):
    """(alpha, across, lo, hi) of a loaded case: the stack's departure from sum along and
    across the frame ideal's, and the turn shares t meeting both rules (lo > hi: none)."""
    finest, stack, frame, plain = case
    sup = artists.support(finest)
    f, s = (frame - plain)[sup], (stack - plain)[sup]
    ff = float((f * f).sum())
    alpha = float((s * f).sum()) / ff
    across2 = max(0.0, float((s * s).sum()) / ff - alpha * alpha)
    reach = np.sqrt(2.25 * alpha * alpha + 1.25 * across2)
    return alpha, np.sqrt(across2), max(alpha - reach, 0.0), min(alpha + reach, 2.0)


def alpha_main(roots):
    lo, hi = 0.0, 2.0
    for case, path in case_dirs(roots):
        data = load(path)
        if rel_err(data[2], data[1], data[0]) < 0.01:
            continue  # the ideals agree: any t near 1 meets both
        alpha, across, a, b = alpha_reading(data)
        print("%-34s alpha %+.2f  across %.2f  turn share t in (%.2f, %.2f]" %
              (case, alpha, across, a, b) if a <= b else
              "%-34s alpha %+.2f  across %.2f  no t meets both rules" % (case, alpha, across))
        lo, hi = max(lo, a), min(hi, b)
    print("every case: " + ("t in (%.2f, %.2f]; t = 1 is the frame ideal, t = 0 is sum" % (lo, hi)
                            if lo <= hi else "no one t meets both rules"))


def case_dirs(roots):
    for d in roots:
        for case in sorted(os.listdir(d)):
            path = os.path.join(d, case)
            if os.path.exists(os.path.join(path, "ideal_frame.ply")):
                yield case, path


def pull_main(binary, roots):
    for case, path in case_dirs(roots):
        found = least_pull(binary, path)
        if found is None:
            continue
        ratio, b, share = found
        print("%-34s full %.2fx sum against the stack; " % (case, ratio) +
              ("least pull b %.2f, keeping %.2f of sum's frame error" % (b, share)
               if b is not None else "no pull meets both rules"))


def main():
    if len(sys.argv) > 2 and sys.argv[1] == "--pull":
        return pull_main(sys.argv[2], sys.argv[3:])
    if len(sys.argv) > 1 and sys.argv[1] == "--alpha":
        return alpha_main(sys.argv[2:])
    lo, hi = 0.0, 1.0
    conflicting = []
    for case, path in case_dirs(sys.argv[1:]):
        case_data = load(path)
        r = interval(case_data)
        if r is None:
            print("%-34s the ideals agree" % case)
            continue
        print("%-34s a in [%.2f, %.2f]" % (case, r[0], r[1]))
        conflicting.append(case_data)
        lo, hi = max(lo, r[0]), min(hi, r[1])
    print("every case: " + ("a in [%.2f, %.2f]" % (lo, hi) if lo <= hi else
                            "no a meets both rules (the ideals conflict)"))
    print("off the segment, frame + a (stack - frame) + b (sum - frame), meeting both rules on "
          "every case where the ideals differ (worst frame error as a share of sum's):")
    for a, b, share in toward_sum(conflicting):
        print("  a %.1f  b %.1f  %.2f" % (a, b, share))


if __name__ == "__main__":
    main()
