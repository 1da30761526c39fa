"""gcs_planner: exact INS-constrained route planning, MAVLink mission export, mock vehicle."""

__version__ = "0.1.0"
