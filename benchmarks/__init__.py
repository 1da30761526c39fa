"""Benchmarks of the planner against its peers: ``python -m benchmarks --help``."""
