"""The autopilot's ground-speed floor in the flight (sim/aircraft.py ``Envelope.held_tas`` and
its compiled twin in sim/point_mass_kernel.py ``arc_step``): into a headwind that leaves less
ground speed than PX4's FW_GND_SPD_MIN (ArduPlane's MIN_GNDSPD_CM) the aircraft flies faster
through the air by the shortfall, at most at its largest airspeed."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from gcs_planner.sim.aircraft import AircraftState, Envelope, arc_step, step
from gcs_planner.sim.flight_records import S_GS, S_HEADING, S_TAS, STATE_SIZE, aircraft_record
from gcs_planner.sim.guidance import AutopilotParams, fly
from gcs_planner.sim.point_mass_kernel import arc_step as compiled_arc_step
from gcs_planner.sim.point_mass_kernel import max_lateral
from gcs_planner.sim.wind import WindModel
from support.flights import FRAME, PROFILE, mission

from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4

EAST = 0.0  # heading, rad counter-clockwise from east


def envelope(floor: float, most: float = 20.0) -> Envelope:
    return Envelope(15.0, 45.0, 5.0, 5.0, 90.0, floor, most)


@pytest.mark.parametrize(
    ("headwind", "floor", "tas", "ground"),
    [(12.0, 5.0, 17.0, 5.0), (8.0, 5.0, 15.0, 7.0), (18.0, 5.0, 20.0, 2.0), (12.0, 0.0, 15.0, 3.0)],
    ids=["raised", "enough ground speed", "at the largest airspeed", "no floor"],
)
def test_the_floor_raises_the_airspeed_into_a_headwind(headwind, floor, tas, ground):
    s = AircraftState(0.0, 0.0, 0.0, EAST)
    for fly_step in (arc_step, step):
        out = fly_step(s, envelope(floor), 0.0, 0.0, 2.0, (-headwind, 0.0))
        assert out.tas == pytest.approx(tas) and out.ground_speed == pytest.approx(ground)
        assert out.x == pytest.approx(2.0 * ground)
    # The compiled step flies the same.
    state = np.zeros(STATE_SIZE)
    state[S_HEADING] = EAST
    out = np.zeros(STATE_SIZE)
    record = aircraft_record(envelope(floor))
    compiled_arc_step(
        state, record, 0.0, 0.0, 2.0, -headwind, 0.0, 0.0, 1.0, max_lateral(45.0), out
    )
    assert out[S_TAS] == pytest.approx(tas) and out[S_GS] == pytest.approx(ground)


def test_a_crosswind_raises_it_by_the_shortfall_along_the_heading():
    """The floor is on the ground speed along the nose (PX4's body-forward ground speed)."""
    s = AircraftState(0.0, 0.0, 0.0, EAST)
    wind = (-12.0 * math.cos(math.radians(30)), 12.0 * math.sin(math.radians(30)))
    out = arc_step(s, envelope(5.0, 40.0), 0.0, 0.0, 1.0, wind)
    assert out.tas + wind[0] == pytest.approx(5.0)


def test_each_autopilot_serves_its_floor():
    assert AutopilotParams.from_parameters(PX4.firmware, {}).ground_speed_floor == 5.0
    assert AutopilotParams.from_parameters(ARDUPLANE.firmware, {}).ground_speed_floor == 0.0
    ap = AutopilotParams.from_parameters(ARDUPLANE.firmware, {"MIN_GNDSPD_CM": 600.0})
    assert ap.ground_speed_floor == 6.0
    assert (
        AutopilotParams.from_parameters(PX4.firmware, {"FW_GND_SPD_MIN": 0.0}).ground_speed_floor
        == 0.0
    )


@pytest.mark.parametrize("compiled", [False, True], ids=["python", "compiled"])
def test_a_px4_flight_into_a_strong_headwind_keeps_its_floor(compiled):
    """4 km east at 15 m/s EAS near the sea into 13 m/s from the east: about 2 m/s over the
    ground without the floor (over half an hour), 5 m/s with PX4's (under 15 minutes)."""
    items = mission((16, (0, 0, 0), {"param2": 1}), (16, (4000, 0, 0), {"param2": 1}))
    wind = WindModel(13.0, 90.0)
    profile = replace(PROFILE, cruise_airspeed=15.0)
    floors = {}
    for floor in (0.0, 5.0):
        params = AutopilotParams.from_parameters(PX4.firmware, {"FW_GND_SPD_MIN": floor})
        flight = fly(items, FRAME, (0.0, 0.0, 0.0), profile, flavour=PX4.firmware,
                     params=params, wind=wind, compiled=compiled)  # fmt: skip
        assert flight.ended == "mission end", flight.ended
        floors[floor] = flight.duration
    assert floors[0.0] > 1500.0 and floors[5.0] < 900.0
