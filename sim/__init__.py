"""The mock vehicle: the vehicle side of the MAVLink mission protocol, seeded link faults, and
the flight of the stored mission with INS drift and corrections against its own landmark
database.

* ``aircraft``: the point-mass fixed wing of the scenario's vehicle profile;
* ``guidance``: mode AUTO as ArduPlane or PX4 flies the mission items;
* ``replay``: the INS along the flown track, corrections within the capture radius, Monte Carlo;
* ``telemetry``: what a ground station sees while it flies;
* ``vehicle``: the MockVehicle on a MAVLink link.

It knows nothing of the planner (a test keeps it from importing it): it checks the mission it
was sent against the correction points it knows, the way a real aircraft would.
"""
