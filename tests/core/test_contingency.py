"""Contingency policies: exact evaluation against an independent enumeration of outcome
bit-vectors and a Monte Carlo replay, fixed routes as policies, and replanning on failure."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from support.policies import can_fail_at, random_policy
from support.scenarios import contingency_scenario

from gcs_planner.core.bnb import flown_route, flown_route_legs
from gcs_planner.core.contingency import Policy, evaluate
from gcs_planner.core.probability import success_probability
from gcs_planner.core.replan import brute_continuation, replan_on_failure, search_continuation
from gcs_planner.errors import GcsPlannerError
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Kind, Parameters, Scenario


def _paths(policy: Policy):
    """Every outcome path: (points A..B, outcomes at its branch points)."""
    if policy.leaf:
        yield list(policy.points), []
        return
    for ok, child in ((True, policy.on_success), (False, policy.on_failure)):
        for pts, outs in _paths(child):
            yield list(policy.points) + pts[1:], [ok, *outs]


def _fly_reference(sc: Scenario, points, outcomes):
    """One outcome path flown from scratch over the whole route's legs (not the segments):
    (arrived, flown length; lost ones up to the point found lost)."""
    legs = [leg.length for leg in flown_route_legs(sc, tuple(points))]
    p = sc.params
    it = iter(outcomes)
    v = h = flown = 0.0
    for j, leg in zip(points[1:], legs):
        if not math.isfinite(leg):
            return False, flown
        v, h, flown = v + leg, h + leg, flown + leg
        kind = Kind(int(sc.kind[j]))
        v_lim, h_lim = p.limits_m(kind)
        if not (v <= v_lim and h <= h_lim):
            return False, flown
        ok = next(it) if can_fail_at(sc, j) else True
        if kind == Kind.V:
            v = 0.0 if ok else min(v, p.residual_m)
        elif kind == Kind.H:
            h = 0.0 if ok else min(h, p.residual_m)
    return True, flown


def _enumerate(sc: Scenario, policy: Policy):
    """Reference: sum over outcome bit-vectors of length K (the deepest path's branch count);
    bits a path does not use sum out."""
    paths = list(_paths(policy))
    depth = max(len(outs) for _, outs in paths)
    p = sc.params.p_success
    prob = e_arr = e_flown = 0.0
    for bits in itertools.product((True, False), repeat=depth):
        w = math.prod(p if b else 1.0 - p for b in bits)
        node, pts, outs = policy, [policy.points[0]], []
        while True:
            pts += node.points[1:]
            if node.leaf:
                break
            ok = bits[len(outs)]
            outs.append(ok)
            node = node.on_success if ok else node.on_failure
        arrived, flown = _fly_reference(sc, pts, outs)
        prob += w * arrived
        e_arr += w * flown * arrived
        e_flown += w * flown
    lengths = [sum(leg.length for leg in flown_route_legs(sc, tuple(pts))) for pts, _ in paths]
    corr = [len(pts) - 2 for pts, _ in paths]
    return prob, e_arr, e_flown, max(lengths), max(corr)


@pytest.mark.parametrize("radius", [0.0, 300.0])
def test_evaluate_matches_enumeration(radius: float) -> None:
    rng = np.random.default_rng(7)
    fractional = arrived = 0
    for seed in range(100):
        sc = contingency_scenario(seed, radius, lenient=True)
        pol = random_policy(sc, rng)
        val = evaluate(sc, pol)
        prob, e_arr, e_flown, longest, corr = _enumerate(sc, pol)
        assert val.probability == pytest.approx(prob, abs=1e-12)
        assert val.expected_flown == pytest.approx(e_flown, rel=1e-12)
        assert val.length == pytest.approx(longest, rel=1e-12)
        assert val.corrections == corr
        if prob > 0:
            arrived += 1
            assert val.expected_length_arrived == pytest.approx(e_arr / prob, rel=1e-12)
        else:
            assert math.isnan(val.expected_length_arrived)
        fractional += 0.0 < prob < 1.0
    # The comparison saw arriving policies and uncertain ones, not only lost or certain ones.
    assert arrived >= 5
    assert fractional >= 5


def test_evaluate_matches_monte_carlo() -> None:
    rng = np.random.default_rng(3)
    draws = 20_000
    tested = 0
    for seed in range(200):
        sc = contingency_scenario(seed, lenient=True)
        pol = random_policy(sc, rng)
        val = evaluate(sc, pol)
        if not 0.05 < val.probability < 0.95 or pol.leaf:
            continue
        mc = np.random.default_rng(seed)
        p = sc.params.p_success
        hits = 0
        flown = np.empty(draws)
        cache: dict = {}
        for d in range(draws):
            node, pts, outs = pol, [pol.points[0]], []
            while True:
                pts += node.points[1:]
                if node.leaf:
                    break
                ok = bool(mc.random() < p)
                outs.append(ok)
                node = node.on_success if ok else node.on_failure
            key = (tuple(pts), tuple(outs))
            if key not in cache:
                cache[key] = _fly_reference(sc, pts, outs)
            a, f = cache[key]
            hits += a
            flown[d] = f
        sigma = math.sqrt(val.probability * (1 - val.probability) / draws)
        assert abs(hits / draws - val.probability) <= 4 * sigma
        sd = flown.std() / math.sqrt(draws)
        assert abs(flown.mean() - val.expected_flown) <= 4 * sd + 1e-9
        tested += 1
        if tested == 4:
            break
    assert tested == 4


@pytest.mark.parametrize("radius", [0.0, 300.0])
def test_from_route_probability_is_the_routes(radius: float) -> None:
    rng = np.random.default_rng(11)
    for seed in range(40):
        sc = contingency_scenario(seed, radius)
        corr = [j for j in range(sc.n) if int(sc.kind[j]) in (Kind.V, Kind.H)]
        k = int(rng.integers(0, len(corr) + 1))
        points = (sc.start, *[int(j) for j in rng.permutation(corr)[:k]], sc.end)
        route = flown_route(sc, points)
        legs = [s.leg for s in route.stops[1:]]
        expected = success_probability(sc, points, legs).probability
        val = evaluate(sc, Policy.from_route(sc, route))
        assert val.probability == pytest.approx(expected, abs=1e-12)
        assert val.length == pytest.approx(route.length, rel=1e-12)
        assert val.corrections == route.corrections


@pytest.mark.parametrize("radius", [0.0, 300.0])
def test_replan_never_worse(radius: float) -> None:
    rng = np.random.default_rng(5)
    better = 0
    for seed in range(60):
        sc = contingency_scenario(seed, radius, n_max=6)
        corr = [j for j in range(sc.n) if int(sc.kind[j]) in (Kind.V, Kind.H)]
        k = int(rng.integers(0, len(corr) + 1))
        points = (sc.start, *[int(j) for j in rng.permutation(corr)[:k]], sc.end)
        route = flown_route(sc, points)
        base = evaluate(sc, Policy.from_route(sc, route))
        brute = replan_on_failure(sc, route, continuation=brute_continuation(sc))
        replanned = evaluate(sc, brute.policy)
        assert replanned.probability >= base.probability - 1e-12
        better += replanned.probability > base.probability + 1e-9
        # The planner's continuations (the most reliable from each state) are as good as
        # brute force's: the same probability and worst-case length.
        searched = replan_on_failure(sc, route, continuation=search_continuation(sc))
        assert searched.plans == brute.plans
        got = evaluate(sc, searched.policy)
        assert got.probability == pytest.approx(replanned.probability, abs=1e-9), seed
        assert got.length == pytest.approx(replanned.length, rel=1e-9), seed
        # Two levels: the branches replanned again are never worse.
        deeper = evaluate(sc, replan_on_failure(sc, route, levels=2).policy)
        assert deeper.probability >= got.probability - 1e-12
    if radius == 0.0:
        assert better >= 1  # (seen: 4 of 60 straight-leg cases improve)


def _line_scenario() -> Scenario:
    """A, H1, U (unreliable V), W (reliable V), B on a line. The route A H1 U B arrives only if
    U's fix takes; after a failure, going on to W resets v and arrives for sure."""
    xs = [0.0, 9000.0, 10000.0, 10500.0, 20000.0]
    kinds = [Kind.A, Kind.H, Kind.V, Kind.V, Kind.B]
    params = Parameters(20, 20, 20, 20, 11, 0.001, turn_radius=0.0, p_success=0.8,
                        fail_residual=5.0)  # fmt: skip
    return Scenario(
        ids=("A", "H1", "U", "W", "B"),
        xyz=np.array([[x, 0.0, 0.0] for x in xs]),
        kind=np.array(kinds, dtype=np.uint8),
        unreliable=np.array([False, False, True, False, False]),
        params=params,
        name="line",
    )


def test_replan_strictly_better_on_constructed_case() -> None:
    sc = _line_scenario()
    route = (0, 1, 2, 4)
    base = evaluate(sc, Policy.from_route(sc, route))
    assert base.probability == pytest.approx(0.8)
    pol = replan_on_failure(sc, route).policy
    assert pol.on_failure is not None and pol.on_failure.points == (2, 3, 4)
    assert pol.on_success is not None and pol.on_success.points == (2, 4)
    val = evaluate(sc, pol)
    assert val.probability == pytest.approx(1.0)
    assert val.length == pytest.approx(20000.0)
    assert val.corrections == 3
    assert val.expected_flown == pytest.approx(20000.0)


def test_revisiting_policy_raises() -> None:
    sc = _line_scenario()
    # The failure branch goes back to H1, already flown.
    bad = Policy((0, 1, 2), Policy((2, 4)), Policy((2, 1, 3, 4)))
    with pytest.raises(GcsPlannerError, match="revisits point H1"):
        evaluate(sc, bad)
    with pytest.raises(GcsPlannerError, match="lacks its on_failure"):
        evaluate(sc, Policy((0, 1, 2), Policy((2, 4))))
    with pytest.raises(GcsPlannerError, match="neither B nor an unreliable"):
        evaluate(sc, Policy((0, 1)))


def test_replan_refuses_large_scenarios() -> None:
    sc = random_scenario(13, 1)
    with pytest.raises(GcsPlannerError, match="stops at 12 correction points"):
        replan_on_failure(sc, (sc.start, sc.end), continuation=brute_continuation(sc))
