"""Each leg's envelope from the altitude of its own highest point (issue 32; docs/model.md,
"Flight in the real world"): the aircraft holds an equivalent airspeed, so it flies slower over
the air, turns tighter and climbs steeper low down than at the scenario's highest point.

What is held here: the envelope of a leg is the one at its higher end (largest radius,
shallowest angles) and equals the scenario's derived envelope at the highest point; the numpy
legs, the compiled legs and the one-leg geometry agree leg by leg; the heading-free bounds stay
below every leg; and the planner's fronts (two and three objectives) equal enumeration on tall
random scenarios, where the per-leg envelope changes the front in a good share of the sample
(it bites), with the compiled search flying the same front as the Python one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.compiled_search import assert_compiled_flies_as_python, legs_modes
from support.enumeration import TWO, assert_plans_enumeration, enumerate_fronts
from support.scenarios import probed_scenario, tall_scenario

from gcs_planner.aircraft.profile import DerivedEnvelope
from gcs_planner.geometry.airplane import LegEnvelope
from gcs_planner.geometry.legs import AirplaneLegs, leg_envelope, scenario_leg_model

PER_LEG = ("turn_radius", "max_climb_angle", "max_descent_angle")


def enveloped(scenario, eas: float, bank: float, climb: float, sink: float, wind: float = 0.0,
              per_leg: tuple[str, ...] = PER_LEG):  # fmt: skip
    """``scenario`` planning with the envelope derived from these terms, as ``plan --firmware``
    derives it (vehicle_from.derive_envelope): the figures at the highest point in the
    parameters, each leg's from its own altitude where ``per_leg`` names them."""
    base = scenario.origin.alt if scenario.origin else 0.0
    env = DerivedEnvelope(
        eas, bank, climb, sink, wind, None, float(scenario.xyz[:, 2].max()) + base, "ardupilot",
        low_altitude=float(scenario.xyz[:, 2].min()) + base, per_leg=per_leg,
    )  # fmt: skip
    out = scenario.with_params(
        turn_radius=env.turn_radius, max_climb_angle=env.climb_angle,
        max_descent_angle=env.descent_angle,
    )  # fmt: skip
    return out.with_vehicle(envelope=env, cruise_airspeed=eas, radius_source="derived")


def _envelope(seed: int) -> LegEnvelope:
    rng = np.random.default_rng(seed)
    return LegEnvelope(
        eas=float(rng.uniform(15, 45)),
        wind=float(rng.uniform(0, 12)),
        base_altitude=float(rng.uniform(0, 3000)),
        lowest=0.0,
        radius=1.0,
        climb_deg=10.0,
        descent_deg=10.0,
        tan_bank=math.tan(math.radians(rng.uniform(15, 45))),
        climb_rate=float(rng.uniform(2, 8)),
        sink_rate=float(rng.uniform(2, 8)),
    )


@pytest.mark.parametrize("seed", range(4))
def test_a_leg_takes_the_envelope_of_its_higher_end(seed: int) -> None:
    env = _envelope(seed)
    z = np.sort(np.random.default_rng(seed).uniform(0, 9000, 50))
    r, c, d = env.at(z)
    # constant above the tropopause (11 km), where ISA's density model here stops
    assert np.all(np.diff(r) >= 0) and np.all(np.diff(c) <= 0) and np.all(np.diff(d) <= 0)
    assert r[-1] > r[0] and c[-1] < c[0] and d[-1] < d[0]
    lo, hi = z[:25], z[25:]
    for a, b in zip(lo, hi):
        for start, end in ((a, b), (b, a)):
            got = env.of_legs(start, np.array([end]))
            want = env.at(np.array([b]))
            assert [float(x[0]) for x in got] == [float(x[0]) for x in want]
    # the bounds are at least as permissive as every leg's limits
    br, bc, bd = env.bounds()
    assert br <= r.min() and bc >= c.max() and bd >= d.max()


def test_the_top_of_the_scenario_has_the_derived_envelope() -> None:
    scenario = enveloped(tall_scenario(3, "airplane", 400.0, True), 30.0, 25.0, 5.0, 4.0, 6.0)
    env, p = scenario.envelope, scenario.params
    top = np.array([scenario.xyz[:, 2].max()])
    r, c, d = leg_envelope(scenario).at(top)
    assert r[0] == pytest.approx(p.turn_radius, rel=1e-12)
    assert math.degrees(math.atan(c[0])) == pytest.approx(env.climb_angle, rel=1e-12)
    assert math.degrees(math.atan(d[0])) == pytest.approx(env.descent_angle, rel=1e-12)
    low = leg_envelope(scenario).at(np.array([scenario.xyz[:, 2].min()]))
    assert low[0][0] < 0.8 * p.turn_radius  # 0 to ~6 km: the radius grows by a third and more


def test_stated_parts_stay_one_for_every_leg() -> None:
    """A radius stated directly (``--turn-radius``) is every leg's; the derived angles still
    vary; with nothing derived per leg there is no per-leg envelope (today's legs)."""
    base = tall_scenario(3, "airplane", 400.0, True)
    stated_radius = enveloped(base, 30.0, 25.0, 5.0, 4.0, per_leg=PER_LEG[1:])
    env = leg_envelope(stated_radius)
    r, c, _ = env.at(np.array([0.0, 5000.0]))
    assert r[0] == r[1] == stated_radius.params.turn_radius and c[0] > c[1]
    assert leg_envelope(enveloped(base, 30.0, 25.0, 5.0, 4.0, per_leg=())) is None
    assert scenario_leg_model(enveloped(base, 30.0, 25.0, 5.0, 4.0, per_leg=())).envelope is None


@pytest.mark.parametrize("seed", range(6))
def test_numpy_compiled_and_one_leg_agree_leg_by_leg(seed: int) -> None:
    rng = np.random.default_rng(500 + seed)
    env = LegEnvelope(
        eas=25.0, wind=float(rng.uniform(0, 10)), base_altitude=0.0, lowest=0.0, radius=300.0,
        climb_deg=10.0, descent_deg=10.0, tan_bank=math.tan(math.radians(20.0)),
        climb_rate=float(rng.uniform(2, 6)), sink_rate=float(rng.uniform(2, 6)),
    )  # fmt: skip
    run_in, run_out = (0.0, 0.0) if seed % 2 else rng.uniform(50, 400, 2)
    model = AirplaneLegs(300.0, 10.0, 10.0, run_in, run_out, envelope=env)
    start = np.array([0.0, 0.0, rng.uniform(0, 6000)])
    heading = np.array([*rng.normal(size=2), 0.0])
    ends = np.column_stack([rng.uniform(-6000, 6000, (400, 2)), rng.uniform(0, 8000, 400)])
    lengths, heads = model.lengths(start, heading, ends)
    fast, fast_heads = model.compiled_lengths(start, heading, ends)
    flown = np.flatnonzero(np.isfinite(lengths))
    assert 0 < len(flown) < len(ends) or run_in == 0
    assert np.array_equal(np.isinf(fast), np.isinf(lengths))
    np.testing.assert_allclose(fast[flown], lengths[flown], rtol=1e-12)
    np.testing.assert_allclose(fast_heads[flown], heads[flown], atol=1e-12)
    bounds = model.lower_bounds(start, ends)
    assert np.all(bounds[flown] <= lengths[flown] * (1 + 1e-12))
    helices = 0
    for i in flown[:60]:
        leg = model.leg(start, heading, ends[i])
        r, c, d = env.of_legs(start[2], ends[i : i + 1, 2])
        assert leg.radius == float(r[0])
        assert leg.length == pytest.approx(lengths[i], rel=1e-12)
        limit = leg.climb_limit_deg if leg.dz > 0 else leg.descent_limit_deg
        assert limit == pytest.approx(math.degrees(math.atan(c[0] if leg.dz > 0 else d[0])))
        assert abs(leg.path_angle) <= limit + 1e-9  # within its own limits
        helices += leg.helix_turns > 0
    assert helices > 0  # some legs climb on a helix of their own radius


def test_the_front_with_a_per_leg_envelope_equals_enumeration() -> None:
    """Tall random scenarios (4.5 to 7 km of altitude spread) with an envelope derived from an
    EAS of 25 m/s, a 30 deg roll limit and climb and sink rates of 6 to 12 m/s, half of them in
    5 m/s of wind (from any direction): the
    planner's fronts equal brute force flown under the same legs, and they differ from the
    fronts of the scenario's one (highest point's) envelope in a good share of the sample."""
    nonempty = bitten = 0
    for seed in range(30):
        rng = np.random.default_rng(4_200 + seed)
        climb, sink = rng.uniform(6, 12, 2)
        wind = float(rng.choice([0.0, 5.0]))
        # 3 or 4 points (16 or 65 routes), not 4 or 5 (65 or 326): as many draws, each a fifth
        # of the enumeration, and the per-leg envelope still changes 7 fronts of 30.
        base = tall_scenario(seed, "airplane", 400.0, True, points=(3, 4))
        scenario = enveloped(base, 25.0, 30.0, float(climb), float(sink), wind)
        assert scenario_leg_model(scenario).envelope is not None
        want = assert_plans_enumeration(scenario, f"seed {seed}")
        nonempty += bool(want[TWO])
        one = enveloped(base, 25.0, 30.0, float(climb), float(sink), wind, per_leg=())
        bitten += want != enumerate_fronts(one)
    assert nonempty >= 8
    assert bitten >= 6, "the per-leg envelope must change the front in the sample"


def test_the_compiled_search_flies_per_leg_envelopes_as_the_python_one(monkeypatch) -> None:
    modes = legs_modes(monkeypatch)
    for seed in range(6):
        base = probed_scenario(seed, "airplane, climb limits")
        scenario = enveloped(base, 40.0, 30.0, 6.0, 6.0, 3.0 * (seed % 2))
        scenario = scenario.with_params(approach=200.0 * (seed % 3), departure=150.0 * (seed % 3))
        assert_compiled_flies_as_python(scenario, seed)
    assert 2 in modes  # airplane legs flown by the kernel


def test_walk_bounds_stay_below_every_two_leg_walk() -> None:
    """The direct bound to B (the reach graph's ``to_end``) holds for walks through any point,
    low or high: below the sum of the two legs' own bounds. A leg's own bound is not that: a
    walk through a low point may climb more steeply than the straight leg may, and the sample
    has such walks."""
    beaten = 0
    for seed in range(6):
        base = tall_scenario(seed, "airplane", 400.0, True)
        scenario = enveloped(base, 25.0, 30.0, 8.0, 8.0, 5.0)
        model = scenario_leg_model(scenario)
        xyz = scenario.xyz
        b = np.repeat(xyz[scenario.end][None, :], len(xyz), 0)
        direct = model.walk_bounds(np.zeros(3), b - xyz)
        own = model.arc_bounds(xyz, b)
        rest = model.arc_bounds(xyz, b)
        for p in range(len(xyz)):
            walks = model.arc_bounds(np.repeat(xyz[p : p + 1], len(xyz), 0), xyz) + rest
            assert np.all(direct[p] <= walks * (1 + 1e-12)), (seed, p)
            beaten += bool(np.any(own[p] > walks * (1 + 1e-9)))
    assert beaten > 0


@pytest.mark.parametrize(("firmware", "varies"), [
    ("ardupilot", PER_LEG), ("px4", ("turn_radius",))])  # fmt: skip
def test_what_varies_per_leg_under_each_autopilot(firmware, varies, dataset_paths) -> None:
    """Only with --per-leg-envelope. ArduPlane counts a helix's turns: its legs take all three
    figures from their own highest point. PX4 leaves a helix on reaching the altitude, on its
    last turn's exit course: its legs keep the highest point's climb and descent angles (the
    dry run of a plan at each leg's own angles lost flights by a lap more) and take the radius
    per leg."""
    from support.envelope import scenario_in_wind

    assert scenario_in_wind(dataset_paths[1], 1, firmware, "5").envelope.per_leg == ()  # asked only
    scenario = scenario_in_wind(dataset_paths[1], 1, firmware, "5", per_leg=True)
    assert scenario.envelope.per_leg == varies
    env = leg_envelope(scenario)
    r, c, d = env.at(np.array([0.0, float(scenario.xyz[:, 2].max())]))
    assert r[0] < r[1]
    assert (c[0] > c[1]) == (firmware == "ardupilot") and (d[0] > d[1]) == (c[0] > c[1])
