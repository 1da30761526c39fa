"""The derived flight reserve against what the mock vehicle flies (issue 32).

For each workbook (its Table 2 limits), autopilot (the envelope in its shipped terms: ArduPlane
12 m/s EAS, 45 deg, 5/5 m/s; PX4 15 m/s, 50 deg, 3/2 m/s) and design wind (0, 5, 10 m/s; gusts
1.5 m/s in wind), the plan derives its reserve and the chosen route is flown by the mock
vehicle's flight kernel (sim/replay.py, as ``dry-run --set-params`` sets the autopilot up: the
plan's rates, roll limit, ArduPlane's NAVL1_LIM_BANK, the loiter radius, a 1 m acceptance
radius) in that wind from drawn directions. Measured: the most any flight flew beyond the plan
between a reset of an error and a check of it (gcs_planner.dryrun.run.stretch_overrun, over the
landmarks the track met); the flights fly their true position so that every stretch is flown
(a flight on the estimate ends where a failed correction loses it; its track differs by the
estimate's metres only).

    python -m benchmarks.reserve [--flights N]
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "gmcm2019f"
TABLE2 = {
    1: {"alpha1": 25, "alpha2": 15, "beta1": 20, "beta2": 25, "theta": 30, "delta": 0.001},
    2: {"alpha1": 20, "alpha2": 10, "beta1": 15, "beta2": 20, "theta": 20, "delta": 0.001},
}
SHIPPED = {
    "ardupilot": {"cruise_airspeed": 12.0, "max_bank_angle": 45.0, "max_climb_rate": 5.0,
                  "max_sink_rate": 5.0},
    "px4": {"cruise_airspeed": 15.0, "max_bank_angle": 50.0, "max_climb_rate": 3.0,
            "max_sink_rate": 2.0},
}  # fmt: skip
GUST = 1.5


@dataclass(frozen=True)
class Measured:
    dataset: int
    firmware: str
    wind: float
    gust: float
    reserve: float  # the plan's (derived) reserve, m
    need: float  # the chosen route's stretches, leg by leg (flight_reserve.route_check), m
    overrun: float  # the most flown beyond the plan between two resets, over the flights, m
    flights: int
    basis: str


def planned(dataset: int, firmware: str, wind: float, gust: float, per_leg: bool = False):
    """The plan ``gcs-planner plan`` makes for this case (default choice and probability)."""
    from gcs_planner.aircraft.derive import derive_envelope
    from gcs_planner.core.planner import plan
    from gcs_planner.scenario.readers import load_scenario

    terms = SHIPPED[firmware]
    scenario = load_scenario(
        DATA / f"dataset{dataset}.xlsx",
        {**TABLE2[dataset], "cruise_airspeed": terms["cruise_airspeed"],
         "max_bank_angle": terms["max_bank_angle"]},
    )  # fmt: skip
    args = SimpleNamespace(firmware=firmware, per_leg_envelope=per_leg, **terms)
    scenario = derive_envelope(args, scenario, wind_text=f"{wind:g}", gust=gust)
    return plan(scenario, time_limit=None)


def fly(result, firmware: str, wind: float, gust: float, seed: int) -> float | None:
    """The overrun of one flight of the chosen route (None when no stretch was flown)."""
    from gcs_planner.dryrun.run import stretch_overrun

    met, flown_to_b = flown_at(result, firmware, wind, gust, seed)
    rows = [
        SimpleNamespace(point=i, distance=d, on_route=True, outcome="ok") for i, d in met.items()
    ]
    return stretch_overrun(result.route, rows, flown_to_b)


def flown_at(
    result, firmware: str, wind: float, gust: float, seed: int
) -> tuple[dict[str, float], float | None]:
    """One flight of the chosen route: (metres flown from A at each point of the route the
    track met, metres flown to B or None)."""
    report = flight(result, firmware, wind, gust, seed)
    on_route = {s.id for s in result.route.stops}
    met = {e.id: e.distance for e in report.encounters if e.id in on_route}
    return met, (report.flown.length if report.flown is not None else None)


def flight(result, firmware: str, wind: float, gust: float, seed: int, from_deg=None):
    """The replay report of one flight of the chosen route, the wind from ``from_deg`` (None:
    a direction drawn from ``seed``)."""
    from gcs_planner.sim.guidance import AutopilotParams
    from gcs_planner.sim.replay import replay
    from gcs_planner.sim.wind import WindSpec

    from gcs_planner.aircraft.profile import ENVELOPE_PARAMS
    from gcs_planner.link.vehicle_check import needs
    from gcs_planner.mission.builder import build_mission
    from gcs_planner.mission.plan_json import plan_to_dict

    plan_dict = plan_to_dict(result)
    mission = build_mission(plan_dict, firmware=firmware, acceptance_radius=1)
    params = {need.name: need.set_to for need in needs(plan_dict, firmware)}
    if mission.loiter_param:
        params[mission.loiter_param[0]] = float(mission.loiter_param[1])
    eas = result.scenario.cruise_airspeed
    params[ENVELOPE_PARAMS[firmware]["cruise_airspeed"]] = eas
    if firmware == "px4":
        params["NAV_ACC_RAD"] = 1.0
    report = replay(
        mission.items, result.scenario, seed=seed, home_at_seq0=firmware == "ardupilot",
        cruise_speed=eas, flavour=firmware,
        autopilot=AutopilotParams.from_parameters(firmware, params),
        wind=WindSpec(wind, from_deg, gust), navigate_on_estimate=False,
    )  # fmt: skip
    return report


def measure(
    dataset: int, firmware: str, wind: float, gust: float, flights: int, per_leg: bool = False
) -> Measured:
    from gcs_planner.mission.plan_json import reserve_of

    result = planned(dataset, firmware, wind, gust, per_leg)
    basis = result.scenario.reserve_basis
    assert basis is not None, "the reserve was not derived"
    overruns = [fly(result, firmware, wind, gust, seed) for seed in range(flights)]
    flown = [o for o in overruns if o is not None]
    return Measured(
        dataset, firmware, wind, gust, result.scenario.params.reserve,
        reserve_of(result)["chosen_route"]["need_m"], max(flown) if flown else math.nan,
        len(flown), basis.describe(),
    )  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=3, help="flights per case (wind directions)")
    ap.add_argument("--per-leg-envelope", action="store_true",
                    help="plan each leg on its own envelope (plan --per-leg-envelope)")  # fmt: skip
    args = ap.parse_args(argv)
    from gcs_planner.errors import InfeasibleError

    print("| workbook | autopilot | wind, gusts | derived reserve | chosen route needs | "
          "most flown beyond the plan | flights |")  # fmt: skip
    print("|---|---|---|---:|---:|---:|---:|")
    for dataset in (1, 2):
        for firmware in ("ardupilot", "px4"):
            for wind in (0.0, 5.0, 10.0):
                gust = GUST if wind > 0 else 0.0
                try:
                    m = measure(dataset, firmware, wind, gust, args.flights, args.per_leg_envelope)
                except InfeasibleError:
                    print(f"| dataset {dataset} | {firmware} | {wind:g}, {gust:g} m/s | "
                          "no route | | | |")  # fmt: skip
                    continue
                print(
                    f"| dataset {dataset} | {firmware} | {wind:g}, {gust:g} m/s | "
                    f"{m.reserve:.0f} m | {m.need:.0f} m | {m.overrun:.1f} m | {m.flights} |"
                )
                sys.stdout.flush()
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    sys.exit(main())
