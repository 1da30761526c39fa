"""Dominance between partial routes at one point (``bnb.dominance._dominated_by``, the Python
search's and probes' check) against its definition, decided independently: a kept partial
route dominates a new one when it is no longer by at least the pair margin between their last
arcs, has no more corrections, and its error states, made worse by that margin, can take all of
the new one's mass (the transport LP of ``support.transport``). Best-first order seldom puts a
longer partial route ahead of a shorter one at the same point, so the fronts of small
scenarios do not show a loosened check; this does."""

from __future__ import annotations

import random

import pytest
from support.transport import movable

from gcs_planner.core.bnb.dominance import _dominated_by, _kept


class _Margins:
    """A pair relaxation's margins between arcs into one point (``PairBounds.margin``)."""

    def __init__(self, rng: random.Random, arcs: int) -> None:
        self.table = {(a, b): rng.choice([0.0, 0.0, 0.3, 0.7, 1.6]) for a in range(arcs)
                      for b in range(arcs)}  # fmt: skip

    def margin(self, kept: int, new: int) -> float:
        return self.table[kept, new]


def _states(rng: random.Random, grid: int) -> dict:
    states = {(float(rng.randint(0, grid)), float(rng.randint(0, grid)))
              for _ in range(rng.randint(1, 5))}  # fmt: skip
    weights = [rng.random() + 0.05 for _ in states]
    mass = rng.choice([1.0, 1.0, 0.8])
    return {s: mass * w / sum(weights) for s, w in zip(states, weights)}


def _near(rng: random.Random, other: tuple, grid: int) -> tuple:
    """A partial route close to ``other``: a little shorter or longer, a correction more or
    fewer, its states moved either way; so that the answer turns on each test."""
    L, k, states, _, _ = other
    moved: dict = {}
    for (v, h), m in states.items():
        state = (
            max(0.0, v + rng.choice([-1, 0, 0, 0.3, 1, 2])),
            max(0.0, h + rng.choice([-1, 0, 0, 0.7, 1])),
        )
        moved[state] = moved.get(state, 0.0) + m * rng.choice([1.0, 1.0, 1.0, 0.9, 1.1])
    longer = rng.choice([-2.0, -0.7, -0.3, 0.0, 0.0, 0.4, 1.0, 3.0])
    more = rng.choice([-1, 0, 0, 1])
    return (L + longer, max(0, k + more), moved, sum(moved.values()), rng.randrange(3))


def _expected(kept: list[tuple], new: tuple, margins: _Margins | None) -> bool | None:
    """The definition, or None where the LP's own rounding would decide."""
    L, k, states, mass, arc = new
    close = False
    for aL, ak, ast, _, a_arc in kept:
        shift = 0.0 if margins is None or a_arc == arc else margins.margin(a_arc, arc)
        if aL + shift > L or ak > k:
            continue
        worse = {(v + shift, h + shift): m for (v, h), m in ast.items()}
        shortfall = mass - movable(worse, states)
        if shortfall <= 1e-9:
            return True
        close |= shortfall < 1e-6
    return None if close else False


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("with_pairs", [False, True])
def test_dominance_between_partial_routes_equals_its_definition(
    seed: int, with_pairs: bool
) -> None:
    rng = random.Random(seed * 2 + with_pairs)
    decided = {True: 0, False: 0}
    for _ in range(400):
        grid = rng.choice([2, 4])
        margins = _Margins(rng, 3) if with_pairs else None
        kept = []
        for _ in range(rng.randint(1, 3)):
            states = _states(rng, grid)
            kept.append((float(rng.randint(0, 20)), rng.randint(0, 4), states,
                         sum(states.values()), rng.randrange(3)))  # fmt: skip
        new = _near(rng, rng.choice(kept), grid)
        expected = _expected(kept, new, margins)
        if expected is None:
            continue
        got = _dominated_by([_kept(*a) for a in kept], _kept(*new), margins)
        assert got is expected, (kept, new)
        decided[expected] += 1
    assert decided[True] >= 25 and decided[False] >= 25  # both answers are exercised
