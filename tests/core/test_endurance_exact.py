"""The front within the endurance (core/endurance_front.py) equals enumeration: every simple
route flown with the project's own route evaluation, its flight time in the design wind from
core/flight_time.py, the routes beyond the endurance dropped, the Pareto front of the rest.

Each random scenario is tall (support.scenarios.tall_scenario) and flown in a design wind of a
stated direction nearly as strong as the airspeed, so that the flight time is far from a
multiple of the length; the endurance is drawn between the quickest and the slowest feasible
route, so that it rules some routes out, the front's own among them often enough."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest
from support.enumeration import THREE, TWO, assert_fronts_close, pareto, planned_front
from support.prefix_flight import every_route_flown
from support.scenarios import tall_scenario, windy_envelope

from gcs_planner.core.flight_time import ground_speeds, route_minutes, seconds_to_b
from gcs_planner.core.planner import plan
from gcs_planner.core.probability import success_probability
from gcs_planner.errors import InfeasibleError

MODELS = [("airplane", 0.0), ("airplane", 400.0)]


def windy(seed: int, leg_model: str, radius: float):  # noqa: ANN201 - a Scenario
    """A tall scenario in a design wind of 0.5 to 0.9 of the airspeed from a drawn direction
    (the envelope carries the wind only: no part of it is per leg, so the legs are unchanged).
    4 or 5 correction points: not tall_scenario's 6 for every twelfth seed with R = 0 (1,957
    routes each to fly, most of the flying here)."""
    rng = np.random.default_rng(9_000 + seed)
    scenario = tall_scenario(seed, leg_model, radius, limited=bool(seed % 2), points=(4, 5))
    envelope = windy_envelope(rng, float(scenario.xyz[:, 2].max()))
    return dataclasses.replace(scenario, envelope=envelope)


@functools.cache
def windy_routes(seed: int, leg_model: str, radius: float) -> tuple:
    """``flown_routes(windy(seed, leg_model, radius))``, once per test process: the two tests
    of the front within the endurance below draw the same scenarios."""
    return tuple(flown_routes(windy(seed, leg_model, radius)))


def flown_routes(scenario) -> list[tuple[float, int, float, float]]:  # noqa: ANN001
    """Every feasible simple route as (length, corrections, -probability, minutes), each flown
    by prefix (support/prefix_flight.py: the same Route as ``flown_route``)."""
    out = []
    for points, route in every_route_flown(scenario):
        if not route.feasible:
            continue
        p = success_probability(scenario, points, [s.leg for s in route.stops[1:]]).probability
        out.append(
            (
                round(route.length, 6),
                route.corrections,
                round(-p, 12),
                route_minutes(scenario, route),
            )
        )
    return out


def fronts_within(routes: list[tuple], minutes: float) -> dict:
    """Both fronts (TWO, THREE) of the routes within ``minutes``."""
    kept = [r for r in routes if r[3] <= minutes]
    return {
        TWO: pareto([(r[0], r[1], 0.0) for r in kept]),
        THREE: pareto([(r[0], r[1], r[2]) for r in kept]),
    }


@pytest.mark.parametrize(("leg_model", "radius"), MODELS, ids=["straight", "airplane"])
def test_the_front_within_the_endurance_equals_enumeration(leg_model, radius):
    bitten = infeasible = 0
    seeds = range(24) if radius == 0 else range(12)
    for seed in seeds:
        scenario = windy(seed, leg_model, radius)
        routes = windy_routes(seed, leg_model, radius)
        if not routes:
            continue
        times = sorted(r[3] for r in routes)
        unlimited = fronts_within(routes, math.inf)
        rng = np.random.default_rng(seed)
        # Between the quickest and the median route, and below the quickest (none within).
        for minutes in (float(rng.uniform(times[0], times[len(times) // 2])), 0.999 * times[0]):
            timed = dataclasses.replace(scenario, endurance=minutes)
            want = fronts_within(routes, minutes)
            for objectives in (TWO, THREE):
                got = planned_front(timed, objectives)
                assert_fronts_close(got, want[objectives], f"seed {seed}, {minutes=}")
            bitten += want[TWO] != unlimited[TWO]
            infeasible += not want[TWO]
    assert bitten >= 4, "the endurance must change the front in the sample"
    assert infeasible >= 4


def test_no_route_within_the_endurance_names_it_and_the_least_time():
    scenario = windy(3, "airplane", 0.0)
    least = float(seconds_to_b(scenario)[scenario.start]) / 60.0
    with pytest.raises(InfeasibleError) as err:
        plan(dataclasses.replace(scenario, endurance=0.9 * least))
    text = str(err.value)
    assert f"endurance of {0.9 * least:g} min" in text and "needs at least" in text


def test_the_ground_speed_is_the_airspeed_plus_the_wind_along_the_track():
    """Vg along a track: the heading that holds the track in the wind, solved independently
    (the air velocity V (cos h, sin h) plus the wind lies along the track)."""
    scenario = windy(1, "airplane", 0.0)
    env = scenario.envelope
    rng = np.random.default_rng(5)
    towards = math.radians(env.wind_from + 180.0)
    wind = env.wind * np.array([math.sin(towards), math.cos(towards)])
    for _ in range(20):
        start = np.array([0.0, 0.0, 0.0])
        end = np.array([*rng.uniform(-5000, 5000, 2), 0.0])
        vg = float(ground_speeds(scenario, start, end)[0])
        tas = float(env.eas)  # at sea level
        track = end[:2] / np.linalg.norm(end[:2])
        # Solve |Vg track - wind| = tas for the positive root.
        b = -2.0 * float(track @ wind)
        c = float(wind @ wind) - tas * tas
        root = (-b + math.sqrt(b * b - 4 * c)) / 2.0
        assert vg == pytest.approx(root, rel=1e-9)


def test_a_headwind_as_strong_as_the_airspeed_never_arrives():
    scenario = windy(2, "airplane", 0.0)
    env = dataclasses.replace(scenario.envelope, wind=2.0 * scenario.envelope.eas)
    scenario = dataclasses.replace(scenario, envelope=env, endurance=10_000.0)
    try:
        result = plan(scenario)
    except InfeasibleError as err:
        assert "endurance" in str(err)
    else:  # every leg it flies has ground speed
        assert math.isfinite(route_minutes(scenario, result.route))


def test_a_search_cut_short_keeps_within_the_endurance_and_says_it_is_not_proven():
    """Straight legs (the layered search ignores the label budget): where the front of all
    routes flies beyond the endurance, a search of one label returns routes within it, each
    marked not settled, the plan not optimal."""
    cut = 0
    for seed in range(40):
        scenario = windy(seed, "airplane", 0.0)
        routes = windy_routes(seed, "airplane", 0.0)
        if not routes:
            continue
        for quantile in (0.1, 0.25, 0.5):
            minutes = float(np.quantile([r[3] for r in routes], quantile))
            if fronts_within(routes, minutes)[TWO] == fronts_within(routes, math.inf)[TWO]:
                continue  # the front of all routes is within it: nothing to search
            timed = dataclasses.replace(scenario, endurance=minutes)
            try:
                result = plan(timed, objectives=TWO, max_labels=1, time_limit=None)
            except InfeasibleError as err:
                assert "not proven" in str(err) or "every route needs at least" in str(err)
                cut += "not proven" in str(err)
                continue
            assert all(route_minutes(timed, r) <= minutes + 1e-9 for r in result.routes)
            if not result.optimal:
                assert not any(result.proven()) and "not proven" in result.statement
                cut += 1
    assert cut >= 2
