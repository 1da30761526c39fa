"""Regenerate ``landmarks.csv``: ``python missions/coast/generate.py``.

Sixty correction landmarks over 60 km x 20 km of the East China Sea, surveyed in WGS84 latitude
and longitude with altitudes above mean sea level: the vertical-correction (V) landmarks low,
200 m to 700 m, where the sea surface calibrates the altimeter; the horizontal ones (H) high,
2,600 m to 3,400 m. A route alternates between the two bands, so a V and an H landmark close
together make a leg too steep for a 15 degree climb or descent, flown as a helix. About three
landmarks in ten are unreliable. The seed was picked (by planning a few dozen candidates) for a
front that shows what the planner weighs: routes that differ in length, number of corrections
and probability of arriving, the shortest through unreliable landmarks, and helices.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Origin

SEED = 21
N = 60
# The survey's frame: its x, y are metres east and north of this point.
SURVEY = Origin(lat=30.62, lon=123.05, alt=0.0)
OUT = Path(__file__).resolve().parent / "landmarks.csv"


def landmarks() -> list[dict[str, object]]:
    rng = np.random.default_rng(SEED)
    a = [0.0, 10_000.0, 1_500.0]
    b = [60_000.0, rng.uniform(6_000, 14_000), 1_200.0]
    xy = np.column_stack([rng.uniform(3_000, 57_000, N), rng.uniform(0, 20_000, N)])
    vertical = rng.random(N) < 0.5
    z = np.where(vertical, rng.uniform(200, 700, N), rng.uniform(2_600, 3_400, N))
    pts = np.column_stack([xy, z])
    unreliable = rng.random(N) < 0.3
    xyz = np.vstack([a, pts, b])
    lat, lon, alt = LocalFrame(SURVEY).to_geodetic(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    rows: list[dict[str, object]] = []
    for i in range(N + 2):
        if i == 0:
            pid, kind, flag = "A", "A", 0
        elif i == N + 1:
            pid, kind, flag = "B", "B", 0
        else:
            kind = "V" if vertical[i - 1] else "H"
            pid, flag = f"{kind}{i:02d}", int(unreliable[i - 1])
        rows.append(
            {
                "id": pid,
                "lat": f"{lat[i]:.8f}",  # 1e-8 degree: about a millimetre
                "lon": f"{lon[i]:.8f}",
                "alt": f"{alt[i]:.2f}",
                "kind": kind,
                "unreliable": flag,
            }
        )
    return rows


def main() -> None:
    with OUT.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(
            f, ["id", "lat", "lon", "alt", "kind", "unreliable"], lineterminator="\n"
        )
        writer.writeheader()
        writer.writerows(landmarks())
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
