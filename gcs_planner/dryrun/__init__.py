"""The dry run: a plan flown end to end against the mock vehicle over real MAVLink on
loopback, and its report (the verdict, the flown track, the success rate's interval)."""
