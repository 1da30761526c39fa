"""A scenario TOML of three points on a 24 km line at 5,000 m (A, one V point, B, 12 km apart):
the route A V B, planned and flown in seconds, with a table of the caller's appended."""

from __future__ import annotations

from pathlib import Path

POINTS = """id,x,y,z,kind,unreliable
P0,0,0,5000,A,0
P1,12000,0,5000,V,0
P2,24000,0,5000,B,0
"""
HEAD = """name = "short line"
points = "line.csv"

[parameters]
alpha1 = 25
alpha2 = 15
beta1 = 20
beta2 = 25
theta = 30
delta = 0.001
turn_radius = 0
"""


def short_line(folder: Path, table: str = "") -> Path:
    """The scenario as ``folder``/line.toml (its points ``folder``/line.csv), ``table`` (TOML
    text: an [environment] or a [vehicle] table) after its parameters."""
    (folder / "line.csv").write_text(POINTS, encoding="utf-8")
    path = folder / "line.toml"
    path.write_text(HEAD + table, encoding="utf-8")
    return path
