"""The mock vehicle's parameters as the autopilot has them (issue 26), over real MAVLink on
127.0.0.1: the shipped defaults of its firmware (not the rates the plan assumed), every write
range-checked (a value the flight cannot use is refused, PARAM_VALUE unchanged, with a
STATUSTEXT, and the flight still runs), and the effective parameters the flight reads."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support.flights import line_scenario, waypoint_items

from gcs_planner.aircraft.autopilot import AUTOPILOTS, effective
from gcs_planner.link.connection import Link, mavlink, open_link
from gcs_planner.link.mission_client import MissionClient

WAIT_S = 30.0  # generous: every wait ends on the message it waits for


def wait_for(link: Link, pred: Callable[[Any], bool], timeout: float = WAIT_S) -> Any | None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is not None and pred(msg):
            return msg
    return None


def value_of(name: str) -> Callable[[Any], bool]:
    def pred(m: Any) -> bool:
        if m.get_type() != "PARAM_VALUE":
            return False
        pid = m.param_id.decode() if isinstance(m.param_id, bytes) else m.param_id
        return pid.rstrip("\x00") == name

    return pred


@contextmanager
def vehicle_and_peer(flavour: str, **kw: Any) -> Iterator[tuple[MockVehicle, Link]]:
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, **kw) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            link.send(link.mav.heartbeat_encode(6, 8, 0, 0, 4))
            assert wait_for(link, lambda m: m.get_type() == "HEARTBEAT") is not None
            yield vehicle, link
        finally:
            link.close()


def answer_and_text(link: Link, name: str) -> tuple[Any | None, Any | None]:
    """The PARAM_VALUE for ``name`` and the STATUSTEXT naming it, in whatever order."""
    value = text = None
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline and (value is None or text is None):
        msg = link.recv(0.05)
        if msg is None:
            continue
        if value is None and value_of(name)(msg):
            value = msg
        elif text is None and msg.get_type() == "STATUSTEXT" and name in msg.text:
            text = msg
    return value, text


def read(link: Link, name: str) -> float:
    link.send(link.mav.param_request_read_encode(1, 1, name.encode(), -1))
    msg = wait_for(link, value_of(name))
    assert msg is not None, f"no PARAM_VALUE for {name}"
    return float(msg.param_value)


# The plan assumes 15 deg climbs and descents (6.5 m/s at 25 m/s) and R = 200 m (17.7 deg
# of bank): none of that is the autopilot's. Before issue 26 the mock served exactly these.
PLAN = {"max_climb_angle": 15.0, "max_descent_angle": 15.0, "turn_radius": 200.0}
SHIPPED = [
    ("ardupilot", "TECS_CLMB_MAX", 5.0),  # AP_TECS.cpp var_info CLMB_MAX
    ("ardupilot", "TECS_SINK_MAX", 5.0),  # AP_TECS.cpp var_info SINK_MAX
    ("ardupilot", "ROLL_LIMIT_DEG", 45.0),  # ArduPlane/config.h HEAD_MAX
    ("ardupilot", "NAVL1_LIM_BANK", 0.0),  # AP_L1_Control.cpp var_info LIM_BANK
    ("ardupilot", "WP_RADIUS", 90.0),  # ArduPlane/config.h WP_RADIUS_DEFAULT
    ("px4", "FW_T_CLMB_R_SP", 3.0),  # fw_path_navigation_params.c
    ("px4", "FW_T_SINK_R_SP", 2.0),
    ("px4", "FW_T_CLMB_MAX", 5.0),
    ("px4", "FW_T_SINK_MAX", 5.0),
    ("px4", "FW_R_LIM", 50.0),
    ("px4", "NAV_ACC_RAD", 10.0),  # navigator_params.c
    ("px4", "NPFG_PERIOD", 10.0),
    ("px4", "NPFG_DAMPING", 0.7),
    ("px4", "NPFG_SW_DST_MLT", 0.32),
]


@pytest.mark.parametrize(("flavour", "name", "value"), SHIPPED)
def test_the_mock_serves_its_firmwares_shipped_defaults_not_the_plans_rates(flavour, name, value):
    with vehicle_and_peer(flavour, scenario=line_scenario(**PLAN)) as (_, link):
        assert read(link, name) == pytest.approx(value, rel=1e-6)


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_the_scenarios_aircraft_sets_cruise_loiter_radius_and_a_given_bank(flavour):
    ap = AUTOPILOTS[flavour]
    given_bank = line_scenario(**PLAN).with_vehicle(
        cruise_airspeed=30.0, radius_source="airspeed and bank"
    )
    with vehicle_and_peer(flavour, scenario=given_bank) as (vehicle, link):
        assert read(link, ap.envelope["cruise_airspeed"]) == pytest.approx(30.0)
        assert read(link, ap.loiter_radius_param) == pytest.approx(200.0)
        bank = math.degrees(math.atan(30.0**2 / (9.80665 * 200.0)))
        assert read(link, ap.envelope["bank_limit"]) == pytest.approx(bank, abs=0.06)
        assert vehicle.autopilot_parameters().cruise_airspeed == pytest.approx(30.0)


HOSTILE = [3e38, math.nan, -25.0, 0.0]


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
@pytest.mark.parametrize("bad", HOSTILE)
def test_an_airspeed_the_flight_cannot_use_is_refused_and_the_flight_still_runs(flavour, bad):
    """AIRSPEED_CRUISE / FW_AIRSPD_TRIM = 3e38 was stored, and MISSION_START then killed the
    flight thread: no telemetry, the vehicle stuck 'flying' nothing."""
    sc = line_scenario()
    name = AUTOPILOTS[flavour].envelope["cruise_airspeed"]
    with vehicle_and_peer(flavour, scenario=sc, speedup=None) as (vehicle, link):
        before = read(link, name)
        real32 = mavlink.MAV_PARAM_TYPE_REAL32
        link.send(link.mav.param_set_encode(1, 1, name.encode(), bad, real32))
        answer, text = answer_and_text(link, name)
        assert answer is not None and answer.param_value == pytest.approx(before)
        assert text is not None and text.severity == mavlink.MAV_SEVERITY_WARNING
        assert vehicle.parameters[name] == before and vehicle.params.refused == 1
        MissionClient(link, target_system=1, target_component=1).upload(waypoint_items(sc, flavour))
        link.send(link.mav.command_long_encode(1, 1, mavlink.MAV_CMD_MISSION_START, 0, 0, 0, 0,
                                               0, 0, 0, 0))  # fmt: skip
        ack = wait_for(link, lambda m: m.get_type() == "COMMAND_ACK")
        assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
        # The flight plays to its end: the corrections are announced.
        made = wait_for(link, lambda m: m.get_type() == "STATUSTEXT" and "fix" in m.text)
        assert made is not None
        vehicle._fly_thread.join(WAIT_S)
    assert vehicle.last_report is not None and vehicle.flight_errors == 0


@pytest.mark.parametrize(
    ("flavour", "name", "bad"),
    [
        ("ardupilot", "ROLL_LIMIT_DEG", 0.0),
        ("ardupilot", "ROLL_LIMIT_DEG", 95.0),
        ("ardupilot", "TECS_CLMB_MAX", -1.0),
        ("ardupilot", "WP_LOITER_RAD", 0.0),
        ("ardupilot", "WP_RADIUS", 1e9),
        ("px4", "FW_T_CLMB_R_SP", math.inf),
        ("px4", "NAV_LOITER_RAD", -80.0),
        ("px4", "NPFG_PERIOD", 0.0),
        ("px4", "NAV_ACC_RAD", 3e38),
    ],
)
def test_every_parameter_is_range_checked(flavour, name, bad):
    with vehicle_and_peer(flavour) as (vehicle, link):
        before = read(link, name)
        ptype = AUTOPILOTS[flavour].spec(name).ptype
        link.send(link.mav.param_set_encode(1, 1, name.encode(), bad, ptype))
        answer, text = answer_and_text(link, name)
        assert answer is not None and answer.param_value == pytest.approx(before)
        assert text is not None
    assert vehicle.parameters[name] == before


def test_a_signed_loiter_radius_and_an_int16_round_are_accepted():
    with vehicle_and_peer("ardupilot") as (vehicle, link):
        link.send(link.mav.param_set_encode(1, 1, b"WP_LOITER_RAD", -187.6, 4))
        answer = wait_for(link, value_of("WP_LOITER_RAD"))
        assert answer is not None and answer.param_value == -188.0
    assert vehicle.autopilot_parameters().loiter_radius == -188.0


def test_the_effective_parameters_follow_what_the_ground_station_sets():
    with vehicle_and_peer("px4") as (vehicle, link):
        got = vehicle.autopilot_parameters()
        assert (got.climb_rate, got.sink_rate, got.bank_limit) == (3.0, 2.0, 50.0)
        assert got.switch_distance(25.0) == pytest.approx(10.0 * 0.7 * 0.32 * 25.0)  # 56 m
        assert got.waypoint_acceptance(25.0, item_radius=1.0) == pytest.approx(56.0)
        for name, value in (("FW_T_CLMB_R_SP", 7.0), ("FW_T_SINK_R_SP", 4.0)):
            link.send(link.mav.param_set_encode(1, 1, name.encode(), value, 9))
            assert wait_for(link, value_of(name)).param_value == value
        got = vehicle.autopilot_parameters()
        # TECS bounds the mission's rate setpoints by FW_T_CLMB_MAX / FW_T_SINK_MAX.
        assert (got.climb_rate, got.sink_rate) == (5.0, 4.0)
    ardu = effective("ardupilot", {})
    assert (ardu.climb_rate, ardu.sink_rate, ardu.bank_limit) == (5.0, 5.0, 45.0)
    assert ardu.loiter_bank_limit == 0.0 and ardu.l1_period == 17.0
    assert ardu.waypoint_acceptance(25.0, item_radius=1.0) == 1.0
    assert ardu.waypoint_acceptance(25.0) == 90.0
