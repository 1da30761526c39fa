"""Leg models: what the search asks of the geometry, and never more (as OMPL's planners ask a state
space for distances and never know the formula).

Each model answers, for one start point and heading and many targets:

* ``lengths(start, heading, ends)``: the flown lengths and the headings at the targets (inf and
  NaN where the leg cannot be flown);
* ``lower_bounds(start, ends)``: a heading-free lower bound of each leg's flown length, which the
  reach graph, the cost-to-go and every admissible bound are made of;
* ``leg(start, heading, end)``: the flown geometry of one leg, for tables, exports and pictures.

``carries_heading`` says whether a leg depends on the heading it starts with; when it does not,
partial routes at one point are comparable whatever their past, and the lower bound is the flown
length itself (``exact_bounds``). The search asks three more things, so that it never looks at
which model it has: ``kernel_legs()`` (the numbers the compiled search flies the legs with, or
None where it needs none), ``chord_bounds`` (whether the lower bounds are the chords) and
``turns_in_bounds`` (whether a pair relaxation over the turn into each leg can raise them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from gcs_planner.geometry.airplane import (
    AirplaneLeg,
    LegEnvelope,
    airplane_leg,
    airplane_legs,
    lower_bounds,
    lower_bounds_tan,
    slope_tan,
)
from gcs_planner.geometry.dubins import CSLeg, cs_leg, cs_lengths, straight_leg

FlownLeg = CSLeg | AirplaneLeg


@dataclass(frozen=True)
class KernelLegs:
    """How the compiled search flies a model's legs from a heading (``search_kernel``)."""

    kind: str  # "airplane" or "cs3d"
    radius: float
    tan_climb: float  # math.inf: no climb limit
    tan_descent: float
    run_in: float = 0.0  # airplane: least tangent into a target (m, horizontal)
    run_out: float = 0.0  # airplane: straight on from a point before turning (m, horizontal)
    envelope: LegEnvelope | None = None  # airplane: each leg's limits from its altitude

    def at_points(
        self, z: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(radius, tan climb, tan descent, the TAS the limits are taken at) at each point's
        altitude ``z``, and the design wind's (east, north) m/s where the angles follow the
        legs' tracks (zeros where not): the envelope's, or the model's one radius and limits
        everywhere."""
        z = np.asarray(z, dtype=float)
        if self.envelope is not None:
            env = self.envelope
            r, c, d = (np.ascontiguousarray(a, float) for a in env.at(z))
            v = np.ascontiguousarray(env.airspeed_at(z), float)
            return r, c, d, v, np.ascontiguousarray(env.wind_vector, float)
        n = len(z)
        return (
            np.full(n, self.radius), np.full(n, self.tan_climb), np.full(n, self.tan_descent),
            np.zeros(n), np.zeros(2),
        )  # fmt: skip


class LegModel(Protocol):
    name: str
    radius: float
    carries_heading: bool
    chord_bounds: bool
    turns_in_bounds: bool

    def kernel_legs(self) -> KernelLegs | None: ...

    def lengths(
        self, start: np.ndarray, heading: np.ndarray | None, ends: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray | None]: ...

    def lower_bounds(self, start: np.ndarray, ends: np.ndarray) -> np.ndarray: ...

    def leg(self, start: np.ndarray, heading: np.ndarray | None, end: np.ndarray) -> FlownLeg: ...

    def relaxation(self) -> LegModel: ...


def _chords(start: np.ndarray, ends: np.ndarray) -> np.ndarray:
    w = np.asarray(ends, dtype=float) - np.asarray(start, dtype=float)
    return np.sqrt(np.einsum("ij,ij->i", w, w))


@dataclass(frozen=True)
class StraightLegs:
    """Straight legs: the chord, no heading (turning radius 0, no climb limit)."""

    name: str = "straight"
    radius: float = 0.0
    carries_heading: bool = False
    chord_bounds: bool = True
    turns_in_bounds: bool = False

    def kernel_legs(self) -> KernelLegs | None:
        return None  # heading-free: the search takes the legs from the reach graph

    def lengths(self, start, heading, ends):
        return _chords(start, ends), None

    def lower_bounds(self, start, ends):
        return _chords(start, ends)

    def leg(self, start, heading, end):
        if heading is None:
            return straight_leg(start, end, None, 0.0)
        return cs_leg(start, heading, end, 0.0)  # the heading jumps to the chord's

    def relaxation(self) -> LegModel:
        return self


@dataclass(frozen=True)
class CS3DLegs:
    """The tilted-plane 3D Dubins CS leg (docs/model.md, "Leg geometry"), kept to reproduce
    earlier figures. It plans without climb limits."""

    radius: float
    name: str = "cs3d"
    carries_heading: bool = True
    chord_bounds: bool = True
    turns_in_bounds: bool = False

    def kernel_legs(self) -> KernelLegs | None:
        return KernelLegs("cs3d", float(self.radius), math.inf, math.inf)

    def lengths(self, start, heading, ends):
        if heading is None:  # free heading at A: the chord
            chord = _chords(start, ends)
            w = np.asarray(ends, dtype=float) - np.asarray(start, dtype=float)
            return chord, w / np.where(chord > 0, chord, 1.0)[:, None]
        return cs_lengths(start, heading, ends, self.radius)

    def compiled_lengths(self, start, heading, ends):
        """``lengths`` from a given heading, compiled (``dubins_kernel``: within a few ulp of
        numpy's). Loads numba on the first call: for searches that fly many partial routes."""
        from gcs_planner.geometry.dubins_kernel import cs_lengths as compiled

        return compiled(start, heading, ends, self.radius)

    def lower_bounds(self, start, ends):
        return _chords(start, ends)

    def leg(self, start, heading, end):
        if heading is None:
            return straight_leg(start, end, None, self.radius)
        return cs_leg(start, heading, end, self.radius)

    def relaxation(self) -> LegModel:
        return StraightLegs()


@dataclass(frozen=True)
class AirplaneLegs:
    """Horizontal turns of radius R, a constant flight-path angle within the climb and descent
    limits, helices where a leg is too steep (docs/model.md, "Airplane legs"); with turns, each
    leg may run ``run_out`` metres straight on before it turns and must arrive on a tangent of
    at least ``run_in`` metres ("Straight at every landmark")."""

    radius: float
    max_climb_angle: float = 90.0
    max_descent_angle: float = 90.0
    run_in: float = 0.0
    run_out: float = 0.0
    name: str = "airplane"
    # Each leg's radius and limits from the altitude of its highest point (the envelope derived
    # from the autopilot's terms, docs/model.md "Flight in the real world"); None: ``radius``
    # and the angles for every leg. With it, ``radius`` and the angles are those of the
    # scenario's highest point (the largest radius, the shallowest angles).
    envelope: LegEnvelope | None = None

    @property
    def carries_heading(self) -> bool:
        return self.radius > 0

    @property
    def chord_bounds(self) -> bool:
        # with unlimited climb no altitude change needs more path than the chord
        return self.max_climb_angle >= 90.0 and self.max_descent_angle >= 90.0

    @property
    def turns_in_bounds(self) -> bool:
        # The pair relaxation (core/pair_bounds.py) bounds the heading cone and the turn of the
        # CS path from the turn start, s_out straight on from the point (its cone widens by
        # the run-out). It takes one radius and one pair of limits for every leg.
        return self.radius > 0 and self.envelope is None

    def kernel_legs(self) -> KernelLegs | None:
        return KernelLegs(
            "airplane", float(self.radius), slope_tan(self.max_climb_angle),
            slope_tan(self.max_descent_angle), float(self.run_in), float(self.run_out),
            self.envelope,
        )  # fmt: skip

    def lengths(self, start, heading, ends):
        legs = airplane_legs(
            start, heading, ends, self.radius, self.max_climb_angle, self.max_descent_angle,
            self.run_in, self.run_out, self.envelope,
        )  # fmt: skip
        return legs.length, (legs.heading if self.radius > 0 else None)

    def compiled_lengths(self, start, heading, ends):
        """``lengths`` from a given heading, compiled (``airplane_kernel``: within a few ulp of
        numpy's). Loads numba on the first call: for searches that fly many partial routes."""
        from gcs_planner.geometry.airplane_kernel import airplane_lengths, airplane_lengths_each

        if self.envelope is not None:
            env = self.envelope
            ends = np.ascontiguousarray(ends, dtype=float)
            r, c, d = env.of_legs(float(start[2]), ends[:, 2])
            return airplane_lengths_each(
                np.asarray(start, dtype=float), np.asarray(heading, dtype=float), ends,
                r, c, d, float(self.run_in), float(self.run_out),
                env.airspeeds(float(start[2]), ends[:, 2]), env.wind_vector,
            )  # fmt: skip
        return airplane_lengths(
            start, heading, ends, self.radius, slope_tan(self.max_climb_angle),
            slope_tan(self.max_descent_angle), float(self.run_in), float(self.run_out),
        )  # fmt: skip

    def lower_bounds(self, start, ends):
        if self.envelope is not None:
            # each leg within the limits of its own highest point, as it is flown (and in a
            # wind of a stated direction as steep as any track between its ends may climb)
            env = self.envelope
            z0, z1 = float(np.asarray(start)[2]), np.asarray(ends, dtype=float)[:, 2]
            r, c, d = env.of_legs(z0, z1)
            f = env.bound_factor(np.asarray(ends) - np.asarray(start), env.airspeeds(z0, z1), c, d)
            return self._bounds_tan(start, ends, c * f, d * f)
        return lower_bounds(start, ends, self.max_climb_angle, self.max_descent_angle, self.radius)

    def arc_bounds(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """``lower_bounds`` of the legs from each row of ``starts`` to the same row of
        ``ends`` (the reach graph's arcs, a block at a time)."""
        starts = np.asarray(starts, dtype=float)
        ends = np.asarray(ends, dtype=float)
        if self.envelope is not None:
            env = self.envelope
            r0, c0, d0 = env.at(starts[:, 2])
            r1, c1, d1 = env.at(ends[:, 2])
            v = np.maximum(env.airspeed_at(starts[:, 2]), env.airspeed_at(ends[:, 2]))
            c, d = np.minimum(c0, c1), np.minimum(d0, d1)
            f = env.bound_factor(ends - starts, v, c, d)
            c, d = c * f, d * f
        else:
            c, d = slope_tan(self.max_climb_angle), slope_tan(self.max_descent_angle)
        return self._bounds_tan(np.zeros(3), ends - starts, c, d)

    def walk_bounds(self, start: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """A lower bound of every walk from ``start`` to each row of ``ends``, whatever points
        it passes through: the straight leg within the most permissive limits any leg has (the
        lowest point's, with a per-leg envelope), never inf. Sums of leg bounds along a walk
        are at least this (it is subadditive), which direct bounds to B rely on."""
        if self.envelope is not None:
            _, c, d = self.envelope.bounds()
        else:
            c, d = slope_tan(self.max_climb_angle), slope_tan(self.max_descent_angle)
        return lower_bounds_tan(start, ends, c, d, math.inf)

    def _bounds_tan(self, start, ends, tan_climb, tan_descent) -> np.ndarray:
        # (R only says whether a too-steep straight leg is ruled out: R = 0, no helix.)
        return lower_bounds_tan(start, ends, tan_climb, tan_descent, self.radius)

    def leg(self, start, heading, end):
        return airplane_leg(
            start, heading, end, self.radius, self.max_climb_angle, self.max_descent_angle,
            self.run_in, self.run_out, self.envelope,
        )  # fmt: skip

    def relaxation(self) -> LegModel:
        """Legs whose flown length is this model's heading-free lower bound: a relaxation every
        route of this model is at least as long as, and at least as feasible under."""
        return BoundLegs(self)


@dataclass(frozen=True)
class BoundLegs:
    """The heading-free relaxation of a model: each leg as long as the model's lower bound."""

    model: LegModel
    name: str = "bound"
    radius: float = 0.0
    carries_heading: bool = False
    turns_in_bounds: bool = False

    @property
    def chord_bounds(self) -> bool:
        return self.model.chord_bounds

    def kernel_legs(self) -> KernelLegs | None:
        return None  # heading-free

    def lengths(self, start, heading, ends):
        return self.model.lower_bounds(start, ends), None

    def lower_bounds(self, start, ends):
        return self.model.lower_bounds(start, ends)

    def leg(self, start, heading, end):
        raise NotImplementedError("a relaxation has no flown geometry")

    def relaxation(self) -> LegModel:
        return self


def leg_model_of(
    radius: float,
    leg_model: str = "airplane",
    max_climb_angle: float = 90.0,
    max_descent_angle: float = 90.0,
    approach: float = 0.0,
    departure: float = 0.0,
    envelope: LegEnvelope | None = None,
) -> LegModel:
    """The leg model a scenario plans with. R = 0 is straight legs (airplane: within the climb
    limits, a too-steep leg infeasible); cs3d ignores the climb limits. ``approach`` and
    ``departure`` (the run-in and run-out, metres) shape airplane legs with turns only: straight
    legs carry no heading to run out on, and cs3d is kept as it was published."""
    unlimited = max_climb_angle >= 90.0 and max_descent_angle >= 90.0
    if leg_model == "cs3d":
        return CS3DLegs(radius) if radius > 0 else StraightLegs()
    if leg_model != "airplane":
        raise ValueError(f"unknown leg model {leg_model!r}")
    if radius <= 0 and unlimited:
        return StraightLegs()
    if radius <= 0:
        approach = departure = 0.0
    return AirplaneLegs(
        radius, max_climb_angle, max_descent_angle, float(approach), float(departure),
        envelope=envelope if radius > 0 else None,
    )  # fmt: skip


def scenario_leg_model(scenario) -> LegModel:  # noqa: ANN001 - Scenario, no import cycle
    """The leg model of ``scenario`` (its turning radius, leg model, climb limits, the straight
    run-in and run-out at every landmark, and with an envelope derived from the autopilot's
    terms, each leg's limits from its own altitude)."""
    p = scenario.params
    return leg_model_of(
        p.turn_radius, scenario.leg_model, p.max_climb_angle, p.max_descent_angle,
        p.approach, p.departure, leg_envelope(scenario),
    )  # fmt: skip


def leg_envelope(scenario) -> LegEnvelope | None:  # noqa: ANN001 - Scenario
    """Each leg's envelope: from the altitude of its highest point, for the parts of the
    scenario's envelope derived from the autopilot's terms (``DerivedEnvelope.per_leg``: the
    radius when derived from the bank, the angles when derived from the rates), and in a design
    wind of a stated direction the angles along its own track (``DerivedEnvelope.along_track``).
    A part stated directly (``--turn-radius``, ``--max-climb-angle``, ...) stays one for every
    leg. None when nothing varies per leg (or the legs are straight)."""
    env = getattr(scenario, "envelope", None)
    p = scenario.params
    if env is None or p.turn_radius <= 0 or scenario.leg_model != "airplane":
        return None
    along = bool(getattr(env, "along_track", False))
    if not env.per_leg and not along:
        return None
    base = scenario.origin.alt if scenario.origin else 0.0
    # The angles from the rates: per leg, or along the track at the scenario's highest point.
    rates = along or "max_climb_angle" in env.per_leg
    return LegEnvelope(
        eas=float(env.eas),
        wind=float(env.wind),
        base_altitude=float(base),
        lowest=float(scenario.xyz[:, 2].min()),
        radius=float(p.turn_radius),
        climb_deg=float(p.max_climb_angle),
        descent_deg=float(p.max_descent_angle),
        tan_bank=math.tan(math.radians(env.bank_deg)) if "turn_radius" in env.per_leg else 0.0,
        climb_rate=float(env.climb_rate) if rates else math.nan,
        sink_rate=float(env.sink_rate) if rates else math.nan,
        angles_at=None if "max_climb_angle" in env.per_leg else float(scenario.xyz[:, 2].max()),
        wind_from=env.wind_from if along else None,
    )


def path_angle_deg(leg: FlownLeg) -> float:
    """Flight-path angle of a flown leg in degrees (positive climbing). An airplane leg has one
    angle throughout; a CS leg's angle varies along its tilted arc, and the steepest one is given
    (the one a climb limit must admit)."""
    if isinstance(leg, AirplaneLeg):
        return leg.path_angle
    if not leg.reachable:
        return math.nan
    z = [float(leg.heading_in[2]), float(leg.heading_out[2])]
    if leg.normal is not None and leg.arc_angle > 0:
        a = np.linspace(0.0, leg.arc_angle, 65)
        z.extend((np.cos(a) * leg.heading_in[2] + np.sin(a) * leg.normal[2]).tolist())
    if leg.arc_angle == 0 and leg.length > 0:  # a chord: its own direction
        z = [float((leg.end[2] - leg.start[2]) / leg.length)]
    steepest = max(z, key=abs)
    return math.degrees(math.asin(max(-1.0, min(1.0, steepest))))
