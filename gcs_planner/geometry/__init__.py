"""Leg geometry: straight legs and 3D Dubins (circle then straight) legs, trajectories."""
