"""The mock vehicle: the vehicle side of the MAVLink mission protocol, seeded link faults, and
the flight of the stored mission with INS drift and corrections against its own landmark
database.

* ``aircraft``: the point-mass fixed wing, at its true airspeed through the air mass;
* ``atmosphere``: ISA, EAS to TAS; ``wind``: steady wind, seeded gusts and vertical
  turbulence (``turbulence``: the Dryden vertical gust of MIL-F-8785C);
* ``navigators``: one per autopilot (ArduPlane, PX4) on one base, with their parameters;
* ``guidance``: mode AUTO as ArduPlane or PX4 flies the mission items;
* ``ins``: the INS estimate the autopilot steers, corrections in the truth;
* ``replay``: the INS along the flown track, corrections within the capture radius, Monte Carlo;
* ``telemetry``: what a ground station sees while it flies;
* ``vehicle``: the MockVehicle on a MAVLink link.

It knows nothing of the planner (a test keeps it from importing it): it checks the mission it
was sent against the correction points it knows, the way a real aircraft would.
"""
