"""The dry run's report: what the upload, the flight and its runs came to
(:class:`DryRunReport`, its verdict and its JSON), put together from the upload's outcome and
the flight (:func:`build_report`).

The report's fields are flat, in the order its JSON has always had them; a report of a mission
that never verified (so never flew) says only what the upload did.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from gcs_planner.aircraft.envelope_fit import LegShortfall
from gcs_planner.dryrun.flight import (
    DEVIATION_STEP_M,
    DryRunRow,
    Flight,
    LostRunRow,
    as_planned,
    lost_runs_of,
    max_deviation,
    never_started,
    rows_of,
    seeded_flight_lost,
    stretch_overrun,
)
from gcs_planner.dryrun.reasons import plan_assumptions, why
from gcs_planner.dryrun.upload import UploadOutcome
from gcs_planner.dryrun.world import DRY_RUN_ACCEPTANCE_RADIUS_M, DryRunSettings, DryRunWorld
from gcs_planner.mission.builder import Mission
from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.items import HELIX_COMMANDS
from gcs_planner.sim import replay as replay_mod


@dataclass(frozen=True)
class DryRunReport:
    scenario: str
    flavour: str
    route: tuple[str, ...]  # planned point ids, A..B
    verified: bool
    link_error: str  # why the upload did not verify ("" when it did)
    upload_attempts: int
    upload_errors: tuple[str, ...]  # of the attempts that failed, in order
    items: int
    upload_seconds: float
    resends: int
    messages_dropped: int
    loss: float
    seed: int
    arrived: bool
    lost_reason: str
    why: str  # where and which limit, when not arrived
    flown_length: float  # to B, or to where the vehicle was lost
    mission_length: float  # of the stored mission's path to B, whatever the draw
    planned_length: float
    arc_length: float
    waypoints: int
    length_tolerance: float
    rows: tuple[DryRunRow, ...]
    corrections_as_planned: bool  # the path meets the planned points, in order, and no other
    v_at_b: float
    h_at_b: float
    theta: float
    planned_probability: float
    flown_to_b: float = 0.0  # the flown track to its closest approach to B (or its loss before)
    flight_seconds: float = 0.0
    flight_ended: str = ""
    max_deviation: float = 0.0  # largest 3D distance of the flown track from the mission's path
    max_deviation_at: float = 0.0  # flown from A, metres
    acceptance_radius: float = DRY_RUN_ACCEPTANCE_RADIUS_M
    capture_radius: float = 0.0
    flight_notes: tuple[str, ...] = ()
    helices: int = 0  # loiter items of the mission (the planner's helices)
    runs: int = 0
    success_rate: float | None = None
    success_ci: tuple[float, float] | None = None
    confidence: float | None = None
    # The plan's flight reserve, and the most the flight flew beyond the plan between two
    # corrections of the same error (what the reserve must cover); None when no stretch of the
    # route was flown from end to end.
    reserve: float = 0.0
    max_overrun: float | None = None
    # The flight's world: the wind flown, the autopilot's limits, whether the aircraft steered
    # its INS estimate, and what the plan assumed that the flight does not (unlimited climb,
    # still air).
    wind: str = "still air"
    autopilot: str = ""
    navigate_on_estimate: bool = False
    assumptions: tuple[str, ...] = ()
    # Runs lost by the flight (a missed landmark, or lost where the plan flown as planned
    # with the same correction outcomes arrives: ``lost_by_the_flight``) and by failed
    # corrections; the seeded flight's own verdict.
    flight_losses: int = 0
    correction_losses: int = 0
    runs_flown: bool = False  # each run flown on its own (wind, gusts, estimate drawn per run)
    flight_lost: bool = False  # the seeded flight was lost by the flight
    # Every lost run of the Monte Carlo: where and why, what it missed and where its
    # corrections failed before, and whether it counts as lost by the flight.
    lost_runs: tuple[LostRunRow, ...] = ()
    # The flight model (sim/jsbsim_airframe.py with --flight-model jsbsim), what it found
    # before the flight that the airframe cannot fly (where and why: the mission cannot be
    # flown as planned) and what it could not hold in flight.
    flight_model: str = "point mass"
    airframe_limits: tuple[str, ...] = ()
    airframe_shortfalls: tuple[str, ...] = ()
    # Checked before the flight (gcs_planner/aircraft/envelope_fit.py): every leg that does not fit
    # the plan's aircraft's envelope in the wind flown (``envelope_wind`` m/s, any direction), with
    # what it needs and what the aircraft can do; None when the plan states no aircraft in
    # the autopilot's terms (no envelope to derive: the flight is the only judge).
    envelope_shortfalls: tuple[LegShortfall, ...] = ()
    envelope_wind: float | None = None
    # the flown wind's direction (degrees it blows from): the climbs are checked along each
    # leg's track; None: from any direction
    envelope_wind_from: float | None = None
    # The plan's vehicle setup (``mission.vehicle_setup``) as set on the vehicle ("NAME=VALUE";
    # empty when the vehicle flew as it is), and what the vehicle's parameters fell short of
    # it when it flew (the first cause of a loss when the vehicle was not set up).
    setup: tuple[str, ...] = ()
    vehicle_as_is: bool = False
    setup_shortfalls: tuple[str, ...] = ()
    # The aircraft's endurance (minutes; None: unlimited) and the runs that were lost by the
    # flight because it ran out before B (the low-battery failsafe ended the mission).
    endurance: float | None = None
    endurance_losses: int = 0

    @property
    def demonstration(self) -> bool:
        """Without runs the one seeded flight shows what can happen; it is no verdict."""
        return self.runs == 0

    @property
    def length_difference(self) -> float:
        return self.mission_length - self.planned_length

    @property
    def length_within_tolerance(self) -> bool | None:
        """The stored mission's chords against the planned length; None when the mission has
        helices (loiters), which its chords cannot measure (the flight does)."""
        if self.helices:
            return None
        return abs(self.length_difference) <= self.length_tolerance

    @property
    def probability_within_ci(self) -> bool | None:
        """The Monte Carlo agrees with the plan: the planned probability within the interval;
        with a flight reserve the plan's probability is a floor (held to limits lowered by the
        reserve), so the promise is kept when it is not above the interval."""
        if self.success_ci is None:
            return None
        low, high = self.success_ci
        if self.reserve > 0:
            return self.planned_probability <= high
        return low <= self.planned_probability <= high

    @property
    def flown_difference(self) -> float:
        return self.flown_to_b - self.planned_length

    @property
    def missed(self) -> tuple[DryRunRow, ...]:
        return tuple(r for r in self.rows if r.outcome == "missed")

    @property
    def ok(self) -> bool:
        """The verdict: verified, and with runs no run lost by the flight and the success rate
        consistent with the planned probability; without runs (a demonstration) the seeded
        flight arrived."""
        # A plan whose legs do not fit the envelope in the wind flown fails whatever the runs
        # drew: the runs fly the legs they reach in the directions they drew, and a shortfall
        # they survive is survived on the flight reserve and the capture radius, which the plan
        # keeps for what it cannot foresee (dataset 2's still-air plan in 5 m/s: issue 32).
        if not self.verified or self.airframe_limits or self.envelope_shortfalls:
            return False
        if self.runs == 0:
            return self.arrived
        return self.flight_losses == 0 and bool(self.probability_within_ci)

    def to_dict(self) -> dict:
        out = asdict(self)
        if not self.verified:
            # Nothing flew: no flight, no rate, no losses to speak of.
            out = {k: out[k] for k in _UPLOAD_KEYS}
            out["route"] = list(self.route)
            out["ok"] = False
            out["flown"] = False
            return out
        out["flown"] = True
        out["route"] = list(self.route)
        out["length_difference"] = self.length_difference
        out["length_within_tolerance"] = self.length_within_tolerance
        out["ok"] = self.ok
        out["demonstration"] = self.demonstration
        # A missed landmark has no errors on arrival: null, not NaN (JSON has no NaN).
        out["rows"] = [
            {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}
            for row in out["rows"]
        ]
        out["flown_difference"] = self.flown_difference
        if self.runs > 0:
            out["success_ci"] = list(self.success_ci or ())
            out["probability_within_ci"] = self.probability_within_ci
        else:
            for key in ("success_rate", "success_ci", "confidence"):
                del out[key]
        return out


# What a report of a mission that never verified (and so never flew) says.
_UPLOAD_KEYS = (
    "scenario", "flavour", "route", "verified", "link_error", "upload_attempts",
    "upload_errors", "items", "upload_seconds", "resends", "messages_dropped", "loss", "seed",
    "planned_length", "planned_probability", "setup", "vehicle_as_is",
)  # fmt: skip


def length_tolerance(arc_length: float, waypoints: int) -> float:
    """How far the flown length may be from the planned one (sim/replay.py): chords under the
    densified arcs are short by at most ``CHORD_SHORTFALL`` of the arc, and each waypoint's
    degE7 position moves it by at most ``QUANTISATION_M``."""
    return replay_mod.CHORD_SHORTFALL * arc_length + replay_mod.QUANTISATION_M * waypoints


def build_report(
    world: DryRunWorld,
    settings: DryRunSettings,
    plan_dict: dict,
    mission: Mission,
    uploaded: UploadOutcome,
    flight: Flight,
    dropped: int,
) -> DryRunReport:
    """The report of a dry run: ``uploaded`` (``dropped``: the messages the vehicle's link
    dropped, both ways) and the ``flight`` of the mission the vehicle stored, set against
    ``world``'s plan (``plan_dict``: its plan JSON; ``mission``: the items exported)."""
    rows = rows_of(flight.replayed, world.plan.route)
    return DryRunReport(
        **_upload_fields(world, settings, mission, uploaded, dropped),
        **_flight_fields(world, settings, plan_dict, mission, flight, rows),
        **_runs_fields(world, settings, flight),
        **_world_fields(world, flight),
        **_airframe(flight.replayed),
    )


def _upload_fields(
    world: DryRunWorld,
    settings: DryRunSettings,
    mission: Mission,
    uploaded: UploadOutcome,
    dropped: int,
) -> dict:
    """What the upload did (the fields of a report of a mission that never verified)."""
    route = world.plan.route
    return {
        "scenario": world.landmarks.name,
        "flavour": world.flavour,
        "route": tuple(route.ids()),
        "verified": uploaded.verified,
        "link_error": "" if uploaded.verified else uploaded.errors[-1],
        "upload_attempts": uploaded.attempts,
        "upload_errors": uploaded.errors,
        "items": len(mission.items),
        "upload_seconds": uploaded.seconds,
        "resends": uploaded.resends,
        "messages_dropped": dropped,
        "loss": settings.loss,
        "seed": settings.seed,
        "planned_length": route.length,
        "planned_probability": route.probability,
        "setup": tuple(f"{n.name}={n.set_to:g}" for n in uploaded.setup),
        "vehicle_as_is": world.vehicle_as_is,
    }


def _flight_fields(
    world: DryRunWorld,
    settings: DryRunSettings,
    plan_dict: dict,
    mission: Mission,
    flight: Flight,
    rows: list[DryRunRow],
) -> dict:
    """The seeded flight: where it went, how far it strayed from the plan, what it met."""
    replayed = flight.replayed
    route = world.plan.route
    planned = list(dict.fromkeys(s.id for s in route.stops[1:-1]))
    dev, dev_at = max_deviation(replayed, trajectory_local(plan_dict, step=DEVIATION_STEP_M))
    arcs = sum(s.leg.arc for s in route.stops if s.leg is not None)
    flown = replayed.flight
    return {
        "arrived": replayed.arrived,
        "lost_reason": replayed.run.lost_reason,
        "why": why(replayed, [r for r in rows if r.outcome == "missed"]),
        "flown_length": replayed.flown_length,
        "mission_length": replayed.mission_length,
        "arc_length": arcs,
        "waypoints": replayed.waypoints,
        "length_tolerance": length_tolerance(arcs, replayed.waypoints),
        "rows": tuple(rows),
        # The landmarks the path meets do not depend on the draw, only their outcomes do.
        "corrections_as_planned": as_planned(
            [e.id for e in replayed.encounters], planned, replayed
        ),
        "v_at_b": replayed.run.v_at_end,
        "h_at_b": replayed.run.h_at_end,
        "theta": replayed.theta,
        "flown_to_b": replayed.flown.length if replayed.flown is not None else 0.0,
        "flight_seconds": replayed.flight_time_s,
        "flight_ended": flown.ended if flown is not None else "",
        "max_deviation": dev,
        "max_deviation_at": dev_at,
        "acceptance_radius": float(settings.acceptance_radius),
        "capture_radius": world.capture_radius,
        "flight_notes": flown.notes if flown is not None else (),
        # the helices' loiters; the last item (the end action) is not one of them
        "helices": sum(it.command in HELIX_COMMANDS for it in mission.items[:-1]),
        "reserve": world.plan.scenario.params.reserve,
        "max_overrun": stretch_overrun(
            route, rows, replayed.flown.length if replayed.arrived and replayed.flown else None
        ),
    }


def _runs_fields(world: DryRunWorld, settings: DryRunSettings, flight: Flight) -> dict:
    """The Monte Carlo's runs (none without ``runs``) and the seeded flight's own loss."""
    replayed = flight.replayed
    route, params = world.plan.route, world.plan.scenario.params
    mc = replayed.monte_carlo
    lost_runs = lost_runs_of(replayed, route, params)
    flight_losses = sum(r.by_the_flight for r in lost_runs)
    return {
        "runs": settings.runs,
        "success_rate": None if mc is None else mc.success_rate,
        "success_ci": None if mc is None else (mc.ci_low, mc.ci_high),
        "confidence": None if mc is None else mc.confidence,
        "flight_losses": flight_losses,
        "endurance_losses": sum(r.out_of_endurance for r in lost_runs),
        "correction_losses": (
            0 if mc is None or never_started(replayed) else mc.runs - mc.successes - flight_losses
        ),
        "runs_flown": False if mc is None else mc.flown,
        "flight_lost": seeded_flight_lost(replayed, route, params),
        "lost_runs": lost_runs,
    }


def _world_fields(world: DryRunWorld, flight: Flight) -> dict:
    """The flight's world, what the plan assumed that it does not, and what the plan's legs and
    setup fall short of in it."""
    return {
        "wind": world.air.describe(),
        "autopilot": flight.autopilot.describe(),
        "navigate_on_estimate": world.navigate_on_estimate,
        "assumptions": plan_assumptions(world.plan, world.wind),
        "envelope_shortfalls": flight.envelope_shortfalls,
        "envelope_wind": flight.flown_wind if world.plan.scenario.envelope is not None else None,
        "envelope_wind_from": world.air.from_deg,
        "setup_shortfalls": tuple(sh.describe() for sh in flight.setup_shortfalls),
        "endurance": world.endurance,
    }


def _airframe(replayed: replay_mod.ReplayReport) -> dict:
    """The flight model's fields of the report."""
    flight = replayed.flight
    if flight is None:
        return {}
    return {
        "flight_model": flight.flight_model,
        "airframe_limits": flight.limits,
        "airframe_shortfalls": flight.shortfalls,
    }
