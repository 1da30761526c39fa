"""Cross-check: the point mass against JSBSim (issue 31) on the same missions and winds.

Each mission is planned once and dry-run (upload over loopback, read back, replay on the INS
estimate) under both autopilots, in still air and in WIND, with the dry run's point mass
(rolling into its turns), the point mass banking at once (its model before issue 31), the
point mass with its legs checked against the c172r's trims first (``dry-run --aircraft
c172r``) and JSBSim's c172r (sim/jsbsim_airframe.py): flown length against the plan, largest 3D
deviation from the planned path, the true miss distance at each landmark met, the verdict.
The missions: the bundled missions/jsbsim (a light aircraft's mission) and the same lifted by
2.6 km (above the c172r's ceiling at 45 m/s: JSBSim says it cannot be flown, the point mass
flies it).

    python -m benchmarks.jsbsim_check [--aircraft c172r]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from gcs_planner.sim.aircraft import InstantBankFlightModel
from gcs_planner.sim.jsbsim_airframe import DEFAULT_AIRCRAFT, CheckedPointMass, FlightModel
from gcs_planner.sim.wind import WindSpec

from benchmarks.report import machine, table
from gcs_planner.core.planner import plan
from gcs_planner.dryrun.run import dry_run
from gcs_planner.scenario.readers import load_scenario

MISSION = Path(__file__).resolve().parents[1] / "missions" / "jsbsim" / "scenario.toml"
WIND = WindSpec(5.0, 270.0, 1.5)
LIFT_M = 2600.0
HEADER = ("mission", "autopilot", "wind", "model", "flown − planned m", "max dev m",
          "miss at landmarks m", "verdict", "s")  # fmt: skip


def lifted(directory: Path) -> Path:
    """missions/jsbsim with every point LIFT_M higher."""
    lines = (MISSION.parent / "points.csv").read_text().splitlines()
    out = [lines[0]]
    for line in lines[1:]:
        f = line.split(",")
        f[3] = f"{float(f[3]) + LIFT_M:g}"
        out.append(",".join(f))
    (directory / "points.csv").write_text("\n".join(out) + "\n")
    (directory / "scenario.toml").write_text(MISSION.read_text())
    return directory / "scenario.toml"


def _model_name(model: object, aircraft: str) -> str:
    if model is None:
        return "point mass"  # the dry run's: rolls into its turns (sim/aircraft.py step)
    if isinstance(model, InstantBankFlightModel):
        return "point mass, instant bank"
    if isinstance(model, CheckedPointMass):
        return f"point mass, checked against {aircraft}"
    return f"JSBSim {aircraft}"


def verdict(r) -> str:  # noqa: ANN001 - DryRunReport
    if r.airframe_limits:
        return "cannot be flown"
    if r.arrived:
        return "arrived"
    return "LOST: " + ", ".join(f"missed {m.point}" for m in r.missed) if r.missed else "LOST"


def rows(aircraft: str) -> list[tuple]:
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        missions = [("jsbsim", MISSION), (f"jsbsim +{LIFT_M:g} m", lifted(Path(tmp)))]
        for name, path in missions:
            planned = plan(load_scenario(path))
            for flavour in ("ardupilot", "px4"):
                for wind in (WindSpec(), WIND):
                    checked = CheckedPointMass(FlightModel(aircraft))
                    for model in (None, InstantBankFlightModel(), checked, FlightModel(aircraft)):
                        t0 = time.perf_counter()
                        r = dry_run(planned, load_scenario(path), flavour=flavour, wind=wind,
                                    flight_model=model)  # fmt: skip
                        misses = (
                            " ".join(
                                f"{row.point} {row.miss:.1f}" for row in r.rows if row.on_route
                            )
                            if not r.airframe_limits
                            else ""
                        )  # not flown: no misses
                        out.append((
                            name, flavour, "still" if wind.still else "5@270 g1.5",
                            _model_name(model, aircraft),
                            "–" if r.airframe_limits else f"{r.flown_difference:+.1f}",
                            "–" if r.airframe_limits else f"{r.max_deviation:.1f}",
                            misses or "–", verdict(r), f"{time.perf_counter() - t0:.1f}",
                        ))  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.jsbsim_check", description=__doc__)
    ap.add_argument("--aircraft", default=DEFAULT_AIRCRAFT)
    args = ap.parse_args(argv)
    print(table(HEADER, rows(args.aircraft)))
    print(f"\nmachine: {machine()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
