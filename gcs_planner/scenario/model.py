"""The scenario: points, their kinds, and the parameters of the INS error model.

Everything downstream (search, export, mock vehicle) reads a :class:`Scenario`; nothing in it
knows which file format it came from.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from enum import IntEnum

import numpy as np

from gcs_planner.aircraft.profile import (
    DEFAULT_CAPTURE_RADIUS_M,
    DEFAULT_CRUISE_AIRSPEED,
    DEFAULT_ERROR_UNIT_M,
    DEFAULT_LEG_MODEL,
    DerivedEnvelope,
    VehicleProfile,
)
from gcs_planner.aircraft.reserve import DerivedReserve


class Kind(IntEnum):
    """Kind of a scenario point. The integer codes are what ``Scenario.kind`` stores."""

    A = 0  # start
    B = 1  # end
    V = 2  # vertical-error correction point
    H = 3  # horizontal-error correction point


# Names of the parameters as they appear in scenario files, flags and the plan JSON.
PARAMETER_NAMES = ("alpha1", "alpha2", "beta1", "beta2", "theta", "delta")


@dataclass(frozen=True)
class Parameters:
    """The model's parameters (docs/model.md, "Scenario"). Error limits are in error units.

    ``turn_radius`` 0 means straight legs. ``p_success`` and ``fail_residual`` only matter at
    points flagged unreliable.
    """

    alpha1: float
    alpha2: float
    beta1: float
    beta2: float
    theta: float
    delta: float
    turn_radius: float = 200.0
    p_success: float = 0.8
    fail_residual: float = 5.0
    # Largest climb and descent (flight-path) angles in degrees; 90 = unlimited (docs/model.md,
    # "Airplane legs"). Only the airplane leg model plans with them.
    max_climb_angle: float = 90.0
    max_descent_angle: float = 90.0
    # Flight reserve in metres: plan so that every error stays within its limit even when the
    # aircraft flies this much more than planned between two resets of that error (an aircraft
    # under its autopilot never flies the planned legs exactly: it enters turns late and leaves
    # loiters where its guidance does). 0 is the model of docs/model.md as it stands.
    reserve: float = 0.0
    # Straight at every landmark (docs/model.md): with turns, each leg arrives at its point on a
    # tangent of at least ``approach`` metres and the next one leaves it ``departure`` metres
    # straight on before it turns (horizontal metres, flown and counted in the errors), so that
    # an autopilot that starts its turns early still overflies the landmark. 0 is the contest's
    # model; derived from the autopilot when the envelope is (vehicle.DerivedEnvelope).
    approach: float = 0.0
    departure: float = 0.0

    def validate(self) -> list[str]:
        """Return the names of invalid parameters with why, empty when all are valid."""
        bad: list[str] = []
        for name in PARAMETER_NAMES:
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                bad.append(f"{name} must be a finite number > 0 (got {value!r})")
        if not math.isfinite(self.turn_radius) or self.turn_radius < 0:
            bad.append(f"turn_radius must be a finite number >= 0 (got {self.turn_radius!r})")
        if not math.isfinite(self.p_success) or not 0.0 <= self.p_success <= 1.0:
            bad.append(f"p_success must lie in [0, 1] (got {self.p_success!r})")
        if not math.isfinite(self.fail_residual) or self.fail_residual < 0:
            bad.append(f"fail_residual must be a finite number >= 0 (got {self.fail_residual!r})")
        for name in ("max_climb_angle", "max_descent_angle"):
            value = getattr(self, name)
            if not math.isfinite(value) or not 0.0 < value <= 90.0:
                bad.append(f"{name} must lie in (0, 90] degrees (got {value!r})")
        for name in ("approach", "departure"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                bad.append(f"{name} must be a finite number >= 0 metres (got {value!r})")
        if bad:
            return bad  # the reserve is judged against valid limits only
        tightest = min(getattr(self, k) for k in PARAMETER_NAMES[:5]) / self.delta
        if not math.isfinite(self.reserve) or not 0.0 <= self.reserve < tightest:
            bad.append(
                f"reserve must lie in [0, {tightest:g}) metres, below the tightest limit in "
                f"metres flown (got {self.reserve!r})"
            )
        return bad

    # Limits in metres of flight: the search works in metres flown since the last reset of a
    # component, so that comparing against a limit needs no multiplication by delta.
    def limits_m(self, kind: Kind) -> tuple[float, float]:
        """(vertical, horizontal) arrival limits at a point of ``kind``, in metres flown as
        planned since the last reset: the limit over delta, less the reserve. Every check is
        linear in those metres and a failed correction only clips them, so a flight that flies
        at most ``reserve`` metres more than planned between two resets keeps every limit."""
        reserve = self.reserve
        if kind == Kind.V:
            return self.alpha1 / self.delta - reserve, self.alpha2 / self.delta - reserve
        if kind == Kind.H:
            return self.beta1 / self.delta - reserve, self.beta2 / self.delta - reserve
        if kind == Kind.B:
            return self.theta / self.delta - reserve, self.theta / self.delta - reserve
        return math.inf, math.inf

    @property
    def residual_m(self) -> float:
        """The residual after a failed correction, in metres flown: one place, so every failed
        correction clips to the very same float."""
        return self.fail_residual / self.delta

    def flown(self) -> Parameters:
        """The same parameters without the reserve: what the aircraft is held to in flight."""
        return replace(self, reserve=0.0)

    def limits(self, kind: Kind) -> tuple[float, float]:
        """(vertical, horizontal) arrival limits at a point of ``kind``, in error units."""
        if kind == Kind.V:
            return self.alpha1, self.alpha2
        if kind == Kind.H:
            return self.beta1, self.beta2
        if kind == Kind.B:
            return self.theta, self.theta
        return math.inf, math.inf

    @property
    def reach_m(self) -> float:
        """Longest leg any feasible route can contain, in metres."""
        limits = (self.alpha1, self.alpha2, self.beta1, self.beta2, self.theta)
        return max(limits) / self.delta - self.reserve

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class Origin:
    """Georeference of the local frame: WGS84 latitude, longitude (degrees), altitude (m AMSL)."""

    lat: float
    lon: float
    alt: float = 0.0


@dataclass(frozen=True, eq=False)
class Scenario:
    """Points in a local Cartesian frame (metres; x east, y north, z up) and the parameters.

    Index 0..n-1 addresses the arrays; ``ids`` are the identifiers of the source file, which is
    how routes are reported to users.
    """

    ids: tuple[str, ...]
    xyz: np.ndarray  # (n, 3) float64
    kind: np.ndarray  # (n,) uint8, Kind codes
    unreliable: np.ndarray  # (n,) bool
    params: Parameters
    name: str = "scenario"
    source: str = ""
    origin: Origin | None = None
    heading_at_a: tuple[float, float, float] | None = None
    # The aircraft beyond the planning parameters: which leg model plans with the turning
    # radius, its cruise airspeed, and where the radius came from (see ``vehicle``).
    leg_model: str = DEFAULT_LEG_MODEL
    cruise_airspeed: float = DEFAULT_CRUISE_AIRSPEED
    radius_source: str = "turn_radius"
    # The envelope derived from the autopilot's terms and the design wind (None: the angles
    # and radius were stated directly, or assumed).
    envelope: DerivedEnvelope | None = None
    # Where params.reserve came from: "stated" (a flag or the scenario file), "default" (the
    # reader's constant for airplane legs, vehicle.DEFAULT_RESERVE_M), "derived" (from what it
    # must cover: ``reserve_basis``, with the envelope) or "" (none: straight and cs3d legs).
    reserve_source: str = ""
    reserve_basis: DerivedReserve | None = None
    # Metres of position error per error unit (Table 2's decimetres) and the landmarks'
    # capture radius (3D, metres): the planner's capture check reads them.
    error_unit: float = DEFAULT_ERROR_UNIT_M
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
    # The errors the aircraft carries at A, as metres flown since the last vertical and
    # horizontal reset (the probability model's units): (0, 0) at a mission's start; a state
    # after a failed fix when planning from it (docs/model.md, "Contingency policies").
    initial_errors: tuple[float, float] = (0.0, 0.0)
    # The minutes of flight the aircraft has (``--endurance``, ``[vehicle] endurance``): the
    # planner keeps only routes whose flight time in the design wind is within it (None: any).
    endurance: float | None = None
    # Per point, the vertical allowance (m) of a capture there for the design turbulence
    # (core/capture_front.py; None: no turbulence planned for, captures not constrained).
    capture_vertical: tuple[float, ...] | None = None
    _index: dict[str, int] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_index", {pid: i for i, pid in enumerate(self.ids)})
        v0, h0 = (float(e) for e in self.initial_errors)
        if not (math.isfinite(v0) and math.isfinite(h0) and v0 >= 0.0 and h0 >= 0.0):
            raise ValueError(f"initial errors must be finite and >= 0 m, not {self.initial_errors}")
        object.__setattr__(self, "initial_errors", (v0, h0))

    @property
    def from_rest(self) -> bool:
        """Whether the aircraft starts with no error (a mission's start, not a state mid-way)."""
        return self.initial_errors == (0.0, 0.0)

    @property
    def vehicle(self) -> VehicleProfile:
        """The aircraft's flight envelope as the planner, exporter and mock vehicle use it."""
        p = self.params
        return VehicleProfile(
            turn_radius=p.turn_radius,
            max_climb_angle=p.max_climb_angle,
            max_descent_angle=p.max_descent_angle,
            cruise_airspeed=self.cruise_airspeed,
            leg_model=self.leg_model,
            radius_source=self.radius_source,
            approach=p.approach,
            departure=p.departure,
        )

    def with_vehicle(self, **changes: object) -> Scenario:
        """A copy with the leg model, cruise airspeed or radius source changed."""
        return replace(self, **changes)

    @property
    def n(self) -> int:
        return len(self.ids)

    @property
    def start(self) -> int:
        return int(np.flatnonzero(self.kind == Kind.A)[0])

    @property
    def end(self) -> int:
        return int(np.flatnonzero(self.kind == Kind.B)[0])

    def index_of(self, point_id: str | int) -> int:
        """Index of the point with identifier ``point_id`` (KeyError if unknown)."""
        return self._index[str(point_id)]

    def subset(self, indices: np.ndarray) -> Scenario:
        """The scenario over the points at ``indices`` (in that order; A and B among them)."""
        idx = np.asarray(indices, dtype=np.int64)
        return replace(
            self,
            ids=tuple(self.ids[i] for i in idx),
            xyz=self.xyz[idx],
            kind=self.kind[idx],
            unreliable=self.unreliable[idx],
        )

    def with_params(self, **changes: float) -> Scenario:
        """A copy with some parameters changed (flags override file values this way)."""
        return replace(self, params=replace(self.params, **changes))

    def counts(self) -> dict[str, int]:
        return {
            "points": self.n,
            "V": int(np.sum(self.kind == Kind.V)),
            "H": int(np.sum(self.kind == Kind.H)),
            "unreliable": int(np.sum(self.unreliable)),
        }


def altitude_of(scenario: Scenario) -> Callable[[str], float]:
    """A point's altitude above sea level (m) by its id, as the envelope's TAS takes it."""
    base = scenario.origin.alt if scenario.origin else 0.0
    return lambda point_id: float(scenario.xyz[scenario.index_of(point_id), 2]) + base
