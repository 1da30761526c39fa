"""The aircraft and the autopilot that flies it: the planning problem's aircraft derived from
the autopilot's terms (:mod:`gcs_planner.aircraft.derive`)."""
