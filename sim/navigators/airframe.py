"""What flies a navigator's demands: the airframe a navigator is given (:class:`Airframe`), by
default the point mass of sim/aircraft.py (:data:`POINT_MASS`)."""

from __future__ import annotations

from typing import Protocol

from gcs_planner.sim.aircraft import AircraftState, Envelope, step


class Airframe(Protocol):
    """What flies a navigator's demands for one step: a lateral acceleration (m/s^2, + left) and
    a climb rate (m/s) within ``env``, through ``wind`` (east, north m/s), from ``s`` (the state
    it returned last). ``exact``: it can fly any step again from any state it returned, so a
    step may be cut at a finish line and lengthened on settled straight legs (the point mass);
    a flight model with its own state (JSBSim) cannot."""

    exact: bool

    def step(
        self,
        s: AircraftState,
        env: Envelope,
        lateral_accel: float,
        climb_rate: float,
        dt: float,
        wind: tuple[float, float] = (0.0, 0.0),
        eas2tas: float = 1.0,
        heading: float | None = None,
    ) -> AircraftState: ...


class PointMass:
    """The point mass of sim/aircraft.py as an airframe."""

    exact = True
    step = staticmethod(step)


POINT_MASS = PointMass()
