"""A route and its table: the INS error model applied along a given chain of points.

This is the one place that states the error model (docs/model.md, "INS error model") for a fixed
route. The searches use their own vectorised form of the same rules; tests hold the two equal.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from gcs_planner.scenario.model import Kind, Scenario


@dataclass(frozen=True)
class Leg:
    """How a leg is flown. ``arc`` is the turn at the start of the leg (0 for straight legs)."""

    length: float
    arc: float = 0.0  # the turning part (arc, and helix where there is one), flown metres
    turn_angle: float = 0.0  # radians turned on the arc (helix turns not counted)
    helix_turns: int = 0  # whole turns flown to gain or lose height (airplane legs)
    path_angle: float = 0.0  # flight-path angle in degrees, positive climbing (steepest on CS)
    # The limit the leg's path angle is held to (degrees; the climb limit when it climbs, the
    # descent limit otherwise): an airplane leg's own (of its highest point when the envelope
    # is derived per leg), None where the scenario's limits apply.
    angle_limit: float | None = None

    @property
    def straight(self) -> float:
        return self.length - self.arc


@dataclass(frozen=True)
class Stop:
    """One row of a route table: a point and the errors on arrival, before its correction."""

    index: int
    id: str
    kind: Kind
    leg: Leg | None  # the leg flown to reach this point; None at A
    cumulative: float
    v_arrival: float  # error units
    h_arrival: float
    v_limit: float
    h_limit: float
    unreliable: bool = False
    p_arrive: float = 1.0  # probability of arriving here within limits (uncertain corrections)
    # The same errors and limits in metres flown since the last reset: feasibility is decided on
    # these, exactly as the searches decide it, so that a boundary case cannot differ by a ulp.
    v_flown: float = 0.0
    h_flown: float = 0.0
    v_limit_m: float = float("inf")
    h_limit_m: float = float("inf")

    @property
    def v_margin(self) -> float:
        return self.v_limit - self.v_arrival

    @property
    def h_margin(self) -> float:
        return self.h_limit - self.h_arrival

    @property
    def within_limits(self) -> bool:
        return self.v_flown <= self.v_limit_m and self.h_flown <= self.h_limit_m


@dataclass(frozen=True)
class Route:
    """A chain A, correction points, B, evaluated assuming every correction succeeds."""

    points: tuple[int, ...]
    stops: tuple[Stop, ...]
    turn_radius: float = 0.0
    probability: float = 1.0
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def length(self) -> float:
        return self.stops[-1].cumulative

    @property
    def corrections(self) -> int:
        return len(self.points) - 2

    @property
    def feasible(self) -> bool:
        return all(s.within_limits for s in self.stops)

    @property
    def simple(self) -> bool:
        return len(set(self.points)) == len(self.points)

    def first_violation(self) -> Stop | None:
        return next((s for s in self.stops if not s.within_limits), None)

    def ids(self) -> list[str]:
        return [s.id for s in self.stops]

    def with_probabilities(self, probability: float, per_stop: Sequence[float]) -> Route:
        stops = tuple(replace(s, p_arrive=float(p)) for s, p in zip(self.stops, per_stop))
        return replace(self, stops=stops, probability=float(probability))


def straight_legs(scenario: Scenario, points: Sequence[int]) -> list[Leg]:
    """Legs of a route flown as straight segments."""
    xyz = scenario.xyz[list(points)]
    lengths = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    return [Leg(float(d)) for d in lengths]


def evaluate_route(
    scenario: Scenario,
    points: Sequence[int],
    legs: Sequence[Leg] | None = None,
    turn_radius: float = 0.0,
) -> Route:
    """Apply the INS error model along ``points`` (indices, A first, B last).

    Errors accrue on the flown length of each leg; ``legs`` defaults to straight legs. The
    route is evaluated whatever its feasibility: ``Route.feasible`` and ``first_violation``
    say whether and where a limit is passed.
    """
    points = [int(p) for p in points]
    if len(points) < 2:
        raise ValueError("a route has at least A and B")
    if scenario.kind[points[0]] != Kind.A or scenario.kind[points[-1]] != Kind.B:
        raise ValueError("a route starts at A and ends at B")
    if legs is None:
        legs = straight_legs(scenario, points)
    if len(legs) != len(points) - 1:
        raise ValueError("one leg per consecutive pair of points")
    p = scenario.params
    # Distances flown since the last vertical / horizontal reset, in metres.
    # (At A: none at a mission's start; the state reached when planning from a failed fix.)
    dv, dh = scenario.initial_errors
    cumulative = 0.0
    a = points[0]
    stops = [
        Stop(
            a, scenario.ids[a], Kind.A, None, 0.0, dv * p.delta, dh * p.delta, float("inf"),
            float("inf"), v_flown=dv, h_flown=dh,
        )
    ]  # fmt: skip
    for j, leg in zip(points[1:], legs):
        kind = Kind(int(scenario.kind[j]))
        dv += leg.length
        dh += leg.length
        cumulative += leg.length
        v_lim, h_lim = p.limits(kind)
        v_lim_m, h_lim_m = p.limits_m(kind)
        stops.append(
            Stop(
                j,
                scenario.ids[j],
                kind,
                leg,
                cumulative,
                dv * p.delta,
                dh * p.delta,
                v_lim,
                h_lim,
                bool(scenario.unreliable[j]),
                v_flown=dv,
                h_flown=dh,
                v_limit_m=v_lim_m,
                h_limit_m=h_lim_m,
            )
        )
        if kind == Kind.V:
            dv = 0.0
        elif kind == Kind.H:
            dh = 0.0
    return Route(tuple(points), tuple(stops), turn_radius=turn_radius)
