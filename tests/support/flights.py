"""Small missions for the mock vehicle to fly (items written by hand in a local frame, a
waypoint on each point of a line), and the autopilot set up for a plan as the vehicle setup
would set it."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
from gcs_planner.sim.atmosphere import eas2tas
from gcs_planner.sim.guidance import AutopilotParams

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.aircraft.profile import VehicleProfile
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Kind, Origin, Scenario

ORIGIN = Origin(30.5, 123.5, 0.0)
FRAME = LocalFrame(ORIGIN)
PROFILE = VehicleProfile(turn_radius=200.0, max_climb_angle=15.0, max_descent_angle=15.0)

# Dataset 2's limits (Table 2) and the turn and climb limits its helices are flown with.
DS2 = {"alpha1": 20, "alpha2": 10, "beta1": 15, "beta2": 20, "theta": 20, "delta": 0.001}
DS2_LIMITS = {"turn_radius": 200.0, "max_climb_angle": 20.0, "max_descent_angle": 25.0}


def item(seq: int, command: int, xyz=None, **params) -> MissionItem:  # noqa: ANN001, ANN003
    """A mission item; with ``xyz`` (local metres in FRAME) at that place, absolute altitude."""
    if xyz is None:
        return MissionItem(seq, 2, command, **params)
    lat, lon, alt = FRAME.to_geodetic(*xyz)
    return MissionItem(seq, 0, command, x=round(lat * 1e7), y=round(lon * 1e7), z=float(alt),
                       **params)  # fmt: skip


def mission(*specs) -> list[MissionItem]:  # noqa: ANN002 - (command, xyz[, params]) each
    """Items numbered from 0, one for each (command, xyz[, params]) spec."""
    return [
        item(k, *spec[:2], **(spec[2] if len(spec) > 2 else {})) for k, spec in enumerate(specs)
    ]


def line_scenario(**params: Any) -> Scenario:
    """A, V1, H1, V2, B on a line 12 km apart at 5,000 m, dataset 1's limits and ``params``."""
    xyz = np.array([[i * 12_000.0, 0.0, 5000.0] for i in range(5)])
    return Scenario(
        ids=("A", "V1", "H1", "V2", "B"),
        xyz=xyz,
        kind=np.array([Kind.A, Kind.V, Kind.H, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.zeros(5, bool),
        params=replace(DATASET1, **params),
        origin=ORIGIN,
    )


def waypoint_items(sc: Scenario, flavour: str) -> list[MissionItem]:
    """A waypoint on each point (home first where the autopilot keeps it at seq 0), 1 m
    acceptance."""
    frame = LocalFrame(ORIGIN)
    points = [sc.xyz[0], *sc.xyz] if autopilot_for(flavour).home_at_seq0 else list(sc.xyz)
    items = []
    for k, p in enumerate(points):
        lat, lon, alt = frame.to_geodetic(*p)
        items.append(
            MissionItem(k, 0, 16, param2=1.0, x=round(lat * 1e7), y=round(lon * 1e7),
                        z=float(alt))
        )  # fmt: skip
    return items


def configured(scenario: Scenario, flavour: str, lim_bank: float = 45.0) -> AutopilotParams:
    """The autopilot set up for the plan: climb and sink at the plan's path angles through the
    air at the true airspeed of the route's highest point (the plan's angles are at cruise EAS;
    TECS rates are vertical metres per second), its pitch limit letting it climb at that rate
    at the lowest point's true airspeed (whole degrees, as the vehicle setup writes it),
    loiters on the planned radius (ArduPlane NAVL1_LIM_BANK = ``lim_bank``; 0 is the shipped
    default)."""
    v = scenario.vehicle
    base = scenario.origin.alt if scenario.origin else 0.0
    top = float(scenario.xyz[:, 2].max()) + base
    scale = eas2tas(top)
    slowest = v.cruise_airspeed * eas2tas(float(scenario.xyz[:, 2].min()) + base)
    climb = v.climb_rate * scale
    pitch = math.ceil(math.degrees(math.asin(min(climb / slowest, 1.0))) - 1e-9)
    ap = AutopilotParams(flavour, loiter_radius=v.turn_radius, acceptance_radius=1.0,
                         loiter_bank_limit=lim_bank)  # fmt: skip
    ap = ap.with_rates(climb, v.sink_rate * scale)
    return replace(ap, pitch_limit=max(float(pitch), ap.pitch_limit or 0.0))
