"""The mock vehicle: the vehicle side of the MAVLink mission protocol, seeded link faults, and a
replay of the stored mission with INS drift and corrections against its own landmark database.

It knows nothing of the planner: it checks the mission it was sent against the correction
points it knows, the way a real aircraft would.
"""
