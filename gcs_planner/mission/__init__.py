"""The mission: route → MAVLink mission items, georeference, .plan/.waypoints, trajectories."""
