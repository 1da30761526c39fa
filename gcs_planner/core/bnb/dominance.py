"""Dominance between partial routes at one point: their length, corrections and error-state
distributions (Hall's condition), in a relaxation whose legs may depend on the arc flown last."""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from gcs_planner.core.pair_bounds import PairBounds
from gcs_planner.core.proof import PROB_EPS

# Dominance between error-state distributions asks Hall's condition of at most this many sets
# (``_stochastically_dominates``); beyond, the partial routes are kept apart (always safe).
MAX_UNIONS = 256


def _key(critical: frozenset[int] | None, j: int, before: tuple[int, ...]) -> tuple:
    """Where a partial route at j that visited ``before`` is compared with others: j and the
    critical points it visited (their revisits are barred)."""
    return (j, frozenset(critical.intersection(before)) if critical else frozenset())


def _pair_margin(pairs: PairBounds | None, kept: int, new: int) -> float:
    """How much longer the next leg can be for a partial route that came to j by arc ``kept``
    than for one that came by arc ``new``, in the pair relaxation (0 without it). Only the
    next leg depends on the arc (lb(i, j, t)); every leg after it is lb(j, t, u) for both. So
    a partial route that is this much shorter, with errors this much smaller, than another
    at j continues no worse whatever it does: its next leg is at most this much longer, every
    later one the same."""
    if pairs is None or kept == new:
        return 0.0
    return pairs.margin(kept, new)


def _kept(L: float, k: int, states: dict, mass: float, arc: int) -> tuple:
    """A partial route as the dominance tests keep it: (L, k, error states, mass, arc flown
    last, least vertical error, least horizontal error)."""
    return (L, k, states, mass, arc, min(v for v, _ in states), min(h for _, h in states))


def _dominated_by(
    kept: Sequence[tuple], state: tuple, pairs: PairBounds | None, upto: int | None = None
) -> bool:
    """Whether a partial route at a point, ``state`` (``_kept``), continues no better than one
    of ``kept`` (at the same point, having visited the same critical points) whatever it does
    next, in a relaxation whose legs depend on the arc flown last only through ``pairs``
    (``_pair_margin``). ``upto``: only the first so many of ``kept`` are asked (those no
    longer than ``state`` when ``kept`` is sorted by length: no longer one dominates)."""
    L, k, states, mass, arc, v, h = state
    for aL, ak, ast, am, a_arc, av, ah in itertools.islice(kept, upto):
        # The cheap tests first; the least errors of a dominating distribution are no larger.
        if aL > L or ak > k or am < mass - PROB_EPS or av > v or ah > h:
            continue
        shift = _pair_margin(pairs, a_arc, arc)
        if (
            aL + shift <= L
            and av + shift <= v
            and ah + shift <= h
            and _stochastically_dominates(_shifted(ast, shift), states)
        ):
            return True
    return False


def _shifted(states: dict, shift: float) -> dict:
    """Error states with ``shift`` metres more on both components."""
    if shift == 0.0:
        return states
    return {(v + shift, h + shift): m for (v, h), m in states.items()}


def _larger(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The pointwise larger of two bounds per m (each carried on with its last entry)."""
    if len(a) == len(b):
        return np.maximum(a, b)
    width = max(len(a), len(b))
    out = np.empty(width)
    out[: len(a)] = a
    out[len(a) :] = a[-1]
    other = np.empty(width)
    other[: len(b)] = b
    other[len(b) :] = b[-1]
    return np.maximum(out, other, out=out)


def _stochastically_dominates(d1: dict, d2: dict) -> bool:
    """Whether every continuation succeeds at least as often from the error-state distribution
    ``d1`` as from ``d2``. Success from a state only falls as either error grows, so this holds
    when d2's mass can be moved, unit by unit, onto d1's states no worse in both components:
    by Hall's theorem, when every set S of d2's states weighs no more than d1's states lying
    below some state of S. Where more than MAX_UNIONS sets would have to be asked (only with
    more than 8 states in d2), the two are not compared (False is always safe)."""
    if len(d1) == 1:  # one state: it must lie below every state of d2 and weigh as much
        (((v1, h1), m1),) = d1.items()
        return all(v1 <= v2 and h1 <= h2 for v2, h2 in d2) and m1 >= sum(d2.values()) - PROB_EPS
    if len(d2) == 1:  # one state: the states of d1 below it must weigh as much
        (((v2, h2), m2),) = d2.items()
        return sum(m for (v1, h1), m in d1.items() if v1 <= v2 and h1 <= h2) >= m2 - PROB_EPS
    weights = list(d1.values())
    # Per state of d2: the set (a bit mask) of d1's states below it, and its mass.
    below: list[tuple[int, float]] = []
    for (v2, h2), m2 in d2.items():
        bits = 0
        for i, (v1, h1) in enumerate(d1):
            if v1 <= v2 and h1 <= h2:
                bits |= 1 << i
        if not bits:
            return False
        below.append((bits, m2))
    # Hall's condition need only be asked of the sets S closed under "below": for a union R of
    # masks, of all of d2's states whose masks lie within R. Any other S with the same reach R
    # is a subset of that one and needs no more. The unions are few where the masks nest.
    unions = {0}
    for bits in {b for b, _ in below}:
        unions |= {u | bits for u in unions}
        if len(unions) > MAX_UNIONS:
            return False
    unions.discard(0)
    for reach in unions:
        need = sum(m2 for bits, m2 in below if bits | reach == reach)
        have = sum(w for i, w in enumerate(weights) if reach >> i & 1)
        if need > have + PROB_EPS:
            return False
    return True
