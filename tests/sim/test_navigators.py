"""Each autopilot's own rules, one at a time, on small missions (sim/navigators/): PX4 accepts a
fixed-wing waypoint at npfg's switch distance and ramps its altitude to NAV_LOITER_RAD before
it, ArduPlane scales its loiters to the altitude, both climb and sink at their TECS rates, and
the aircraft flies at its true airspeed through the ISA atmosphere."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gcs_planner.sim.atmosphere import eas2tas
from gcs_planner.sim.guidance import AutopilotParams, fly
from support.flights import FRAME, PROFILE, mission

from gcs_planner.aircraft.autopilot import (
    ARDUPLANE,
    MAV_CMD_NAV_LOITER_TURNS,
    PX4,
    autopilot_for,
)


def reached(f, seq):
    return [e for e in f.events if e.kind == "reached" and e.seq == seq][0]


def test_isa_eas2tas():
    assert eas2tas(0.0) == pytest.approx(1.0)
    assert eas2tas(5000.0) == pytest.approx(1.2897, abs=1e-3)  # ISA: rho/rho0 = 0.6012


def test_px4_accepts_a_fixed_wing_waypoint_at_the_npfg_switch_distance():
    """NAV_ACC_RAD 1 m, as the dry run sets it, does not make PX4 fly up to the waypoint: it
    switches at max(NAV_ACC_RAD, NPFG_SW_DST_MLT * NPFG_PERIOD * NPFG_DAMPING * ground speed)."""
    items = mission((16, (0, 0, 0)), (16, (4000, 0, 0)), (16, (4000, 4000, 0)))
    f = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, flavour=PX4.firmware,
            params=AutopilotParams(PX4.firmware, acceptance_radius=1.0))  # fmt: skip
    e = reached(f, 1)
    x, y, _ = f.xyz[e.sample]
    vg = f.ground_speed[e.sample - 1]
    switch = 0.32 * 10.0 * 0.7 * vg
    assert switch == pytest.approx(56.0, abs=0.5)  # 25 m/s at sea level
    assert math.hypot(4000.0 - x, y) == pytest.approx(switch, abs=vg * 0.5 + 0.5)
    # ArduPlane with param2 = 1 flies up to the finish line.
    ardu = mission((16, (0, 0, 0), {"param2": 1}), (16, (4000, 0, 0), {"param2": 1}),
                   (16, (4000, 4000, 0), {"param2": 1}))  # fmt: skip
    g = fly(ardu, FRAME, (0.0, 0.0, 0.0), PROFILE, flavour=ARDUPLANE.firmware)
    x, y, _ = g.xyz[reached(g, 1).sample]
    assert math.hypot(4000.0 - x, y) < 1.5


@pytest.mark.parametrize("compiled", [False, True], ids=["python", "compiled"])
def test_px4_passes_an_early_accepted_waypoint_at_its_altitude(compiled):
    """PX4 accepts the waypoint at (4000, 0) about 56 m early, then the leg to (8000, 0) climbs
    600 m: its altitude setpoint holds the waypoint's altitude until abeam of it (the altitude
    first-order hold), so the aircraft passes it level, not already climbing."""
    items = mission((16, (0, 0, 1000)), (16, (4000, 0, 1000)), (16, (8000, 0, 1600)))
    f = fly(items, FRAME, (0.0, 0.0, 1000.0), PROFILE, flavour=PX4.firmware,
            params=AutopilotParams(PX4.firmware, acceptance_radius=1.0),
            compiled=compiled)  # fmt: skip
    x, _, _ = f.xyz[reached(f, 1).sample]
    assert x < 4000.0 - 40.0  # accepted early
    at = int(np.argmin(np.abs(f.xyz[:, 0] - 4000.0)))
    assert f.xyz[at, 2] == pytest.approx(1000.0, abs=0.5)
    assert f.xyz[-1, 2] > 1500.0  # and it does climb afterwards


def test_px4_altitude_ramp_ends_nav_loiter_rad_before_the_waypoint():
    items = mission((16, (0, 0, 0)), (16, (4000, 0, 100)), (16, (8000, 0, 100)))
    ap = AutopilotParams(PX4.firmware, acceptance_radius=1.0, loiter_radius=400.0)
    f = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, flavour=PX4.firmware, params=ap)
    at = int(np.argmin(np.abs(f.xyz[:, 0] - 3700.0)))  # 300 m before: past the ramp's end
    assert f.xyz[at, 2] == pytest.approx(100.0, abs=3.0)
    mid = int(np.argmin(np.abs(f.xyz[:, 0] - 1800.0)))  # half way along the 3600 m ramp
    assert f.xyz[mid, 2] == pytest.approx(50.0, abs=3.0)


@pytest.mark.parametrize("flavour", [ARDUPLANE.firmware, PX4.firmware])
def test_climb_and_sink_at_the_autopilots_tecs_rates(flavour):
    """ArduPlane TECS_CLMB_MAX = TECS_SINK_MAX = 5 m/s; PX4 in missions FW_T_CLMB_R_SP = 3 and
    FW_T_SINK_R_SP = 2 m/s: whatever angle the planner assumed (15 degrees: 6.5 m/s)."""
    items = mission((16, (0, 0, 1000), {"param2": 1}), (16, (3000, 0, 1600), {"param2": 1}),
                    (16, (6000, 0, 1000), {"param2": 1}), (16, (12000, 0, 1000)))  # fmt: skip
    f = fly(items, FRAME, (0.0, 0.0, 1000.0), PROFILE, flavour=flavour,
            params=AutopilotParams(flavour, acceptance_radius=1.0))  # fmt: skip
    climb, sink = {ARDUPLANE.firmware: (5.0, 5.0), PX4.firmware: (3.0, 2.0)}[flavour]
    assert f.climb.max() == pytest.approx(climb)
    assert f.climb.min() == pytest.approx(-sink)


def test_vehicle_parameters_override_the_shipped_defaults():
    vehicle = {"FW_T_CLMB_R_SP": 4.0, "FW_T_CLMB_MAX": 3.5}
    ap = AutopilotParams.from_parameters(PX4.firmware, vehicle)
    assert ap.climb_rate == 3.5 and ap.sink_rate == PX4.defaults["FW_T_SINK_R_SP"]
    assert ap.bank_limit == 50.0
    ap = AutopilotParams.from_parameters(ARDUPLANE.firmware, {"ROLL_LIMIT_DEG": float("nan")})
    assert ap.bank_limit == 45.0 and ap.climb_rate == 5.0


@pytest.mark.parametrize("altitude", [0.0, 5000.0])
def test_arduplane_scales_its_loiter_radius_with_altitude(altitude):
    """AP_L1_Control::loiter_radius with NAVL1_LIM_BANK = 0: radius * EAS2TAS^2, so a 200 m
    helix at 5 km is flown on ~333 m; PX4 flies the radius as given."""

    def ring(flavour):
        items = mission((16, (0, 0, altitude), {"param2": 1}),
                        (18, (3000, 0, altitude), {"param1": 2, "param3": 200}),
                        (16, (8000, 0, altitude), {"param2": 1}))  # fmt: skip
        f = fly(items, FRAME, (0.0, 0.0, altitude), PROFILE, flavour=flavour)
        # ArduPlane flies LOITER_TURNS (its helix); PX4 skips it.
        turns = autopilot_for(flavour).helix_command == MAV_CMD_NAV_LOITER_TURNS
        during = (f.current == 1) if turns else None
        return f, during

    f, during = ring(ARDUPLANE.firmware)
    r = np.linalg.norm(f.xyz[during, :2] - np.array([3000.0, 0.0]), axis=1)
    r = r[r < 600.0]  # on the circle, not on the way to it
    assert np.median(r) == pytest.approx(200.0 * eas2tas(altitude) ** 2, rel=0.03)
    if altitude > 0:
        assert np.median(r) > 320.0


def test_px4_leaves_a_loiter_within_5_degrees_of_the_exit_course():
    items = mission((16, (0, 0, 1000)),
                    (31, (3000, 0, 1300), {"param1": 1, "param2": -250, "param4": 1}),
                    (16, (3000, 6000, 1300)))  # fmt: skip
    f = fly(items, FRAME, (0.0, 0.0, 1000.0), PROFILE, flavour=PX4.firmware,
            params=AutopilotParams(PX4.firmware, acceptance_radius=1.0))  # fmt: skip
    left = reached(f, 1).sample
    bearing = math.atan2(6000.0 - f.xyz[left, 1], 3000.0 - f.xyz[left, 0])
    error = abs((f.course[left] - bearing + math.pi) % (2 * math.pi) - math.pi)
    assert error <= math.radians(5.0)
