"""The MAVLink link, ground-station side: mission upload/download/clear, parameters."""
