"""A design wind of a stated direction (issue 32; docs/model.md, "Flight in the real world"):
each leg climbs and descends within the limits of the fastest ground speed along its own track,
atan(rate / Vg_max), instead of those from any direction, atan(rate / (V + W)); a helix flies
every heading and keeps the latter; the turning radius stays one from any direction.

What is held here: the factor by which a leg may be steeper equals the fastest ground speed
found by sampling the leg's headings; numpy and compiled legs and the one-leg geometry agree
leg by leg; every heading-free bound stays below every leg, whatever its heading; every leg,
re-flown as a polyline in the stated wind, needs no more than the climb and sink rates; the
fronts equal enumeration on random scenarios and differ from those of the any-direction rule in
a share of the sample; the compiled search flies them as the Python one.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from support import enumeration
from support.compiled_search import assert_compiled_flies_as_python, legs_modes
from support.enumeration import TWO, assert_plans_enumeration, enumerate_fronts
from support.flown_route_memo import remember_flown_routes
from support.scenarios import probed_scenario, tall_scenario

from gcs_planner.aircraft.profile import DerivedEnvelope
from gcs_planner.geometry.airplane import LegEnvelope, track_factor
from gcs_planner.geometry.legs import AirplaneLegs, leg_envelope


@pytest.fixture(scope="module", autouse=True)
def routes_flown_once():
    """The enumerations below fly every simple route of each scenario: each leg once for the
    routes that share the partial route before it (support/prefix_flight.py)."""
    yield from remember_flown_routes(enumeration)


def along_track(scenario, eas: float, bank: float, climb: float, sink: float, wind: float,
                wind_from: float | None, along: bool = True,
                per_leg: tuple[str, ...] = ()):  # fmt: skip
    """``scenario`` planning with the envelope derived from these terms in a design wind of
    ``wind`` m/s from ``wind_from`` deg, as ``plan --wind W@DIR`` derives it: each leg's angles
    along its own track where ``along``, else from any direction."""
    base = scenario.origin.alt if scenario.origin else 0.0
    env = DerivedEnvelope(
        eas, bank, climb, sink, wind, wind_from, float(scenario.xyz[:, 2].max()) + base,
        "ardupilot", low_altitude=float(scenario.xyz[:, 2].min()) + base, per_leg=per_leg,
        along_track=along,
    )  # fmt: skip
    out = scenario.with_params(
        turn_radius=env.turn_radius, max_climb_angle=env.climb_angle,
        max_descent_angle=env.descent_angle,
    )  # fmt: skip
    return out.with_vehicle(envelope=env, cruise_airspeed=eas, radius_source="derived")


def _ground_speed(track: np.ndarray, v: float, wind: np.ndarray) -> np.ndarray:
    along = track @ wind
    cross = track[:, 0] * wind[1] - track[:, 1] * wind[0]
    return along + np.sqrt(v * v - cross * cross)


def _envelope(rng: np.random.Generator, per_leg: bool) -> LegEnvelope:
    return LegEnvelope(
        eas=25.0, wind=float(rng.uniform(2, 10)), base_altitude=float(rng.uniform(0, 2000)),
        lowest=0.0, radius=300.0, climb_deg=10.0, descent_deg=10.0,
        tan_bank=math.tan(math.radians(25.0)) if per_leg else 0.0,
        climb_rate=float(rng.uniform(2, 6)), sink_rate=float(rng.uniform(2, 6)),
        angles_at=None if per_leg else 8000.0, wind_from=float(rng.uniform(0, 360)),
    )  # fmt: skip


@pytest.mark.parametrize("seed", range(3))
def test_the_factor_is_the_fastest_ground_speed_over_the_arc(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m = 400
    a = rng.uniform(0, 2 * np.pi, m)
    u = np.column_stack([np.cos(a), np.sin(a)])
    side = rng.choice([-1.0, 1.0], m)
    n = side[:, None] * np.column_stack([-u[:, 1], u[:, 0]])
    phi = np.where(rng.random(m) < 0.2, 0.0, rng.uniform(0, 2 * np.pi, m))
    v = rng.uniform(15, 40, m)
    b = rng.uniform(0, 2 * np.pi)
    wind = 8.0 * np.array([np.cos(b), np.sin(b)])
    got = track_factor(u, n, phi, v, wind)
    w = float(np.hypot(*wind))
    for i in range(m):
        t = np.linspace(0, phi[i], 4001)
        tracks = np.cos(t)[:, None] * u[i] + np.sin(t)[:, None] * n[i]
        fastest = _ground_speed(tracks, v[i], wind).max()
        # sampling finds at most the fastest, and within (step)^2 of it near downwind
        assert fastest <= (v[i] + w) / got[i] * (1 + 1e-12) + 1e-9
        assert (v[i] + w) / got[i] == pytest.approx(fastest, rel=1e-6)
    assert np.all(got >= 1.0) and np.any(got > 1.3)


@pytest.mark.parametrize("seed", range(6))
def test_numpy_compiled_and_one_leg_agree_and_bounds_hold(seed: int) -> None:
    rng = np.random.default_rng(900 + seed)
    env = _envelope(rng, per_leg=bool(seed % 2))
    run_in, run_out = (0.0, 0.0) if seed % 3 == 0 else rng.uniform(50, 400, 2)
    model = AirplaneLegs(300.0, 10.0, 10.0, run_in, run_out, envelope=env)
    starts = [np.array([0.0, 0.0, rng.uniform(0, 6000)]) for _ in range(4)]
    ends = np.column_stack([rng.uniform(-6000, 6000, (300, 2)), rng.uniform(0, 8000, 300)])
    steeper = helices = 0
    for start in starts:
        heading = np.array([*rng.normal(size=2), 0.0])
        lengths, heads = model.lengths(start, heading, ends)
        fast, fast_heads = model.compiled_lengths(start, heading, ends)
        flown = np.flatnonzero(np.isfinite(lengths))
        assert np.array_equal(np.isinf(fast), np.isinf(lengths))
        np.testing.assert_allclose(fast[flown], lengths[flown], rtol=1e-12)
        np.testing.assert_allclose(fast_heads[flown], heads[flown], atol=1e-12)
        # the heading-free bounds, one leg at a time and by blocks, below every leg
        bounds = model.lower_bounds(start, ends)
        assert np.all(bounds[flown] <= lengths[flown] * (1 + 1e-12))
        arcs = model.arc_bounds(np.repeat(start[None, :], len(ends), 0), ends)
        np.testing.assert_allclose(arcs, bounds, rtol=1e-12)
        free, _ = model.lengths(start, None, ends)
        assert np.all(bounds <= free * (1 + 1e-12))
        walk = model.walk_bounds(start, ends)
        assert np.all(walk <= bounds * (1 + 1e-12))
        # against the same legs from any direction: never longer, shorter on steep legs
        anywhere = replace(model, envelope=replace(env, wind_from=None))
        plain, _ = anywhere.lengths(start, heading, ends)
        assert np.all(lengths[flown] <= plain[flown] * (1 + 1e-12))
        steeper += int(np.sum(lengths[flown] < plain[flown] * (1 - 1e-9)))
        for i in flown[:40]:
            leg = model.leg(start, heading, ends[i])
            assert leg.length == pytest.approx(lengths[i], rel=1e-12)
            limit = leg.climb_limit_deg if leg.dz > 0 else leg.descent_limit_deg
            assert abs(leg.path_angle) <= limit + 1e-9
            helices += leg.helix_turns > 0
    assert steeper > 0 and helices > 0


def test_the_least_horizontal_path_is_the_v_shaped_tracks_minimum() -> None:
    """``least_horizontal`` against brute force: a track flown at the two headings b either
    side of downwind, whose chord is at a <= b off downwind, is h cos a / cos b long and may
    climb as steeply as its faster heading allows (``track_factor`` of each heading, the leg
    rule itself); the least over a fine grid of b of max(its length, need / factor) is what
    the bound claims, and is never below it."""
    rng = np.random.default_rng(11)
    env = replace(_envelope(rng, per_leg=False), wind=9.0, wind_from=30.0)
    m = 300
    downwind = env.wind_vector / env.wind
    off = rng.uniform(-math.pi, math.pi, m)
    dw = math.atan2(downwind[1], downwind[0])
    h = rng.uniform(500, 8000, m)
    w = np.column_stack([h * np.cos(dw + off), h * np.sin(dw + off), np.zeros(m)])
    v = rng.uniform(20, 35, m)
    need = h * rng.uniform(0.5, 1.6, m)
    got = env.least_horizontal(w, v, need)
    bs = np.linspace(0.0, math.pi / 2, 20001)[:-1]
    zero = np.zeros(len(bs))
    for i in range(m):
        a = abs(off[i])
        grid = np.concatenate([[a], bs[bs > a]]) if a < math.pi / 2 else np.array([a])
        tracks = np.column_stack([np.cos(dw + grid), np.sin(dw + grid)])
        f = track_factor(tracks, tracks, zero[: len(grid)], np.full(len(grid), v[i]),
                         env.wind_vector)  # fmt: skip
        length = h[i] * math.cos(a) / np.cos(grid) if a < math.pi / 2 else np.array([h[i]])
        brute = float(np.min(np.maximum(length, need[i] / f)))
        assert got[i] <= brute * (1 + 1e-12), i
        assert got[i] >= brute * (1 - 2e-3), (i, got[i], brute)
    # the slowest ground speed any track between the points can have (the chord's, or the
    # crosswind's where the chord is downwind of it) bounds every leg too, more loosely
    ground = env.wind * np.cos(off) + np.sqrt(v * v - (env.wind * np.sin(off)) ** 2)
    slowest = np.minimum(ground, np.sqrt(v * v - env.wind**2))
    loose = np.maximum(h, need * slowest / (v + env.wind))
    assert np.all(got >= loose * (1 - 1e-8))
    assert np.mean(got > loose * (1 + 1e-3)) > 0.2


def test_the_bound_stays_below_legs_from_every_heading() -> None:
    """Steep legs with downwind chords, where the bound leaves the chord's own ground speed:
    the bound is below the shortest leg over 180 headings, run-in and run-out included."""
    rng = np.random.default_rng(3)
    for seed in range(4):
        env = replace(_envelope(rng, per_leg=bool(seed % 2)), wind=float(rng.uniform(6, 12)))
        runs = (0.0, 0.0) if seed % 2 == 0 else (150.0, 120.0)
        model = AirplaneLegs(300.0, 10.0, 10.0, *runs, envelope=env)
        start = np.array([0.0, 0.0, rng.uniform(0, 3000)])
        dw = math.atan2(*env.wind_vector[::-1])
        off = dw + rng.uniform(-1.3, 1.3, 200)
        h = rng.uniform(800, 5000, 200)
        dz = h * rng.uniform(0.05, 0.35, 200) * rng.choice([-1.0, 1.0], 200)
        ends = np.column_stack([h * np.cos(off), h * np.sin(off), np.maximum(start[2] + dz, 0)])
        bound = model.lower_bounds(start, ends)
        best = np.full(len(ends), np.inf)
        for k in range(180):
            a = 2 * math.pi * k / 180
            lengths, _ = model.lengths(start, np.array([math.cos(a), math.sin(a), 0.0]), ends)
            best = np.minimum(best, lengths)
        assert np.all(bound <= best * (1 + 1e-12))


# On a straight the track and the slope (a leg's z is linear in its horizontal distance) are
# the same throughout, so every step there asks the same rate: a coarser step on the run-out and
# the tangent measures the same need with fewer points; where the leg turns, every TURN_STEP_M.
TURN_STEP_M = 2.0
STRAIGHT_STEP_M = 100.0


def polyline(leg) -> np.ndarray:  # noqa: ANN001 - a flown AirplaneLeg
    """The leg every TURN_STEP_M on its helix and arc and every STRAIGHT_STEP_M on its run-out
    and tangent, the ends of each part and the helix's end included."""
    ro = leg.run_out
    helix_end = ro + leg.helix_horizontal
    turn_end = helix_end + leg.arc_horizontal
    parts = [(0.0, ro, STRAIGHT_STEP_M), (ro, turn_end, TURN_STEP_M),
             (turn_end, leg.horizontal_length, STRAIGHT_STEP_M)]  # fmt: skip
    marks = [np.array([0.0, helix_end])]
    for lo, hi, step in parts:
        if hi > lo:
            marks.append(np.linspace(lo, hi, max(1, math.ceil((hi - lo) / step)) + 1))
    out = leg.points_at_horizontal(np.unique(np.concatenate(marks)))
    out[-1] = leg.end
    return out


def reflown_rate_excess(leg, *envs: LegEnvelope) -> tuple[float, ...]:
    """The most the leg, re-flown as a polyline (``polyline``: 2 m steps where it turns) in the
    stated wind of each of ``envs``, asks of the climb or sink rate beyond what the aircraft has
    (m/s; <= 0 when it fits), one figure per envelope: on each step the ground speed along its
    own track times the tangent of its flight-path angle. The airspeed is the one the leg's
    limits were taken at (its higher end's, ``LegEnvelope.airspeeds``). The polyline is sampled
    once for all."""
    pts = polyline(leg)
    d = np.diff(pts, axis=0)
    h = np.hypot(d[:, 0], d[:, 1])
    keep = h > 1e-6
    track = d[keep, :2] / h[keep, None]
    excess = []
    for env in envs:
        v = float(env.airspeeds(float(leg.start[2]), np.array([float(leg.end[2])]))[0])
        vg = _ground_speed(track, v, env.wind_vector)
        rate = vg * np.abs(d[keep, 2]) / h[keep]
        limit = env.climb_rate if leg.dz > 0 else env.sink_rate
        excess.append(float(np.max(rate) - limit) if len(rate) else -limit)
    return tuple(excess)


@pytest.mark.parametrize("seed", range(4))
def test_every_leg_reflown_in_the_stated_wind_stays_within_the_rates(seed: int) -> None:
    """The independent check: legs re-flown as polylines, each step's climb at its own ground
    speed. The same legs flown with the wind from the opposite direction need more than the
    aircraft has on some legs: the rule uses the direction, it does not ignore it."""
    rng = np.random.default_rng(70 + seed)
    env = _envelope(rng, per_leg=bool(seed % 2))
    model = AirplaneLegs(300.0, 10.0, 10.0, 0.0, 0.0, envelope=env)
    flipped = replace(env, wind_from=(env.wind_from + 180.0) % 360.0)
    worst = flipped_worst = -math.inf
    for _ in range(6):
        start = np.array([0.0, 0.0, rng.uniform(0, 3000)])
        heading = np.array([*rng.normal(size=2), 0.0])
        ends = np.column_stack([rng.uniform(-3000, 3000, (60, 2)), rng.uniform(0, 4000, 60)])
        lengths, _ = model.lengths(start, heading, ends)
        for i in np.flatnonzero(np.isfinite(lengths)):
            leg = model.leg(start, heading, ends[i])
            excess, flipped_excess = reflown_rate_excess(leg, env, flipped)
            worst = max(worst, excess)
            flipped_worst = max(flipped_worst, flipped_excess)
    assert worst <= 1e-6
    assert flipped_worst > 0.1


def test_the_front_along_the_track_equals_enumeration() -> None:
    """Tall random scenarios, an envelope from an EAS of 20 m/s, a 30 deg roll limit, climb and
    sink rates of 6 to 12 m/s and a design wind of 10 m/s from a drawn direction, half of them
    with the per-leg envelope too: the fronts equal brute force under the same legs and differ
    from the any-direction rule's in a share of the sample. 3 or 4 points each (16 or 65
    routes, not 65 or 326), so more of them: fewer of these arrive at all."""
    nonempty = bitten = 0
    for seed in range(36):
        rng = np.random.default_rng(7_300 + seed)
        climb, sink = rng.uniform(6, 12, 2)
        wind, wind_from = 10.0, float(rng.uniform(0, 360))
        per_leg = ("turn_radius", "max_climb_angle", "max_descent_angle") if seed % 2 else ()
        base = tall_scenario(seed, "airplane", 400.0, True, points=(3, 4))
        terms = (20.0, 30.0, float(climb), float(sink), wind, wind_from)
        scenario = along_track(base, *terms, per_leg=per_leg)
        assert leg_envelope(scenario).directional
        want = assert_plans_enumeration(scenario, f"seed {seed}")
        nonempty += bool(want[TWO])
        anywhere = along_track(base, *terms, along=False, per_leg=per_leg)
        bitten += want != enumerate_fronts(anywhere)
    assert nonempty >= 10
    assert bitten >= 4, "the stated direction must change the front in the sample"


def test_the_compiled_search_flies_along_the_track_as_the_python_one(monkeypatch) -> None:
    modes = legs_modes(monkeypatch)
    for seed in range(6):
        base = probed_scenario(seed, "airplane, climb limits")
        scenario = along_track(base, 40.0, 30.0, 6.0, 6.0, 8.0, 45.0 * seed)
        scenario = scenario.with_params(approach=200.0 * (seed % 3), departure=150.0 * (seed % 3))
        assert_compiled_flies_as_python(scenario, seed)
    assert 2 in modes


def test_a_stated_angle_keeps_the_any_direction_rule() -> None:
    """Angles stated directly (not from the rates) have no airspeed to follow the track with:
    no per-leg envelope, and the plan says the direction is held from any direction."""
    base = tall_scenario(2, "airplane", 400.0, True)
    scenario = along_track(base, 25.0, 30.0, 6.0, 6.0, 5.0, 90.0, along=False)
    assert leg_envelope(scenario) is None
    assert "held from any direction" in scenario.envelope.wind_rule
    along = along_track(base, 25.0, 30.0, 6.0, 6.0, 5.0, 90.0)
    assert "along its own track" in " ".join(along.envelope.describe())
    assert along.envelope.to_dict()["along_track"] is True
