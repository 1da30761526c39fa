"""Section 6: the mock vehicle flies the longest route of the front.

For each workbook the planner's front (length, corrections; R = 200 m) is exported with the dry
run's 1 m acceptance radius and its longest route is replayed: the flight model and autopilot
(sim/guidance.py, fixed 0.5 s step) plus the INS replay along the flown track, against the
chord replay it replaced (the mission's items joined by straight segments, no autopilot), both
timed in this process; and the same mission in a 5 m/s wind with 1.5 m/s gusts, the aircraft
steering its INS estimate (sim/ins.py), against the still-air flight. Also the flown length
against the planned one and the largest deviation from the planned path.

Each flight is timed twice in the same run: compiled (the plain steps in sim/flight_kernel.py,
the default) and in the Python navigators (``compiled=False``, the reference), with their ratio.
``--dry-run-runs N`` also times the whole ``gcs-planner dry-run`` of dataset 2 (the command
docs/benchmarks.md quotes) with ``--runs N`` per autopilot, compiled, against the Python flight when
``--python-dry-run`` is given (PX4's takes minutes), else against the figures measured before
the kernel (stated as such: ArduPlane 11.1 s, PX4 241.7 s for 200 runs, issue 26's session).

A long mission (``--long``, on by default): dataset 2's longest front route out to B and its
waypoints back to A, about 220 km, flown in WIND (5 m/s, gusts 1.5 m/s) by each autopilot on
the truth (``sim.guidance.fly``), compiled and in Python, against the still-air replay of the
same mission (``sim.replay.replay``: flight and INS, as the dry run replays), timed in the same
run: issue 26's "a 220 km mission flown with wind and gusts in under 1 s".

    python -m benchmarks.flight [--runs N] [--dry-run-runs 200 [--python-dry-run]] [--no-long]
"""

from __future__ import annotations

import argparse
import statistics
import time
from dataclasses import dataclass

import numpy as np
from gcs_planner.sim import replay as replay_mod
from gcs_planner.sim.guidance import AutopilotParams
from gcs_planner.sim.wind import WindSpec

from benchmarks.cases import DATA, load_case
from benchmarks.report import seconds, table
from gcs_planner.aircraft.profile import FIRMWARES
from gcs_planner.core.planner import plan
from gcs_planner.dryrun.run import DRY_RUN_ACCEPTANCE_RADIUS_M, max_deviation
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.plan_json import plan_to_dict

# The real-world flight timed beside the still-air one: 5 m/s from 270 deg, 1.5 m/s gusts, the
# aircraft steering its INS estimate.
WIND = WindSpec(5.0, 270.0, 1.5)

TURN_RADIUS = 200.0
FLAVOURS = FIRMWARES


@dataclass(frozen=True)
class FlightRow:
    scenario: str
    flavour: str
    planned_m: float
    flown_m: float
    deviation_m: float
    items: int
    flight_s: float  # flight model + INS replay, still air, on the truth
    chord_s: float  # the chord replay
    arrived: bool
    wind_s: float = 0.0  # in WIND, on the INS estimate
    python_s: float = 0.0  # the still-air flight in the Python navigators
    python_wind_s: float = 0.0  # the WIND flight in the Python navigators


def _chord_replay(items, scenario, home: bool) -> None:
    path = replay_mod.decode_path(items, scenario, home_at_seq0=home)
    encounters = replay_mod.find_encounters(path, scenario)
    replay_mod._fly(path, encounters, scenario, scenario.params, np.random.default_rng(0), 5.0)


def run_flight(specs: list[str], runs: int) -> list[FlightRow]:
    rows = []
    for spec in specs:
        scenario = load_case(spec, TURN_RADIUS)
        result = plan(scenario, objectives=("length", "corrections"))
        longest = max(range(len(result.routes)), key=lambda k: result.routes[k].length)
        route = result.routes[longest]
        for flavour in FLAVOURS:
            mission = build_mission(
                plan_to_dict(result),
                route_index=longest,
                firmware=flavour,
                acceptance_radius=DRY_RUN_ACCEPTANCE_RADIUS_M,
            )
            home = flavour == "ardupilot"
            ap = AutopilotParams(
                flavour, acceptance_radius=DRY_RUN_ACCEPTANCE_RADIUS_M, loiter_radius=TURN_RADIUS
            )
            flight_t, chord_t, wind_t, py_t, py_wind_t = [], [], [], [], []
            report = None
            for _ in range(runs):
                for compiled, still, windy in ((True, flight_t, wind_t), (False, py_t, py_wind_t)):
                    t0 = time.perf_counter()
                    replay_mod.replay(
                        mission.items, scenario, home_at_seq0=home, flavour=flavour,
                        autopilot=ap, wind=WIND, navigate_on_estimate=True, compiled=compiled,
                    )  # fmt: skip
                    windy.append(time.perf_counter() - t0)
                    t0 = time.perf_counter()
                    report = replay_mod.replay(
                        mission.items, scenario, home_at_seq0=home, flavour=flavour,
                        autopilot=ap, compiled=compiled,
                    )  # fmt: skip
                    still.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                _chord_replay(mission.items, scenario, home)
                chord_t.append(time.perf_counter() - t0)
            assert report is not None and report.flown is not None
            rows.append(
                FlightRow(
                    spec,
                    flavour,
                    route.length,
                    report.flown.length,
                    max_deviation(report, trajectory_local(plan_to_dict(result), longest, 2.0))[0],
                    len(mission.items),
                    statistics.median(flight_t),
                    statistics.median(chord_t),
                    report.arrived,
                    statistics.median(wind_t),
                    statistics.median(py_t),
                    statistics.median(py_wind_t),
                )
            )
    return rows


def render(rows: list[FlightRow]) -> str:
    head = ["scenario", "autopilot", "planned", "flown", "largest deviation", "items",
            "flight + INS", "Python flight", "compiled speed-up", "chord replay", "arrived",
            "wind 5 + gusts 1.5, on the estimate", "Python", "speed-up",
            "wind / still-air Python"]  # fmt: skip
    body = [
        [
            r.scenario,
            r.flavour,
            f"{r.planned_m / 1000:,.3f} km",
            f"{r.flown_m / 1000:,.3f} km ({(r.flown_m - r.planned_m):+,.1f} m)",
            f"{r.deviation_m:.1f} m",
            str(r.items),
            seconds(r.flight_s),
            seconds(r.python_s),
            f"{r.python_s / r.flight_s:.1f}x",
            seconds(r.chord_s),
            "yes" if r.arrived else "no",
            seconds(r.wind_s),
            seconds(r.python_wind_s),
            f"{r.python_wind_s / r.wind_s:.1f}x",
            f"{r.wind_s / r.python_s:.2f}x",
        ]
        for r in rows
    ]
    return table(head, body)


@dataclass(frozen=True)
class LongRow:
    flavour: str
    items: int
    flown_m: float  # the wind flight's length
    still_replay_s: float  # replay in still air: the flight and the INS along it
    still_flight_s: float  # the flight alone in still air, compiled
    wind_s: float  # the flight in WIND, compiled
    python_wind_s: float  # the same in the Python navigators
    ended: str


def out_and_back(items: list, home: bool) -> list:
    """The mission ``items`` to B, where its final loiter becomes a waypoint, and its
    waypoints back to the first, in reverse (home, on ArduPilot, left at seq 0)."""
    from dataclasses import replace

    body = items[1:] if home else list(items)
    if body[-1].command == 17:  # NAV_LOITER_UNLIM at B: fly on
        body[-1] = replace(body[-1], command=16, param1=0.0, param2=1.0, param3=0.0, param4=0.0)
    back = [it for it in reversed(body[:-1]) if it.command == 16]
    out = ([items[0]] if home else []) + body + back
    return [it.with_seq(k) for k, it in enumerate(out)]


def run_long(runs: int) -> list[LongRow]:
    from gcs_planner.sim.guidance import fly
    from gcs_planner.sim.replay import scenario_frame

    scenario = load_case("dataset2", TURN_RADIUS)
    result = plan(scenario, objectives=("length", "corrections"))
    longest = max(range(len(result.routes)), key=lambda k: result.routes[k].length)
    frame = scenario_frame(scenario)
    a = scenario.xyz[scenario.start]
    start = (float(a[0]), float(a[1]), float(a[2]))
    wind = WindSpec(WIND.speed, WIND.from_deg, WIND.gust).draw(np.random.default_rng(0))
    rows = []
    for flavour in FLAVOURS:
        home = flavour == "ardupilot"
        mission = build_mission(plan_to_dict(result), route_index=longest, firmware=flavour,
                                acceptance_radius=DRY_RUN_ACCEPTANCE_RADIUS_M)  # fmt: skip
        items = out_and_back(list(mission.items), home)
        ap = AutopilotParams(
            flavour, acceptance_radius=DRY_RUN_ACCEPTANCE_RADIUS_M, loiter_radius=TURN_RADIUS
        )
        still_t, still_fly_t, wind_t, py_t = [], [], [], []
        flight = None
        for _ in range(runs):
            t0 = time.perf_counter()
            replay_mod.replay(items, scenario, home_at_seq0=home, flavour=flavour, autopilot=ap)
            still_t.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            fly(items, frame, start, scenario.vehicle, flavour=flavour, params=ap,
                home_at_seq0=home)  # fmt: skip
            still_fly_t.append(time.perf_counter() - t0)
            for compiled, out in ((True, wind_t), (False, py_t)):
                t0 = time.perf_counter()
                flight = fly(items, frame, start, scenario.vehicle, flavour=flavour, params=ap,
                             home_at_seq0=home, wind=wind, compiled=compiled)  # fmt: skip
                out.append(time.perf_counter() - t0)
        assert flight is not None
        rows.append(
            LongRow(
                flavour,
                len(items),
                float(flight.cumulative[-1]),
                statistics.median(still_t),
                statistics.median(still_fly_t),
                statistics.median(wind_t),
                statistics.median(py_t),
                flight.ended,
            )
        )
    return rows


def render_long(rows: list[LongRow]) -> str:
    head = ["autopilot", "items", "flown (wind)", "ended", "still-air replay (flight + INS)",
            "still-air flight", "wind 5 + gusts 1.5 flight, compiled", "ratio to still-air replay",
            "ratio to still-air flight", "Python", "speed-up"]  # fmt: skip
    body = [
        [
            r.flavour,
            str(r.items),
            f"{r.flown_m / 1000:,.1f} km",
            r.ended,
            seconds(r.still_replay_s),
            seconds(r.still_flight_s),
            seconds(r.wind_s),
            f"{r.wind_s / r.still_replay_s:.2f}x",
            f"{r.wind_s / r.still_flight_s:.2f}x",
            seconds(r.python_wind_s),
            f"{r.python_wind_s / r.wind_s:.1f}x",
        ]  # fmt: skip
        for r in rows
    ]
    return table(head, body)


# The dataset 2 dry run docs/benchmarks.md quotes; --runs and --firmware are added.
DRY_RUN_ARGS = ["dry-run", str(DATA / "dataset2.xlsx"), "--alpha1", "20", "--alpha2", "10",
                "--beta1", "15", "--beta2", "20", "--theta", "20", "--delta", "0.001",
                "--choose", "most-reliable"]  # fmt: skip
# The whole dry run with --runs 200 before the compiled flight (issue 26's session, Python).
BEFORE_KERNEL_S = {"ardupilot": 11.1, "px4": 241.7}


def _time_dry_run(flavour: str, runs: int, compiled: bool) -> tuple[float, str]:
    """(seconds, the success line) of the whole dry run in this process."""
    import contextlib
    import io
    from functools import partial

    from gcs_planner.cli import main as cli_main
    from gcs_planner.dryrun import run as dry_run_mod

    original = dry_run_mod.replay_mod.replay
    out = io.StringIO()
    try:
        if not compiled:
            dry_run_mod.replay_mod.replay = partial(original, compiled=False)
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            cli_main([*DRY_RUN_ARGS, "--firmware", flavour, "--runs", str(runs)])
        elapsed = time.perf_counter() - t0
    finally:
        dry_run_mod.replay_mod.replay = original
    line = next((x for x in out.getvalue().splitlines() if x.startswith("success rate")), "")
    return elapsed, line


def render_dry_runs(runs: int, python: bool) -> str:
    body = []
    for flavour in FLAVOURS:
        fast, line = _time_dry_run(flavour, runs, True)
        if python:
            slow, slow_line = _time_dry_run(flavour, runs, False)
            against = f"{seconds(slow)} (Python, this run)"
            same = "yes" if slow_line == line else "NO"
        else:
            slow = BEFORE_KERNEL_S[flavour] * runs / 200
            against = f"{seconds(slow)} (before the kernel, measured last session, scaled)"
            same = "-"
        body.append([flavour, str(runs), seconds(fast), against, f"{slow / fast:.1f}x", same,
                     line.split(",")[0]])  # fmt: skip
    head = ["autopilot", "runs", "dry run, compiled", "against", "speed-up", "same report",
            "result"]  # fmt: skip
    return table(head, body)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.flight", description=__doc__)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--scenarios", nargs="+", default=["dataset1", "dataset2"])
    ap.add_argument("--dry-run-runs", type=int, default=0)
    ap.add_argument("--python-dry-run", action="store_true")
    ap.add_argument("--no-long", dest="long", action="store_false",
                    help="leave out the ~220 km out-and-back mission")  # fmt: skip
    args = ap.parse_args(argv)
    print(render(run_flight(args.scenarios, args.runs)))
    if args.long:
        print()
        print(render_long(run_long(args.runs)))
    if args.dry_run_runs > 0:
        print()
        print(render_dry_runs(args.dry_run_runs, args.python_dry_run))


if __name__ == "__main__":
    main()
