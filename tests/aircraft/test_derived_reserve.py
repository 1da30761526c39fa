"""The flight reserve derived from what it must cover (turn entry, gusts) when the envelope is
derived from the autopilot's terms and nobody states a reserve (gcs_planner/aircraft/reserve.py),
its line in the plan's summary and its block in the plan JSON; and the mock vehicle's flights
of the contest routes staying within it."""

from __future__ import annotations

import functools
import json
import math
from dataclasses import replace

import pytest
from support.paths import DATA, MISSIONS
from support.plan_once import plan_each_scenario_once
from support.workbook_once import read_workbooks_once

from benchmarks.reserve import SHIPPED, TABLE2, flown_at, fly, planned
from gcs_planner.aircraft.profile import DRYDEN_SCALE_LENGTH_M, ROLL_RESPONSE_S
from gcs_planner.aircraft.reserve import GUST_MARGIN, MAX_SHARE, DerivedReserve, track_wander
from gcs_planner.cli import main

DS1 = [f"--{k}={v:g}" for k, v in TABLE2[1].items()]
AP = [f"--{k.replace('_', '-')}={v:g}" for k, v in SHIPPED["ardupilot"].items()]


@pytest.fixture(scope="module", autouse=True)
def workbooks_read_once():
    """Each contest workbook read once for the module (support/workbook_once.py)."""
    yield from read_workbooks_once()


def plan_json(capsys, *argv: str) -> dict:
    assert main(["plan", str(DATA / "dataset1.xlsx"), *DS1, *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def plan_text(capsys, *argv: str) -> str:
    assert main(["plan", str(DATA / "dataset1.xlsx"), *DS1, *argv]) == 0
    return capsys.readouterr().out


def basis(**changes) -> DerivedReserve:
    base = DerivedReserve(turn_radius=96.0, tas=20.7, ground_speed=30.7, bank_deg=45.0,
                          autopilot="ardupilot", gust=1.5, stretch=30_000.0, cap=750.0,
                          late=62.0)  # fmt: skip
    return replace(base, **changes)


def test_a_turn_adds_most_as_a_u_turn_and_gusts_by_the_square_of_their_speed() -> None:
    b = basis()
    extras = [b.turn_extra(math.radians(a)) for a in range(0, 181, 5)]
    assert extras[0] == 0.0 and extras == sorted(extras)
    assert extras[-1] == pytest.approx(b.per_turn)
    # A turn entered d late: d straight on, the same arc, and only d cos(theta) gained along the
    # new line: flown against planned at the point abeam on the new line.
    theta, d = math.radians(70), b.late
    assert b.turn_extra(theta) == pytest.approx(d - d * math.cos(theta))
    assert basis(gust=0.0).gust_term == 0.0
    assert basis(gust=3.0).gust_term == pytest.approx(4 * b.gust_term)
    assert b.needed == pytest.approx(b.turns * b.per_turn + b.gust_term)
    assert basis(late=2 * b.late, gust=0.0).needed == pytest.approx(2 * basis(gust=0.0).needed)
    capped = basis(cap=100.0)
    assert capped.capped and capped.metres == 100.0 < capped.needed


@pytest.fixture(scope="module")
def planned_once():
    """The JSON and the text of one plan are printed from the same search
    (support/plan_once.py): the memory of the plans asked for."""
    yield from plan_each_scenario_once()


def test_plan_derives_the_reserve_prints_it_with_its_reason_and_writes_it(
    capsys, planned_once
) -> None:
    d = plan_json(capsys, *AP, "--firmware=ardupilot", "--wind=5", "--gust=1.5")
    r = d["reserve"]
    env = d["vehicle"]["envelope"]
    assert r["source"] == "derived" and r["metres"] == d["parameters"]["reserve"]
    # 2 turns x 2d, d = L1/2 (ArduPlane's L1 distance is its run-in) + the roll-in's lag at
    # the ground speed; gusts wander (sigma/Vg)^2/2 over the longest stretch, 30 km, Vg the
    # TAS at the lowest point into the 5 m/s wind
    d = env["approach_m"] / 2 + ROLL_RESPONSE_S * r["ground_speed"]
    assert r["slowest_ground_speed"] == pytest.approx(env["tas_low"] - 5.0)
    assert env["tas_low"] < env["tas"]
    wander = GUST_MARGIN * track_wander(17.0, 0.75, DRYDEN_SCALE_LENGTH_M / env["tas"])
    assert r["gust_wander"] == pytest.approx(wander)
    want = 4 * d + wander * 0.5 * (1.5 / (env["tas_low"] - 5.0)) ** 2 * 30 / 0.001
    assert r["metres"] == pytest.approx(want)
    assert r["metres"] != 200.0  # not the constant default
    check = r["chosen_route"]
    assert check["covered"] == (check["need_m"] <= r["metres"])
    text = plan_text(capsys, *AP, "--firmware=ardupilot", "--wind=5", "--gust=1.5")
    line = next(x for x in text.splitlines() if x.startswith("flight reserve:"))
    want = f"flight reserve: {r['metres']:,.0f} m, derived for ardupilot: turn entry"
    assert line.startswith(want)
    assert "gusts 1.5 m/s over 30.0 km" in line and line.endswith("--reserve M states it")
    assert len(planned_once) == 1  # the text printed from the plan the JSON wrote


def test_stated_and_contest_reserves_are_unchanged(capsys) -> None:
    stated = plan_json(capsys, *AP, "--wind=5", "--reserve=150")
    assert stated["parameters"]["reserve"] == 150.0 and stated["reserve"]["source"] == "stated"
    assert "derivation" not in stated["reserve"]
    # the envelope stated directly: the constant default, as before
    direct = plan_json(capsys, "--turn-radius=200")
    assert direct["parameters"]["reserve"] == 200.0 and direct["reserve"]["source"] == "default"
    for legs in (["--turn-radius=0"], ["--turn-radius=200", "--leg-model=cs3d"]):
        contest = plan_json(capsys, *legs, "--objectives=length,corrections")
        assert contest["parameters"]["reserve"] == 0.0
        assert contest["reserve"]["source"] == "none"


def test_the_derived_reserve_keeps_the_default_cap() -> None:
    """Limits of a few kilometres: the derived reserve is held to 5 % of the tightest, as the
    constant default is."""
    from types import SimpleNamespace

    from gcs_planner.aircraft.derive import derive_envelope
    from gcs_planner.scenario.readers import load_scenario

    tight = {k: v / 4 for k, v in TABLE2[1].items() if k != "delta"}
    terms = SHIPPED["ardupilot"]
    loaded = load_scenario(DATA / "dataset1.xlsx", {**TABLE2[1], **tight, "turn_radius": 50.0})
    assert loaded.reserve_source == "default"
    s = derive_envelope(SimpleNamespace(autopilot="ardupilot", **terms), loaded, wind_text="10",
                        gust=5.0)  # fmt: skip
    b = s.reserve_basis
    assert s.reserve_source == "derived" and b.capped and b.needed > s.params.reserve
    assert s.params.reserve == pytest.approx(MAX_SHARE * 15 / 4 / 0.001)
    assert s.params.validate() == []


# (workbook, autopilot, design wind, gusts): still air, wind and gusts on both autopilots,
# dataset 2's tighter limits.
FLOWN = [(1, "ardupilot", 0.0, 0.0), (1, "ardupilot", 10.0, 1.5), (1, "px4", 10.0, 1.5),
         (2, "ardupilot", 5.0, 1.5), (2, "ardupilot", 10.0, 1.5)]  # fmt: skip


@pytest.mark.parametrize(("dataset", "firmware", "wind", "gust"), FLOWN)
def test_the_mock_vehicle_flies_no_stretch_longer_than_the_derived_reserve_covers(
    dataset, firmware, wind, gust, monkeypatch
) -> None:
    """The chosen route flown by the mock autopilot (set up as --set-params does) in the design
    wind from two drawn directions: the most it flies beyond the plan between a reset and a
    check of an error stays within the derived reserve, and within the route's own leg-by-leg
    need (its turns, helices and gusts)."""
    import benchmarks.reserve
    from benchmarks.turn_entry import stretches
    from gcs_planner.mission.plan_json import reserve_of
    from gcs_planner.scenario.model import altitude_of

    # Each flight flown once: ``fly`` (the overrun) and ``flown_at`` (stretch by stretch) below
    # both read the flight of the same result, wind and seed.
    flights: dict[tuple, object] = {}
    one_flight = benchmarks.reserve.flight

    def flown_once(result, *case):  # noqa: ANN001, ANN202 - benchmarks.reserve.flight's
        key = (id(result), *case)
        if key not in flights:
            flights[key] = one_flight(result, *case)
        return flights[key]

    monkeypatch.setattr(benchmarks.reserve, "flight", flown_once)
    result = planned(dataset, firmware, wind, gust)
    reserve = result.scenario.params.reserve
    need = reserve_of(result)["chosen_route"]["need_m"]
    flown = [fly(result, firmware, wind, gust, seed) for seed in range(2)]
    assert all(o is not None for o in flown)
    worst = max(flown)
    assert worst > 0  # the flights do fly beyond the plan: the check measures something
    assert worst <= reserve, (worst, reserve)
    assert worst <= need, (worst, need)
    # and stretch by stretch, each within its own need (its turns, helices and gusts)
    basis = result.scenario.reserve_basis
    assert len(flights) == 2
    for seed in range(2):
        met, to_b = flown_at(result, firmware, wind, gust, seed)
        if to_b is not None:
            met[result.route.stops[-1].id] = to_b
        rows = stretches(result.route, met, basis, altitude_of(result.scenario))
        assert rows
        for over, coef, gusts, _ in rows:
            # 1 m: sub-metre differences between a straight flown through its waypoints and
            # the plan's line (0.6 m at most in still air, benchmarks.turn_entry)
            assert over <= basis.late * coef + gusts + 1.0, (seed, over, coef, gusts)
    assert len(flights) == 2  # no flight flown twice


def test_each_autopilot_enters_its_turns_as_late_as_its_guidance() -> None:
    """ArduPlane trails by half its L1 distance (the run-in it settles over) and the roll-in's
    lag at the ground speed, PX4 by half the radius; an autopilot not named by the larger, so
    it holds for either."""
    from gcs_planner.aircraft.autopilot import effective
    from gcs_planner.aircraft.reserve import late_entry

    for radius, speed in ((44.0, 20.7), (96.0, 30.7), (400.0, 30.7)):
        l1 = effective("ardupilot", {}).settle_distance(speed)
        ardupilot = l1 / 2 + ROLL_RESPONSE_S * speed
        assert late_entry("ardupilot", radius, speed)[0] == pytest.approx(ardupilot)
        assert late_entry("px4", radius, speed)[0] == pytest.approx(radius / 2)
        either = late_entry(None, radius, speed)[0]
        assert either == pytest.approx(max(ardupilot, radius / 2))


def _scenario_toml(tmp_path, environment: str) -> str:

    points = MISSIONS / "example" / "points.csv"
    text = (
        f'name = "gusty"\npoints = "{points}"\n[parameters]\nalpha1 = 25\nalpha2 = 15\n'
        "beta1 = 20\nbeta2 = 25\ntheta = 30\ndelta = 0.001\n[vehicle]\ncruise_airspeed = 20\n"
        'max_bank_angle = 40\nmax_climb_rate = 4\nmax_sink_rate = 4\nfirmware = "px4"\n'
        f"[environment]\n{environment}\n"
    )
    path = tmp_path / "gusty.toml"
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_the_scenario_file_states_the_design_gust(tmp_path, capsys) -> None:
    """[environment] gust is the design gust the derived reserve covers; --gust wins; a bad one
    is one line naming the file, line and field."""
    path = _scenario_toml(tmp_path, 'wind = "5"\ngust = 2')
    assert main(["plan", path, "--json"]) == 0
    r = json.loads(capsys.readouterr().out)["reserve"]
    assert r["source"] == "derived" and r["gust"] == 2.0 and r["autopilot"] == "px4"
    assert main(["plan", path, "--json", "--gust", "0"]) == 0
    still = json.loads(capsys.readouterr().out)["reserve"]
    assert still["gust"] == 0.0 and still["metres"] == pytest.approx(r["metres"] - r["gust_term_m"])
    bad = _scenario_toml(tmp_path, "gust = -1")
    assert main(["plan", bad]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gusty.toml" in err[0] and "environment.gust" in err[0]
    assert "Traceback" not in err[0]


def test_a_stretch_needs_its_own_turns_and_one_u_turn_per_helix_and_for_the_start() -> None:
    """A stretch's leg-by-leg need: each turn's d (1 - cos theta), each helix (a loiter joined
    and left where its guidance does) and the start at A (its heading is free) a U-turn."""
    b = basis(gust=0.0)
    assert b.stretch_need([], 0, False, 1000.0) == 0.0
    assert b.stretch_need([], 1, False, 1000.0) == pytest.approx(b.per_turn)
    assert b.stretch_need([], 0, True, 1000.0) == pytest.approx(b.per_turn)
    quarter = math.radians(90)
    assert b.stretch_need([quarter], 1, True, 1000.0) == pytest.approx(
        b.turn_extra(quarter) + 2 * b.per_turn
    )
    gusty = basis()
    assert gusty.stretch_need([], 0, False, 10_000.0) == pytest.approx(gusty.gust_share * 10_000.0)


def _simulated_wander(period: float, damping: float, tau: float, roll: float) -> float:
    """E[y'^2] / sigma^2 of the same loop integrated in time (0.01 s steps over 20,000 s, a
    unit first-order gust drawn exactly per step): an independent check of the integral."""
    import numpy as np

    rng = np.random.default_rng(7)
    dt, n = 0.01, 2_000_000
    w0 = 2 * math.pi / period
    a = math.exp(-dt / tau)
    kick = math.sqrt(1 - a * a) * rng.standard_normal(n)
    v = float(rng.standard_normal())
    return _stepped_loop(kick, v, a, w0, damping, roll, dt) / n


def _stepped_loop(kick, v: float, a: float, w0: float, damping: float, roll: float, dt: float):
    """The sum of the squared cross-track rates over the steps: ``_step_loop`` compiled (two
    million steps of a few multiplications each; the same IEEE arithmetic, no fast-math)."""
    return _compiled_step_loop()(kick, v, a, w0, damping, roll, dt)


@functools.cache
def _compiled_step_loop():  # noqa: ANN202 - a numba dispatcher
    import numba

    return numba.njit(_step_loop)


def _step_loop(kick, v, a, w0, damping, roll, dt):  # noqa: ANN001, ANN202 - numba's
    n = len(kick)
    y = vy_air = acc = 0.0
    total = 0.0
    for k in range(n):  # the loop's few states, stepped as the equations say
        v = v * a + kick[k]
        rate = vy_air + v  # the cross-track rate over the ground: the air's and the gust's
        command = -(w0 * w0 * y + 2 * damping * w0 * rate)
        acc = command if roll <= 0 else acc + (command - acc) * dt / roll
        vy_air += acc * dt
        y += rate * dt
        total += rate * rate
    return total


@pytest.mark.parametrize(("period", "damping", "tau"), [(17.0, 0.75, 30.0), (10.0, 0.7, 20.0)])
def test_the_gusts_wander_is_the_closed_loops_share_of_their_power(period, damping, tau) -> None:
    """track_wander's frequency integral against the loop flown in time, and its limits: a
    gust far faster than the loop passes whole, one far slower is steered out."""
    f = track_wander(period, damping, tau, ROLL_RESPONSE_S)
    assert f == pytest.approx(_simulated_wander(period, damping, tau, ROLL_RESPONSE_S), rel=0.05)
    assert track_wander(period, damping, 0.01, ROLL_RESPONSE_S) > 0.95
    assert track_wander(period, damping, 1e5, ROLL_RESPONSE_S) < 1e-3
    assert track_wander(period, damping, tau, 0.0) < f  # the roll response lets more through
    # a loop the roll response cannot follow does not settle: no finite wander
    assert math.isinf(track_wander(1.0, 0.3, tau, ROLL_RESPONSE_S))


def test_gusts_wander_most_into_a_headwind_at_the_lowest_point() -> None:
    """The share is taken at the slowest ground speed: the lowest point's TAS into the wind."""
    from gcs_planner.aircraft.profile import tas_from_eas

    b = basis(wind=10.0, slowest_tas=15.0, eas=12.0, wander=0.2)
    assert b.slowest_ground_speed == pytest.approx(5.0)
    assert b.gust_share == pytest.approx(0.2 * 0.5 * (1.5 / 5.0) ** 2)
    assert b.gust_share_at(20.7) < b.gust_share  # a faster leg wanders less
    assert basis(wind=10.0, slowest_tas=10.0, eas=12.0).gust_share == math.inf
    # a leg's own: its lowest point's TAS (12 m/s EAS at 5 km) into the wind
    leg = b.leg_gusts(1000.0, 5000.0)
    assert leg == pytest.approx(1000.0 * b.gust_share_at(tas_from_eas(12.0, 5000.0)))
