"""How late the mock vehicle enters its turns, against the derived reserve's d (issue 31).

The flights of benchmarks.reserve (each workbook's chosen route, the shipped envelopes, design
wind 0, 5, 10 m/s with 1.5 m/s gusts in wind, drawn wind directions, flown on the truth), each
stretch between a reset of an error (or A) and a check of it split as
gcs_planner/aircraft/reserve.py ``route_check`` splits it: what the stretch flew beyond the plan
against its leg-by-leg need at the rule's d (ArduPlane L1/2 + its roll-in, PX4 R/2) and each
leg's own gusts, and the d that would make the need equal to what it flew, (overrun - gusts) /
(sum of 1 - cos(turn) + 2 per helix and the start at A): the most over the stretches with 60
degrees of turn or more and no helix, and over those with a helix.

    python -m benchmarks.turn_entry [--flights N]
"""

from __future__ import annotations

import argparse
import math
import sys

from benchmarks.reserve import GUST, flown_at, planned
from gcs_planner.scenario.model import altitude_of


def stretches(
    route, flown: dict[str, float], basis, altitude=None
) -> list[tuple[float, float, float, int]]:
    """(flown beyond the plan, turn coefficient, gust term, helices) of each stretch flown;
    ``altitude``: a point's altitude by id, for each leg's own gusts (route_check's)."""
    out = []
    stops = route.stops
    leg_gusts = basis.route_gusts(route, altitude)
    last = {"V": 0, "H": 0}
    for k in range(1, len(stops)):
        if stops[k].id not in flown:
            break  # missed: the stretches after it were not flown as planned
        for start in set(last.values()):
            f0 = 0.0 if start == 0 else flown[stops[start].id]
            over = (flown[stops[k].id] - f0) - (stops[k].cumulative - stops[start].cumulative)
            legs = [s.leg for s in stops[start + 1 : k + 1] if s.leg is not None]
            helices = sum(1 for leg in legs if leg.helix_turns > 0)
            # The leg from A has no turn of its own: the start counts as a U-turn (route_check).
            coef = sum(1.0 - math.cos(min(abs(leg.turn_angle), math.pi)) for leg in legs)
            coef += 2.0 * (helices + (1 if start == 0 else 0))
            gusts = sum(leg_gusts[start + 1 : k + 1])
            out.append((over, coef, gusts, helices))
        if stops[k].kind.name in last:
            last[stops[k].kind.name] = k
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=5, help="flights per case (wind directions)")
    args = ap.parse_args(argv)
    from gcs_planner.errors import InfeasibleError

    print(
        "| workbook | autopilot | wind, gusts | d (rule) | stretch most over its need: flown "
        "beyond / need | d needed, turns of 60+ deg (share of d) | d needed, helices (share) |"
    )
    print("|---|---|---|---|---:|---:|---:|")  # fmt: skip
    for dataset in (1, 2):
        for firmware in ("ardupilot", "px4"):
            for wind in (0.0, 5.0, 10.0):
                gust = GUST if wind > 0 else 0.0
                case = f"| dataset {dataset} | {firmware} | {wind:g}, {gust:g} m/s |"
                try:
                    result = planned(dataset, firmware, wind, gust)
                except InfeasibleError:
                    print(f"{case} no route | | | |")
                    continue
                basis = result.scenario.reserve_basis
                margin, at, turns, helix = -math.inf, (0.0, 0.0), 0.0, 0.0
                for seed in range(args.flights):
                    met, to_b = flown_at(result, firmware, wind, gust, seed)
                    if to_b is not None:
                        met[result.route.stops[-1].id] = to_b
                    for over, coef, gusts, helices in stretches(
                        result.route, met, basis, altitude_of(result.scenario)
                    ):
                        need = basis.late * coef + gusts
                        if over - need > margin:
                            margin, at = over - need, (over, need)
                        if over > gusts and coef >= 0.5 and helices == 0:
                            turns = max(turns, (over - gusts) / coef)
                        if over > gusts and helices > 0:
                            helix = max(helix, (over - gusts) / coef)
                d = basis.late
                print(
                    f"{case} {d:.1f} m ({basis.late_rule}) | {at[0]:.1f} / {at[1]:.1f} m | "
                    f"{turns:.1f} m ({turns / d:.2f}) | {helix:.1f} m ({helix / d:.2f}) |"
                )
                sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
