"""What a plan needs of the autopilot that will fly it, checked on upload (issue 32).

A plan whose envelope was derived from the autopilot's terms (``vehicle.envelope`` in the plan
JSON: docs/model.md, "Flight in the real world") climbs, sinks and banks at most at the rates and
roll limit it names. The aircraft flies it only if its autopilot is set up for that:

* its mission climb and sink rates are at least the plan's: ArduPlane TECS_CLMB_MAX and
  TECS_SINK_MAX (``AP_TECS``); PX4 in missions the rate setpoints FW_T_CLMB_R_SP / FW_T_SINK_R_SP,
  bounded by FW_T_CLMB_MAX / FW_T_SINK_MAX (``FixedwingPositionControl``), so all four;
* its roll limit is at least the bank the plan's turning radius was derived with
  (ROLL_LIMIT_DEG; FW_R_LIM);
* ArduPlane keeps loiters at the radius the mission gives only when NAVL1_LIM_BANK allows it:
  ``AP_L1_Control::loiter_radius`` returns radius x EAS2TAS^2 when it is 0 (the default: a 44 m
  helix at 10 km becomes 80 m), and max(radius, EAS^2 / (g tan(NAVL1_LIM_BANK)) x EAS2TAS^2)
  otherwise, which is the radius itself once TAS^2 / (g tan(NAVL1_LIM_BANK)) <= R.

:func:`needs` lists them for a plan and a firmware; :func:`vehicle_shortfalls` reads the
vehicle's values and returns what falls short; with ``--set-params`` the upload sets each to
what the plan needs (listed before anything is written) and reads it back. A plan whose
envelope was stated directly (angles and a radius) names no rates, and nothing is checked
beyond the loiter radius the upload sets anyway.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from gcs_planner.autopilot import autopilot_for
from gcs_planner.link.connection import Link
from gcs_planner.link.params import read_parameter
from gcs_planner.vehicle import G

# Slack for rates and angles written and read back as float32.
_SLACK = 1e-4


@dataclass(frozen=True)
class ParameterNeed:
    """The plan needs parameter ``name`` to be at least ``least`` (in the parameter's unit),
    for the reason ``why``; ``set_to`` is the value the upload writes with ``--set-params``."""

    name: str
    least: float
    set_to: float
    why: str

    def met_by(self, value: float) -> bool:
        return math.isfinite(value) and value >= self.least - _SLACK * max(1.0, abs(self.least))


def needs(plan: dict, firmware: str) -> list[ParameterNeed]:
    """What ``plan`` (a plan JSON) needs of a ``firmware`` autopilot's parameters; empty when the
    plan has no derived envelope."""
    vehicle = plan.get("vehicle") if isinstance(plan.get("vehicle"), dict) else {}
    env = vehicle.get("envelope") if isinstance(vehicle, dict) else None
    if not isinstance(env, dict):
        return []
    ap = autopilot_for(firmware)
    out: list[ParameterNeed] = []
    rates = [("climb_rate", "climbs"), ("sink_rate", "sinks")]
    for i, (key, verb) in enumerate(rates):
        rate = env.get(key)
        if not isinstance(rate, (int, float)) or not math.isfinite(rate):
            continue  # unlimited in the plan: the aircraft's own limit is what it flies with
        why = f"the plan {verb} at up to {rate:g} m/s (its envelope's {key.replace('_', ' ')})"
        names = [ap.mission_climb[i]]
        if ap.mission_climb_bounds:
            names.append(ap.mission_climb_bounds[i])
        out += [ParameterNeed(name, float(rate), float(rate), why) for name in names]
    bank = env.get("bank_limit_deg")
    if isinstance(bank, (int, float)) and 0 < bank < 90:
        out.append(
            ParameterNeed(
                ap.envelope["bank_limit"],
                float(bank),
                float(bank),
                f"the plan's turning radius {env.get('turn_radius', 0):.1f} m was derived with "
                f"a {bank:g} deg bank",
            )
        )
    radius, tas = env.get("turn_radius"), env.get("tas")
    if firmware == "ardupilot" and _positive(radius) and _positive(tas):
        # the least bank for which loiter_radius keeps R at the highest point's TAS
        least = math.degrees(math.atan(tas * tas / (G * radius)))
        set_to = min(89.0, max(least, float(bank) if _positive(bank) else least))
        out.append(
            ParameterNeed(
                "NAVL1_LIM_BANK",
                least,
                set_to,
                f"loiters must keep the plan's {radius:.1f} m radius at {tas:.1f} m/s TAS "
                "(0 widens every loiter by EAS2TAS^2)",
            )
        )
    return out


def _positive(x: object) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


@dataclass(frozen=True)
class Shortfall:
    need: ParameterNeed
    value: float

    def describe(self) -> str:
        return (
            f"{self.need.name} is {self.value:g}, the plan needs at least {self.need.least:.4g}: "
            f"{self.need.why}"
        )


def shortfalls(plan: dict, firmware: str, read: Callable[[str], float]) -> list[Shortfall]:
    """What the vehicle falls short of among ``plan``'s needs, reading each parameter with
    ``read(name)``."""
    out = []
    for need in needs(plan, firmware):
        value = read(need.name)
        if not need.met_by(value):
            out.append(Shortfall(need, value))
    return out


def vehicle_shortfalls(
    link: Link,
    target: tuple[int, int],
    plan: dict,
    firmware: str,
    *,
    timeout: float,
    retries: int,
) -> list[Shortfall]:
    """:func:`shortfalls` read over ``link`` from the vehicle at ``target`` (upload and the dry
    run ask it the same way)."""

    def read(name: str) -> float:
        return read_parameter(link, target, name, timeout=timeout, retries=retries)

    return shortfalls(plan, firmware, read)


def refusal(short: Sequence[Shortfall], advice: str) -> str:
    """The one line that refuses a vehicle not set up for the plan, each shortfall named."""
    return (
        "the vehicle is not set up to fly this plan: "
        + "; ".join(s.describe() for s in short)
        + f". Nothing was uploaded: {advice}"
    )
