"""An airframe's envelope from its own JSBSim trims (``plan --aircraft NAME``): the cruise
airspeed, the climb and sink rates at the mission's highest point and the bank, each found by
JSBSim's trim of the airframe (sim/jsbsim_trim.py), then bounded by the autopilot's own limits.

The figures, at the highest altitude of the scenario (where the air is thinnest: the least
thrust, the highest true airspeed):

* **stall**: the lowest equivalent airspeed with a level trim (bisection to 0.1 m/s);
* **cruise**: ``STALL_MARGIN`` times it, rounded up to 0.5 m/s, unless ``--cruise-airspeed``
  states one (a stated airspeed the airframe cannot trim at is refused);
* **climb**: the steepest flight-path angle trimmed at the cruise EAS (the throttle within its
  stops), to ``GAMMA_SEARCH_DEG``; the rate is the true airspeed times its sine;
* **sink**: the steepest descent trimmed at the cruise EAS with the throttle at or above idle;
* **bank**: the steepest level turn trimmed at the cruise EAS (the wing's lift at the stall:
  the load factor 1/cos(bank) it can carry).

The plan then climbs, sinks and banks at the lesser of the airframe's figure and the
autopilot's (TECS_CLMB_MAX / FW_T_CLMB_MAX, TECS_SINK_MAX / FW_T_SINK_MAX, ROLL_LIMIT_DEG /
FW_R_LIM): the autopilot never asks for more than its parameters allow, and the airframe cannot
give more than it trims to. A cruise airspeed the scenario states is the one trimmed at, and
climb and descent angles it states (or ``--max-climb-angle`` / ``--max-descent-angle``) steeper
than the airframe's at that airspeed are cut to the airframe's (``bound_by_airframe``; the dry
run's ``--aircraft`` too): a plan never climbs steeper than its aircraft can.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING

from gcs_planner.errors import InputError

if TYPE_CHECKING:
    from gcs_planner.scenario.model import Scenario

# Cruise at 1.3 times the stall: the wing then carries a load factor of 1.3^2 = 1.69 (a level
# turn of 54 deg) before it stalls, and gusts of 30 % of the airspeed.
STALL_MARGIN = 1.3
SPEED_SEARCH = (5.0, 120.0)  # m/s EAS: the stall is looked for between these
SPEED_TOL = 0.1  # m/s
GAMMA_SEARCH_DEG = 30.0  # the steepest climb and descent looked for (autopilots limit pitch
# far below: ArduPlane TECS_PITCH_MAX 15-20 deg, PX4 FW_P_LIM_MAX 30 deg)
GAMMA_TOL_DEG = 0.25
BANK_SEARCH_DEG = 75.0
BANK_TOL_DEG = 0.5


@dataclass(frozen=True)
class AirframeTrims:
    """What the airframe trims to at ``altitude`` (m above sea level)."""

    aircraft: str
    altitude: float
    stall_eas: float  # m/s
    cruise_eas: float  # m/s
    cruise_tas: float  # m/s
    throttle: float  # level trim at cruise, 0..1
    climb_deg: float  # steepest climb trimmed (GAMMA_SEARCH_DEG: at least that)
    sink_deg: float  # steepest descent trimmed, positive
    bank_deg: float  # steepest level turn trimmed

    @property
    def climb_rate(self) -> float:
        return self.cruise_tas * math.sin(math.radians(self.climb_deg))

    @property
    def sink_rate(self) -> float:
        return self.cruise_tas * math.sin(math.radians(self.sink_deg))

    def describe(self) -> str:
        """One line: what it trims to (">=" where the search's bound was reached)."""

        def at_least(deg: float) -> str:
            return ">= " if deg >= GAMMA_SEARCH_DEG else ""

        return (
            f"the {self.aircraft} trims at {self.altitude:,.0f} m: stall {self.stall_eas:.1f} m/s "
            f"EAS, cruise {self.cruise_eas:g} m/s EAS ({self.cruise_tas:.1f} m/s TAS, "
            f"{self.throttle:.0%} throttle), climb {at_least(self.climb_deg)}"
            f"{self.climb_deg:.1f} deg ({self.climb_rate:.1f} m/s), sink "
            f"{at_least(self.sink_deg)}{self.sink_deg:.1f} deg ({self.sink_rate:.1f} m/s), "
            f"bank {self.bank_deg:.0f} deg"
        )


def _highest(lo: float, hi: float, ok, tol: float) -> float:  # noqa: ANN001 - predicate
    """The highest x in [lo, hi] with ok(x), ok(lo) known true, ok monotone (bisection)."""
    if ok(hi):
        return hi
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def _lowest(lo: float, hi: float, ok, tol: float) -> float:  # noqa: ANN001 - predicate
    """The lowest x in [lo, hi] with ok(x), ok(hi) known true, ok monotone: the highest of the
    mirrored predicate."""
    return -_highest(-hi, -lo, lambda x: ok(-x), tol)


def _steepest(fdm, altitude: float, eas: float) -> tuple[float, float]:  # noqa: ANN001
    """The steepest climb and descent (deg, both positive) trimmed at ``eas`` and ``altitude``,
    the throttle within its stops (to ``GAMMA_SEARCH_DEG``; the level trim known to exist)."""
    from gcs_planner.sim.jsbsim_trim import trim

    def climbs(g: float) -> bool:
        return trim(fdm, altitude, eas, gamma_deg=g) is not None

    def sinks(g: float) -> bool:
        return trim(fdm, altitude, eas, gamma_deg=-g) is not None

    return (
        _highest(0.0, GAMMA_SEARCH_DEG, climbs, GAMMA_TOL_DEG),
        _highest(0.0, GAMMA_SEARCH_DEG, sinks, GAMMA_TOL_DEG),
    )


def airframe_trims(
    aircraft: str,
    altitude: float,
    cruise_eas: float | None = None,
    *,
    field: str = "--aircraft",
    cruise_field: str = "--cruise-airspeed",
) -> AirframeTrims:
    """The airframe's trims at ``altitude`` (m AMSL), at ``cruise_eas`` when given (m/s EAS),
    else at ``STALL_MARGIN`` times its stall. InputError naming ``field`` when JSBSim is
    missing, the aircraft unknown, or it trims at no airspeed there (above its ceiling)."""
    try:
        import jsbsim  # noqa: F401
    except ImportError:
        raise InputError("needs the jsbsim package: pip install '.[jsbsim]'", field=field) from None
    from gcs_planner.sim import atmosphere
    from gcs_planner.sim.jsbsim_trim import _new_fdm, available_aircraft, trim

    known = available_aircraft()
    if aircraft not in known:
        raise InputError(
            f"no JSBSim aircraft {aircraft!r} (e.g. aerosonde, c172r; {len(known)} known)",
            field=field,
        )
    fdm = _new_fdm(aircraft, 60.0)

    def level(eas: float) -> bool:
        return trim(fdm, altitude, eas) is not None

    lo, hi = SPEED_SEARCH
    fastest = next((v for v in range(int(hi), int(lo), -5) if level(float(v))), None)
    if fastest is None:
        raise InputError(
            f"the {aircraft} trims level at no airspeed up to {hi:g} m/s EAS at {altitude:,.0f} m "
            "(above its ceiling)",
            field=field,
        )
    stall = _lowest(lo, float(fastest), level, SPEED_TOL)
    if cruise_eas is None:
        cruise_eas = math.ceil(STALL_MARGIN * stall * 2.0) / 2.0
    at_cruise = trim(fdm, altitude, cruise_eas)
    if at_cruise is None:
        raise InputError(
            f"the {aircraft} cannot be trimmed level at {cruise_eas:g} m/s EAS at "
            f"{altitude:,.0f} m (its stall there: {stall:.1f} m/s EAS)",
            field=cruise_field,
        )
    climb, sink = _steepest(fdm, altitude, cruise_eas)
    bank = _highest(
        0.0,
        BANK_SEARCH_DEG,
        lambda b: trim(fdm, altitude, cruise_eas, bank_deg=b) is not None,
        BANK_TOL_DEG,
    )
    return AirframeTrims(
        aircraft,
        altitude,
        stall,
        cruise_eas,
        cruise_eas * atmosphere.eas2tas(altitude),
        at_cruise.throttle,
        climb,
        sink,
        bank,
    )


def highest_altitude(scenario: Scenario) -> float:
    """The scenario's highest point, m above sea level (its frame's origin altitude added)."""
    base = scenario.origin.alt if scenario.origin is not None else 0.0
    return float(scenario.xyz[:, 2].max()) + base


def _stated(scenario: Scenario) -> set[str]:
    """The aircraft figures the scenario's TOML states ([vehicle] or [parameters])."""
    if not scenario.source.lower().endswith(".toml"):
        return set()
    from pathlib import Path

    from gcs_planner.scenario.toml_reader import read_scenario_toml

    spec = read_scenario_toml(Path(scenario.source))
    return set(spec.vehicle) | set(spec.parameters)


def _plan_cruise(args: argparse.Namespace, scenario: Scenario | None) -> tuple[float | None, str]:
    """The cruise EAS the plan flies (``--cruise-airspeed``, else the scenario's stated one,
    else None) and the field that states it."""
    given = getattr(args, "cruise_airspeed", None)
    if given is not None:
        return float(given), "--cruise-airspeed"
    if scenario is not None and "cruise_airspeed" in _stated(scenario):
        return float(scenario.cruise_airspeed), f"{scenario.source}: vehicle.cruise_airspeed"
    return None, "--cruise-airspeed"


def _cut_angles(
    args: argparse.Namespace, scenario: Scenario, name: str, climb_deg: float, sink_deg: float
) -> list[str]:
    """Cut the climb and descent angles the plan would take (``--max-climb-angle`` /
    ``--max-descent-angle``, else the scenario's stated ones) to the airframe's ``climb_deg``
    and ``sink_deg``: set as the flags, which win over the file. What was cut, as text."""
    stated = _stated(scenario)
    cut = []
    for key, airframe, what in (
        ("max_climb_angle", climb_deg, "climb"),
        ("max_descent_angle", sink_deg, "descent"),
    ):
        given = getattr(args, key, None)
        if given is None and key in stated:
            given = getattr(scenario.params, key)
        if given is None or float(given) <= airframe:
            continue
        if airframe < GAMMA_TOL_DEG:
            raise InputError(
                f"the {name} cannot {what} at the plan's cruise airspeed at the scenario's "
                "highest point (no trim): a slower --cruise-airspeed, or a lower mission",
                field="--aircraft",
            )
        setattr(args, key, airframe)
        cut.append(f"{key} {float(given):g} -> {airframe:.2f} (the {name}'s)")
    return cut


def with_angle_flags(args: argparse.Namespace, scenario: Scenario) -> Scenario:
    """The scenario with the climb and descent angles ``args`` holds (as flags, which win over
    the file; set by ``_cut_angles`` after the scenario was read)."""
    keys = ("max_climb_angle", "max_descent_angle")
    changes = {k: float(getattr(args, k)) for k in keys if getattr(args, k, None) is not None}
    return scenario.with_params(**changes) if changes else scenario


def bound_by_airframe(args: argparse.Namespace, scenario: Scenario) -> Scenario:
    """The dry run's ``--aircraft``: cut the climb and descent angles the plan would take to
    what ``args.aircraft`` trims to at the plan's cruise EAS at the scenario's highest point,
    so the plan it flies is one the airframe can climb; the scenario so cut. Unchanged when the
    airframe cannot fly level there (the check before the flight reports that)."""
    name = getattr(args, "aircraft", None)
    if name is None:
        return scenario
    from gcs_planner.sim.jsbsim_trim import _new_fdm, available_aircraft, trim

    if name not in available_aircraft():
        return scenario  # refused with its one line by the flight model's own check
    cruise, _ = _plan_cruise(args, scenario)
    eas = cruise if cruise is not None else float(scenario.cruise_airspeed)
    altitude = highest_altitude(scenario)
    fdm = _new_fdm(name, 60.0)
    if trim(fdm, altitude, eas) is None:
        return scenario
    climb, sink = _steepest(fdm, altitude, eas)
    cut = _cut_angles(args, scenario, name, climb, sink)
    if cut:
        print(
            f"gcs-planner: the {name} climbs at most {climb:.1f} deg and sinks {sink:.1f} deg at "
            f"{eas:g} m/s EAS at {altitude:,.0f} m: planned within them: {', '.join(cut)}",
            file=sys.stderr,
        )
    return with_angle_flags(args, scenario)


def apply_airframe_trims(
    args: argparse.Namespace, highest: float, autopilot: str, scenario: Scenario | None = None
) -> None:
    """Fill the autopilot-term flags left unset (``--cruise-airspeed``, ``--max-bank-angle``,
    ``--max-climb-rate``, ``--max-sink-rate``) from ``args.aircraft``'s trims at ``highest``
    (m AMSL), each bounded by ``autopilot``'s own limit; with the ``scenario``, trim at the
    cruise airspeed it states and cut its stated climb and descent angles to the airframe's.
    Say what it trims to on stderr."""
    name = getattr(args, "aircraft", None)
    if name is None:
        return
    from gcs_planner.aircraft.autopilot import effective

    cruise, cruise_field = _plan_cruise(args, scenario)
    trims = airframe_trims(name, highest, cruise, cruise_field=cruise_field)
    ap = effective(autopilot, {})
    figures: dict[str, float | None] = {
        # a stated cruise airspeed (flag or scenario) is the one trimmed at, not derived
        "cruise_airspeed": None if cruise is not None else trims.cruise_eas,
        "max_bank_angle": min(trims.bank_deg, ap.bank_limit),
        "max_climb_rate": min(trims.climb_rate, ap.climb_rate),
        "max_sink_rate": min(trims.sink_rate, ap.sink_rate),
    }
    used = []
    for key, value in figures.items():
        if value is not None and getattr(args, key, None) is None:
            setattr(args, key, value)
            used.append(f"{key} {value:.3g}")
    cut = (
        []
        if scenario is None
        else _cut_angles(args, scenario, name, trims.climb_deg, trims.sink_deg)
    )
    args.vehicle_source = f"the {name} airframe's trims"
    print(
        f"gcs-planner: {trims.describe()}; with {autopilot}'s limits (bank {ap.bank_limit:g} deg, "
        f"climb {ap.climb_rate:g} m/s, sink {ap.sink_rate:g} m/s) the envelope is derived from: "
        f"{', '.join(used) or 'nothing (all given as flags)'} (a turning radius the scenario "
        f"states wins){'; climbs cut to the airframe: ' + ', '.join(cut) if cut else ''}",
        file=sys.stderr,
    )
