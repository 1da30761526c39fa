"""What contingency policies buy on the contest workbooks (docs/model.md, "Contingency
policies"): the route front's most reliable route against the best policy replanned from the
front's routes (``core/replan.py``: at each failed fix, the most reliable continuation planned
from the state reached), one to three levels deep.

Dataset 2 with Table 2's limits, R = 200 m, the default 200 m reserve, climb/descent limits
15°/15° and 20°/25° (the envelopes issue 27 names). Each row: the best of its kind by F3, then
shorter worst case; the policy front's size (the non-dominated of routes and policies).

An envelope written ``15/15:ardupilot`` is the one flown by the mock ArduPlane at 25 m/s EAS:
every leg straight for ArduPlane's settle distance before and after each landmark (its L1
distance at the TAS of the highest point, docs/model.md "Straight at every landmark") and every
run-out at least the switch room of a 10 s switch (core/switch_room.py), as `plan --policy`
plans it; the others are the contest's model (no run-in or run-out, no switch room).

    python -m benchmarks.policies [--levels 1,2,3] [--envelopes 15/15,20/25,15/15:ardupilot]
"""

from __future__ import annotations

import argparse
import time

from benchmarks.cases import DATA
from benchmarks.report import table
from gcs_planner.aircraft.autopilot import effective
from gcs_planner.aircraft.profile import tas_from_eas
from gcs_planner.core.contingency import Policy, evaluate
from gcs_planner.core.planner import plan
from gcs_planner.core.policy_front import replanned_front
from gcs_planner.core.replan import replan_on_failure
from gcs_planner.core.switch_room import DEFAULT_SWITCH_TIME_S, switch_room, with_switch_room
from gcs_planner.library import load_scenario
from gcs_planner.scenario.model import Scenario

TABLE2 = {"alpha1": 20, "alpha2": 10, "beta1": 15, "beta2": 20, "theta": 20, "delta": 0.001}


def flown_by(sc: Scenario, firmware: str) -> Scenario:
    """``sc`` as ``plan --policy --approach S --departure S`` plans it for ``firmware``: S its
    settle distance at the TAS of the highest point, every run-out at least the switch room."""
    top = float(sc.xyz[:, 2].max()) + (sc.origin.alt if sc.origin else 0.0)
    settle = effective(firmware, {}).settle_distance(tas_from_eas(sc.cruise_airspeed, top))
    sc = sc.with_params(approach=settle, departure=settle)
    return with_switch_room(sc, switch_room(sc, DEFAULT_SWITCH_TIME_S))


def rows(envelopes: list[tuple[float, float, str]], levels: list[int]) -> list[list[object]]:
    out: list[list[object]] = []
    for climb, descent, firmware in envelopes:
        sc = load_scenario(
            DATA / "dataset2.xlsx", **TABLE2, turn_radius=200.0,
            max_climb_angle=climb, max_descent_angle=descent,
        )  # fmt: skip
        if firmware:
            sc = flown_by(sc, firmware)
        t0 = time.perf_counter()
        result = plan(sc, choice="most-reliable", min_probability=0.0)
        planned = time.perf_counter() - t0
        values = [evaluate(sc, Policy.from_route(sc, r)) for r in result.routes]
        best = max(values, key=lambda v: (v.probability, -v.length))
        envelope = f"{climb:g}°/{descent:g}°" + (
            f", {firmware} (run-in {sc.params.approach:.0f} m, run-out {sc.params.departure:.0f} m)"
            if firmware
            else ""
        )
        out.append([
            envelope, "best route", f"{len(result.routes)} routes", f"{best.probability:.4f}",
            f"{best.length:,.0f}", best.corrections, f"{best.expected_length_arrived:,.0f}",
            "–", f"{planned:.1f}",
        ])  # fmt: skip
        for depth in levels:
            t0 = time.perf_counter()
            policies, plans = [], 0
            for route in result.routes:
                got = replan_on_failure(sc, route, levels=depth)
                policies.append(got.policy)
                plans += got.plans
            front = replanned_front(sc, result.routes, policies)
            seconds = time.perf_counter() - t0
            top = max(front, key=lambda pt: (pt.value.probability, -pt.value.length)).value
            out.append([
                envelope, f"best policy, {depth} level(s)", f"front of {len(front)}",
                f"{top.probability:.4f}", f"{top.length:,.0f}", top.corrections,
                f"{top.expected_length_arrived:,.0f}", plans, f"{seconds:.1f}",
            ])  # fmt: skip
    return out


HEADER = [
    "envelope", "what", "front", "P arrive", "worst-case m", "corrections (most)",
    "expected m (arrived)", "continuations planned", "seconds",
]  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", default="1,2,3")
    ap.add_argument("--envelopes", default="15/15,20/25,15/15:ardupilot")
    args = ap.parse_args(argv)
    levels = [int(x) for x in args.levels.split(",")]
    envelopes = []
    for spec in args.envelopes.split(","):
        angles, _, firmware = spec.partition(":")
        climb, descent = (float(y) for y in angles.split("/"))
        envelopes.append((climb, descent, firmware))
    print(table(HEADER, rows(envelopes, levels)))  # type: ignore[arg-type]


if __name__ == "__main__":
    main()
