"""The dry run's straight test line: the points, their parameters and flags, and its CSV.

A straight chain A, V*, H, V*, H, V*, H, V, B, 12 km apart (* unreliable). Every point is needed
(a 24 km leg breaks a limit), and by hand: a failed V* leaves v = 5, so the next H sees 17 <= 20
but the V after it sees 29 > 25. The route arrives only if all three V* succeed: P = 0.8 ** 3.
"""

from __future__ import annotations

from pathlib import Path

LINE = [
    ("P0", 0, 0, "A", 0),
    ("P1", 12_000, 300, "V", 1),
    ("P2", 24_000, 0, "H", 0),
    ("P3", 36_000, 300, "V", 1),
    ("P4", 48_000, 0, "H", 0),
    ("P5", 60_000, 300, "V", 1),
    ("P6", 72_000, 0, "H", 0),
    ("P7", 84_000, 300, "V", 0),
    ("P8", 96_000, 0, "B", 0),
]
LINE_P = 0.8**3
PARAMS = {"alpha1": 25, "alpha2": 15, "beta1": 20, "beta2": 25, "theta": 30, "delta": 0.001}
# The line's route arrives with LINE_P < 0.99 on purpose: its dry runs accept the risk.
LINE_FLAGS = [f for k, v in PARAMS.items() for f in (f"--{k}", str(v))] + [
    "--turn-radius", "0", "--allow-risky",
]  # fmt: skip


def write_points(path: Path, rows: list[tuple]) -> Path:
    """``rows`` (id, x, y, kind, unreliable) as a points CSV at ``path``."""
    lines = ["id,x,y,z,kind,unreliable"]
    # Altitude from the point's number, so that a file without some points keeps the others.
    lines += [f"{i},{x},{y},{5000 + 10 * int(i[1:])},{k},{u}" for i, x, y, k, u in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def write_line(folder: Path) -> Path:
    """The line as ``folder``/line.csv."""
    return write_points(folder / "line.csv", LINE)
