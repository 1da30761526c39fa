"""What a plan needs of the autopilot that will fly it, checked on upload.

The needs themselves (cruise airspeed and its range, climb and sink rates, roll limit,
ArduPlane's NAVL1_LIM_BANK, the loiter radius) are the plan's vehicle setup
(:mod:`gcs_planner.mission.vehicle_setup`); here they are read from a vehicle over the link:
:func:`vehicle_shortfalls` returns what falls short, :func:`refusal` says it in one line.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import Link
from gcs_planner.link.params import read_parameter
from gcs_planner.mission.vehicle_setup import ParameterNeed, needs

__all__ = ["ParameterNeed", "Shortfall", "needs", "refusal", "shortfalls", "vehicle_shortfalls"]


@dataclass(frozen=True)
class Shortfall:
    need: ParameterNeed
    value: float

    def describe(self) -> str:
        if self.need.impossible:
            return f"{self.need.name}: {self.need.impossible} ({self.need.why})"
        if math.isnan(self.value):
            return (
                f"{self.need.name} is not on the vehicle (it did not answer), the plan needs "
                f"{self.need.wanted()}: {self.need.why}"
            )
        return (
            f"{self.need.name} is {self.value:g}, the plan needs {self.need.wanted()}: "
            f"{self.need.why}"
        )


def shortfalls(
    plan: dict, firmware: str, read: Callable[[str], float], wanted: Sequence[ParameterNeed] = ()
) -> list[Shortfall]:
    """What the vehicle falls short of among ``plan``'s needs (or ``wanted``, a setup file's),
    reading each parameter with ``read(name)``."""
    out = []
    for need in wanted or needs(plan, firmware):
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
    wanted: Sequence[ParameterNeed] = (),
) -> list[Shortfall]:
    """:func:`shortfalls` read over ``link`` from the vehicle at ``target`` (upload and the dry
    run ask it the same way)."""

    def read(name: str) -> float:
        try:
            return read_parameter(link, target, name, timeout=timeout, retries=retries)
        except LinkError:
            return math.nan  # not on the vehicle: a shortfall, named with the others

    return shortfalls(plan, firmware, read, wanted)


def refusal(short: Sequence[Shortfall], advice: str) -> str:
    """The one line that refuses a vehicle not set up for the plan, each shortfall named."""
    return (
        "the vehicle is not set up to fly this plan: "
        + "; ".join(s.describe() for s in short)
        + f". Nothing was uploaded: {advice}"
    )
