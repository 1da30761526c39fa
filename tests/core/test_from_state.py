"""Planning from a state mid-flight: the state's scenario flies continuations exactly as the
whole route flies them, and the branch and bound's front from a state equals enumeration of
every continuation, with straight and airplane legs, two and three objectives."""

from __future__ import annotations

import numpy as np
import pytest
from support.enumeration import pareto
from support.prefix_flight import PrefixFlights, every_route_flown
from support.scenarios import contingency_scenario

from gcs_planner.core.bnb import Options, bnb_front, flown_route_legs
from gcs_planner.core.from_state import FlightState, original_points, state_scenario
from gcs_planner.core.planner import plan
from gcs_planner.core.probability import outcomes, success_probability
from gcs_planner.errors import GcsPlannerError, InfeasibleError
from gcs_planner.scenario.model import Kind


def _failed_state(sc, rng) -> tuple[FlightState, tuple[int, ...]] | None:
    """A state reached by flying a random prefix that ends at an unreliable point whose fix
    fails (the prefix's other fixes take): the state a policy replans from."""
    corr = [j for j in range(sc.n) if int(sc.kind[j]) in (Kind.V, Kind.H)]
    risky = [j for j in corr if sc.unreliable[j]]
    if not risky:
        return None
    last = int(rng.choice(risky))
    others = [j for j in corr if j != last]
    k = int(rng.integers(0, len(others) + 1))
    prefix = (sc.start, *[int(j) for j in rng.permutation(others)[:k]], last)
    # Flown to B (once: the legs flown_route evaluates), to read the prefix's legs.
    legs = flown_route_legs(sc, (*prefix, sc.end))
    lengths = [float(leg.length) for leg in legs[: len(prefix) - 1]]
    v = h = 0.0
    if not all(np.isfinite(lengths)):
        return None  # a leg of the prefix cannot be flown: no state is reached
    for point, length in zip(prefix[1:], lengths, strict=True):
        v += length
        h += length
        kind = Kind(int(sc.kind[point]))
        ok, failed = outcomes(v, h, kind, sc.params.residual_m)
        v, h = failed if point == last else ok
    leg = legs[len(prefix) - 2]
    if not (leg.reachable and np.isfinite(leg.length)):
        return None
    heading = None if leg.heading_out is None else tuple(float(c) for c in leg.heading_out)
    return FlightState(last, heading, v, h, frozenset(prefix)), prefix


def _enumerated(sub) -> dict[bool, list[tuple]]:
    """Both fronts of every continuation, by whether probability is an objective: each route
    flown once for both."""
    values: dict[bool, list[tuple]] = {False: [], True: []}
    for pts, route in every_route_flown(sub):
        p = success_probability(sub, pts, [s.leg for s in route.stops[1:]]).probability
        for probability in (False, True):
            if (p > 0) if probability else route.feasible:
                length = round(route.length, 6)
                values[probability].append((length, route.corrections, round(-p, 12) * probability))
    return {probability: pareto(v) for probability, v in values.items()}


@pytest.mark.parametrize("radius", [0.0, 1500.0])
def test_a_continuation_is_flown_as_the_whole_route_flies_it(radius: float) -> None:
    """Prefix then continuation, flown whole in the scenario, has the legs of the prefix then
    those of the continuation flown in the state's scenario; and its errors at every stop
    after the state are the same."""
    compared = 0
    for seed in range(60):
        sc = contingency_scenario(seed, radius=radius)
        rng = np.random.default_rng(seed)
        got = _failed_state(sc, rng)
        if got is None:
            continue
        state, prefix = got
        sub, indices = state_scenario(sc, state)
        whole_flights = PrefixFlights(sc)
        for pts, part in every_route_flown(sub):
            whole = whole_flights.route((*prefix[:-1], *original_points(indices, pts)))
            tail = whole.stops[len(prefix) :]
            np.testing.assert_allclose(
                [s.leg.length for s in tail], [s.leg.length for s in part.stops[1:]], rtol=1e-12
            )
            # The errors on arrival, failed fix included, are the state's own.
            if tail and np.isfinite(tail[0].leg.length):
                assert part.stops[1].v_flown == pytest.approx(state.v + tail[0].leg.length)
                assert part.stops[1].h_flown == pytest.approx(state.h + tail[0].leg.length)
            compared += 1
    assert compared > 100


# Compiled from the first label (the search kernel's first label, the probes, the legs), and
# the Python reference.
COMPILED = Options(probe_from=0, trial=0, compiled_legs_from=-1)
PYTHON = Options(compiled_search=False, compiled_probes=False, compiled_legs=False)


@pytest.mark.parametrize(("radius", "objective_sets"), [(0.0, (True,)), (1500.0, (False, True))])
def test_front_from_a_state_equals_enumeration(radius: float, objective_sets: tuple) -> None:
    """Both engines (compiled from the first label, and the Python reference), two and three
    objectives, against one enumeration of each state's continuations."""
    nonempty = dict.fromkeys(objective_sets, 0)
    carried = 0
    for seed in range(120):
        sc = contingency_scenario(seed, radius=radius, lenient=True)
        got = _failed_state(sc, np.random.default_rng(seed + 1000))
        if got is None:
            continue
        state, _ = got
        sub, _ = state_scenario(sc, state)
        fronts = _enumerated(sub)
        for probability in objective_sets:
            want = fronts[probability]
            for options in (COMPILED, PYTHON):
                result = bnb_front(sub, probability=probability, max_labels=10**6, options=options)
                what = (seed, probability, options is COMPILED)
                assert result.optimal, what
                front = [
                    (round(f.length, 6), f.corrections, round(-f.probability, 12) * probability)
                    for f in result.front
                ]
                assert [g[1:] for g in front] == [w[1:] for w in want], what
                np.testing.assert_allclose(
                    [g[0] for g in front], [w[0] for w in want], atol=1e-6, err_msg=str(what)
                )
            nonempty[probability] += bool(want)
        carried += state.v > 0 or state.h > 0
    assert min(nonempty.values()) > 20 and carried > 20


def test_plan_from_a_state_starts_with_its_errors() -> None:
    """The planner (its seeds, focus and straight search) plans the state's scenario: errors at
    A are the state's in the route table, and a state whose errors already pass every limit
    is infeasible with the reason."""
    for seed in range(40):
        sc = contingency_scenario(seed, lenient=True)
        got = _failed_state(sc, np.random.default_rng(seed + 7))
        if got is None:
            continue
        state, _ = got
        sub, _ = state_scenario(sc, state)
        try:
            p = plan(sub, objectives=("length", "corrections"), min_probability=0.0)
        except InfeasibleError:
            continue
        a = p.route.stops[0]
        assert (a.v_flown, a.h_flown) == (state.v, state.h)
        assert p.optimal
        lost = state_scenario(sc, FlightState(state.point, state.heading, 1e9, 1e9, state.visited))
        with pytest.raises(InfeasibleError):
            plan(lost[0], objectives=("length", "corrections"), min_probability=0.0)
        return
    pytest.fail("no scenario with a feasible continuation")


def test_bad_states_are_refused() -> None:
    sc = contingency_scenario(3)
    with pytest.raises(GcsPlannerError, match="at B"):
        state_scenario(sc, FlightState(sc.end, None, 0.0, 0.0, frozenset()))
    with pytest.raises(GcsPlannerError, match="error"):
        state_scenario(sc, FlightState(sc.start, None, -1.0, 0.0, frozenset()))
    with pytest.raises(GcsPlannerError, match="include B"):
        state_scenario(sc, FlightState(sc.start, None, 0.0, 0.0, frozenset({sc.end})))
