"""How far gusts wander the mock vehicle's track on straight legs, against the derived reserve's
rule (gcs_planner/aircraft/reserve.py: wander = GUST_MARGIN x F (sigma / Vg)^2 / 2, F the closed
loop's share of the gust's power, track_wander).

The chosen route of a workbook (Table 2 limits, the autopilot's shipped envelope, design wind
10 m/s, gusts 1.5 m/s) flown on the truth in a 10 m/s wind from 12 directions, two gust draws
each. Each straight leg of 3 km or more, its first and last tenth left out (turns), gives the
share its track is longer than its chord and its ground speed (the TAS at its mean altitude
and the wind's components along and across it). k = share / ((sigma / Vg)^2 / 2): the rule
takes GUST_MARGIN x F for it, F at the fastest TAS.

    python -m benchmarks.gust_wander [--directions 12] [--draws 2]
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from benchmarks.reserve import GUST, flight, planned

WIND = 10.0
BANDS = (2.0, 5.0, 8.0, 11.0, 14.0, 17.0, 20.0, 23.0, 26.0, 29.0, 32.0)


def straight_legs(result, firmware: str, from_deg: float, seed: int) -> list[tuple[float, float]]:
    """(ground speed, share the track is longer than its chord) of each long straight leg."""
    from gcs_planner.aircraft.profile import tas_from_eas

    path = flight(result, firmware, WIND, GUST, seed, from_deg).flown
    pts, seqs = path.points, np.asarray(path.seqs)
    a_from = math.radians(from_deg)
    towards = np.array([-WIND * math.sin(a_from), -WIND * math.cos(a_from)])
    out = []
    for seq in sorted(set(seqs.tolist())):
        idx = np.nonzero(seqs == seq)[0]
        if len(idx) < 50:
            continue
        a, b = idx[len(idx) // 10], idx[-(len(idx) // 10)]
        horizontal = pts[a : b + 1, :2]
        chord = float(np.linalg.norm(horizontal[-1] - horizontal[0]))
        if chord < 3000.0:
            continue
        flown = float(np.linalg.norm(np.diff(horizontal, axis=0), axis=1).sum())
        along_unit = (horizontal[-1] - horizontal[0]) / chord
        along = float(along_unit @ towards)
        across = abs(float(along_unit[0] * towards[1] - along_unit[1] * towards[0]))
        tas = tas_from_eas(result.scenario.cruise_airspeed, float((pts[a, 2] + pts[b, 2]) / 2))
        ground = along + math.sqrt(max(tas * tas - across * across, 0.0))
        if ground > 0:
            out.append((ground, (flown - chord) / chord))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--directions", type=int, default=12, help="wind directions, evenly spaced")
    ap.add_argument("--draws", type=int, default=2, help="gust draws per direction")
    args = ap.parse_args(argv)
    print(
        "| route | ground speed | legs | longer than the chord: mean (most) | k: mean (most) | "
        "the rule's factor |"
    )
    print("|---|---|---:|---:|---:|---:|")  # fmt: skip
    for dataset, firmware in ((2, "ardupilot"), (1, "px4")):
        result = planned(dataset, firmware, WIND, GUST)
        rule = result.scenario.reserve_basis.wander
        rows = []
        for j in range(args.directions):
            for seed in range(args.draws):
                rows += straight_legs(result, firmware, 360.0 * j / args.directions, seed)
        name = f"dataset {dataset}, {'ArduPlane' if firmware == 'ardupilot' else 'PX4'}"
        for lo, hi in zip(BANDS, BANDS[1:], strict=False):
            band = [(v, e) for v, e in rows if lo <= v < hi]
            if not band:
                continue
            shares = [e for _, e in band]
            ks = [e / (0.5 * (GUST / v) ** 2) for v, e in band]
            print(
                f"| {name} | {lo:g}-{hi:g} m/s | {len(band)} | {100 * np.mean(shares):.3f} % "
                f"({100 * max(shares):.3f} %) | {np.mean(ks):.2f} ({max(ks):.2f}) | {rule:.2f} |"
            )
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
