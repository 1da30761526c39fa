"""The compiled flight (sim/flight_kernel.py) against the Python navigators it is modelled on:
the same missions flown both ways make the same decisions (events, corrections and their
outcomes, missed landmarks, verdict) and the same track, within float reassociation.

Tolerance: the kernel evaluates the navigators' formulas in the same order, but its libm (hypot,
pow) may round the last bit otherwise than CPython's math module; such a bit can flip the choice
of a coarse step on a settled leg (guidance.COARSE_STEPS), so the two tracks may be sampled at
other times. They are compared at equal times (the kernel's track interpolated at the Python
one's samples): measured within 3 mm at the median and 1.4 m at worst (a coarse step's chord
against fine steps), 6 mm at the end of a 230 km helix flight. TRACK_TOLERANCE_M allows 2.5 m,
END_TOLERANCE_M 0.5 m; the decisions (events, corrections and outcomes, misses, verdict) must
be the same.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_helix_flight import DS2, DS2_LIMITS, configured
from test_mission_builder import make_plan, steep_scenario

from gcs_planner.core.planner import plan
from gcs_planner.mission.builder import build_mission
from gcs_planner.plan_json import plan_to_dict
from gcs_planner.scenario.readers import load_scenario
from sim import flight_kernel
from sim.guidance import AutopilotParams
from sim.replay import replay
from sim.wind import WindSpec

TRACK_TOLERANCE_M = 2.5
END_TOLERANCE_M = 0.5
WINDS = {
    "still": WindSpec(),
    "wind": WindSpec(5.0, 250.0),
    "gusts": WindSpec(6.0, None, 1.5),
}


@pytest.fixture
def kernel_steps(monkeypatch) -> list[int]:
    """Counts the steps the kernel flew (so that a test sees it was used)."""
    flown: list[int] = []
    original = flight_kernel.fly_plain

    def counted(*args):
        out = original(*args)
        flown.append(int(out[0]))
        return out

    monkeypatch.setattr(flight_kernel, "fly_plain", counted)
    return flown


def both(items, scenario, flavour, autopilot, wind, runs=0, estimate=True):
    kw = dict(home_at_seq0=flavour == "ardupilot", flavour=flavour, autopilot=autopilot,
              wind=wind, navigate_on_estimate=estimate, runs=runs, seed=3)  # fmt: skip
    return replay(items, scenario, compiled=False, **kw), replay(items, scenario, **kw)


def assert_same_flight(ref, got) -> None:
    assert got.flight.ended == ref.flight.ended
    assert [(e.seq, e.kind) for e in got.flight.events] == [
        (e.seq, e.kind) for e in ref.flight.events
    ]
    assert [(c.id, c.succeeded, c.within_limits) for c in got.run.corrections] == [
        (c.id, c.succeeded, c.within_limits) for c in ref.run.corrections
    ]
    assert [m.id for m in got.missed] == [m.id for m in ref.missed]
    assert (got.arrived, got.run.lost, got.run.flight_lost) == (
        ref.arrived, ref.run.lost, ref.run.flight_lost,
    )  # fmt: skip
    ref_t, got_t = ref.flight.t, got.flight.t
    assert abs(len(got_t) - len(ref_t)) <= 0.01 * len(ref_t)
    assert got_t[-1] == pytest.approx(ref_t[-1], abs=5.0)
    at = np.stack([np.interp(ref_t, got_t, got.flight.xyz[:, k]) for k in range(3)], axis=1)
    assert np.abs(at - ref.flight.xyz).max() <= TRACK_TOLERANCE_M
    assert np.abs(got.flight.xyz[-1] - ref.flight.xyz[-1]).max() <= END_TOLERANCE_M
    for a, b in zip(got.run.corrections, ref.run.corrections, strict=True):
        assert a.distance == pytest.approx(b.distance, abs=TRACK_TOLERANCE_M)
        assert a.miss == pytest.approx(b.miss, abs=TRACK_TOLERANCE_M)
    if ref.monte_carlo is not None:
        assert got.monte_carlo == ref.monte_carlo


@pytest.mark.parametrize("wind", list(WINDS))
@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
@pytest.mark.parametrize("shipped", [False, True], ids=["configured", "shipped"])
def test_helix_missions_fly_the_same_compiled(kernel_steps, flavour, wind, shipped):
    """Helices of 5 to 22 turns (ArduPlane LOITER_TURNS, PX4 LOITER_TO_ALT), set up for the plan
    or with the shipped parameters (PX4 climbing at 3 m/s circles its waypoints for altitude),
    in still air, a steady wind and gusts, on the INS estimate."""
    s = steep_scenario()
    m = build_mission(make_plan(s, routes=([0, 1, 2, 3, 4, 5, 6],), probability=False),
                      firmware=flavour)  # fmt: skip
    ap = AutopilotParams(flavour, loiter_radius=200.0) if shipped else configured(s, flavour)
    ref, got = both(m.items, s, flavour, ap, WINDS[wind])
    assert_same_flight(ref, got)
    assert sum(kernel_steps) > len(got.flight.t) // 3


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_truth_flown_and_monte_carlo_of_flights_are_the_same_compiled(flavour):
    """Flying the truth (the INS replayed after) and a Monte Carlo of flights in gusts: the
    seeded draws are the same, so the summaries are equal."""
    s = steep_scenario()
    m = build_mission(make_plan(s, routes=([0, 1, 2, 3, 4, 5, 6],), probability=False),
                      firmware=flavour)  # fmt: skip
    ap = configured(s, flavour)
    assert_same_flight(*both(m.items, s, flavour, ap, WindSpec(), estimate=False))
    ref, got = both(m.items, s, flavour, ap, WindSpec(4.0, None, 1.0), runs=4)
    assert_same_flight(ref, got)
    assert ref.monte_carlo is not None and ref.monte_carlo.flown


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_straight_leg_plans_fly_the_same_compiled(flavour):
    """R = 0 (turns on the spot): the kernel leaves these steps to Python; the flight is the
    same whichever is asked for."""
    s = steep_scenario((90.0, 90.0)).with_params(turn_radius=0.0)
    m = build_mission(make_plan(s, routes=([0, 1, 2, 3, 4, 5, 6],), probability=False),
                      firmware=flavour)  # fmt: skip
    for wind in (WindSpec(), WindSpec(5.0, 90.0, 1.0)):
        assert_same_flight(*both(m.items, s, flavour, AutopilotParams(flavour), wind))


@pytest.fixture(scope="module")
def ds2_missions(dataset_paths):
    scenario = load_scenario(dataset_paths[2], {**DS2, **DS2_LIMITS})
    p = plan_to_dict(plan(scenario, objectives=("length", "corrections", "probability"),
                          choice="most-reliable"))  # fmt: skip
    return scenario, {f: build_mission(p, firmware=f, acceptance_radius=1) for f in
                      ("ardupilot", "px4")}  # fmt: skip


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_dataset2_lost_flight_is_the_same_compiled(kernel_steps, ds2_missions, flavour):
    """Dataset 2's certain route with the shipped parameters (PX4 at 3 m/s circles for its
    altitudes and misses landmarks; the flights are lost): the same losses, the same misses."""
    scenario, missions = ds2_missions
    ap = AutopilotParams(flavour, acceptance_radius=1.0, loiter_radius=200.0)
    ref, got = both(missions[flavour].items, scenario, flavour, ap, WindSpec(5.0, 270.0, 1.5))
    assert not ref.arrived
    assert_same_flight(ref, got)
    assert sum(kernel_steps) > len(got.flight.t) // 2
