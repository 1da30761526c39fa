"""Dominance between error-state distributions by an independent method: a transport linear
programme (scipy's HiGHS), shared by the tests of the planner's dominance checks."""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog


def movable(d1: dict, d2: dict) -> float:
    """The most of d2's mass that can be moved onto d1's states lying below it (no larger in
    both components), each state of d1 taking at most its own mass. d1 dominates d2 exactly
    when all of d2's mass can be moved: by max-flow min-cut the shortfall is the largest Hall
    deficiency."""
    s1, s2 = list(d1.items()), list(d2.items())
    pairs = [
        (i, j)
        for i, ((v2, h2), _) in enumerate(s2)
        for j, ((v1, h1), _) in enumerate(s1)
        if v1 <= v2 and h1 <= h2
    ]
    if not pairs:
        return 0.0
    rows, caps = [], []
    for i, (_, m2) in enumerate(s2):  # each state of d2 gives at most its mass
        rows.append([1.0 if a == i else 0.0 for a, _ in pairs])
        caps.append(m2)
    for j, (_, m1) in enumerate(s1):  # each state of d1 takes at most its mass
        rows.append([1.0 if b == j else 0.0 for _, b in pairs])
        caps.append(m1)
    res = linprog(-np.ones(len(pairs)), A_ub=rows, b_ub=caps, bounds=(0, None), method="highs")
    assert res.status == 0
    return -float(res.fun)
