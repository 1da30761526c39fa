"""How fast an airframe takes up a climb asked from level flight (issue 31): the dry run's point
mass climbs at the rate asked at once (sim/aircraft.py); JSBSim's aircraft under the adapter's
energy loops (sim/jsbsim_airframe.py) has to pitch up and add throttle first.

Each row: level at the cruise EAS for 20 s, then a step to the climb rate asked for 30 s. The
time until the climb is within 10 % of the rate asked, the largest climb rate reached, and how
far the airframe is below an aircraft that took the rate at once, 5 s and 30 s into the step
(the altitude a leg at the climb limit arrives short by, since the navigator cannot ask more).

    python -m benchmarks.climb_response [--aircraft c172r] [--eas 45] [--altitude 650]
"""

from __future__ import annotations

import argparse

from gcs_planner.sim import atmosphere
from gcs_planner.sim.aircraft import AircraftState, Envelope
from gcs_planner.sim.jsbsim_airframe import DEFAULT_AIRCRAFT, FlightModel

from benchmarks.report import table

STEP_S = 0.5  # the dry run's navigator step (sim/jsbsim_airframe.py OUTER_STEP_S)
LEVEL_S = 20.0
CLIMB_S = 30.0
HEADER = ("aircraft", "EAS m/s", "altitude m", "climb asked m/s", "within 10 % after s",
          "largest climb m/s", "below the point mass at 5 s m", "at 30 s m")  # fmt: skip


def step_response(aircraft: str, eas: float, altitude: float, asked: float) -> tuple:
    """One row of the table: the airframe's climb after a step from level to ``asked``."""
    model = FlightModel(aircraft)
    start = AircraftState(0.0, 0.0, altitude, 0.0, 0.0)
    frame = model.airframe(start, eas, 0.0)
    env = Envelope(eas, 30.0, asked + 2.0, 4.0)  # the rate asked within the autopilot's
    e2t = atmosphere.eas2tas(altitude)
    s = start
    z0 = altitude  # where the climb starts: the altitude at the end of the level flight
    t = 0.0
    settled = None
    top = 0.0
    below = {}
    while t < LEVEL_S + CLIMB_S - 1e-9:
        ask = 0.0 if t < LEVEL_S - 1e-9 else asked
        s = frame.step(s, env, 0.0, ask, STEP_S, (0.0, 0.0), e2t)
        t += STEP_S
        into = t - LEVEL_S
        if into <= 0.0:
            z0 = s.z
            continue
        top = max(top, s.climb_rate)
        if settled is None and abs(s.climb_rate - asked) <= 0.1 * asked:
            settled = into
        for mark in (5.0, CLIMB_S):
            if abs(into - mark) < 1e-6:
                below[mark] = z0 + asked * into - s.z
    return (aircraft, eas, altitude, asked, settled if settled is not None else "–", top,
            below[5.0], below[CLIMB_S])  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--aircraft", default=DEFAULT_AIRCRAFT)
    parser.add_argument("--eas", type=float, default=45.0)
    parser.add_argument("--altitude", type=float, default=650.0)
    args = parser.parse_args(argv)
    rows = [step_response(args.aircraft, args.eas, args.altitude, a) for a in (1.0, 2.0, 3.0)]
    print(table(HEADER, rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
