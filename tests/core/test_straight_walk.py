"""The depth-first walk of straight routes (support/straight_walk.py), the reference of the
three-objective straight-leg tests, gives exactly the front of the plain enumeration of every
simple route (support/enumeration.py), on the scenarios those tests draw: dense and sparse, up
to five correction points, corrections that fail and some that never succeed."""

from __future__ import annotations

from support.enumeration import enumerate_straight_front
from support.scenarios import uncertain_straight_scenario
from support.straight_walk import walked_straight_front


def test_the_walked_front_is_the_enumerated_one() -> None:
    nonempty = uncertain = five = 0
    for seed in range(200):
        scenario = uncertain_straight_scenario(seed)
        want = enumerate_straight_front(scenario)
        assert walked_straight_front(scenario) == want, seed
        nonempty += bool(want)
        uncertain += any(-1 < w[2] < 0 for w in want)
        five += scenario.n == 7 and bool(want)
    assert nonempty >= 50 and uncertain >= 5 and five >= 10, (nonempty, uncertain, five)
