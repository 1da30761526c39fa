"""The dry run's words for its findings: why the vehicle was lost (where, which limit broke and
by how much, what the flight missed on the way) and what the plan assumed of the aircraft that
the flight does not give it."""

from __future__ import annotations

from gcs_planner.core.planner import Plan
from gcs_planner.dryrun.flight import DryRunRow
from gcs_planner.sim import replay as replay_mod
from gcs_planner.sim.wind import WindSpec


def plan_assumptions(plan: Plan, wind: WindSpec | None = None) -> tuple[str, ...]:
    """What the plan assumed of the aircraft that the flight does not give it."""
    v = plan.scenario.vehicle
    out = []
    if not v.climb_limited:
        out.append(
            "the plan assumed unlimited climb and descent (90 deg, the contest's model); the "
            "aircraft climbs and sinks at its autopilot's rates"
        )
    if v.turn_radius <= 0:
        out.append("the plan assumed turns on the spot (R = 0): so does this flight")
    flown = "" if wind is None or wind.still else f"; this flight: {wind.describe()}"
    env = plan.scenario.envelope
    if env is not None and env.wind > 0:
        where = (
            f"from {env.wind_from:g} deg only (each leg along its own track)"
            if env.along_track
            else "from any direction"
        )
        out.append(f"the plan's envelope holds in a design wind of {env.wind:g} m/s {where}{flown}")
    else:
        out.append(f"the plan assumed still air{flown}")
    if env is None and wind is not None and wind.speed > 0:
        out.append(
            "the plan states no aircraft in the autopilot's terms (rates, bank, airspeed): its "
            "legs are not checked against the envelope in the wind flown; the flight judges"
        )
    if env is not None:
        each = (
            "; each leg at the TAS of its own highest point, down to "
            f"{env.tas_low:.1f} m/s at {env.lowest_altitude:.0f} m"
            if env.per_leg
            else ""
        )
        out.append(
            f"the plan took {env.eas:g} m/s EAS as {env.tas:.1f} m/s TAS at "
            f"{env.altitude:.0f} m (ISA, the highest point){each}"
        )
    else:
        out.append(
            f"the plan assumed {v.cruise_airspeed:g} m/s over the air; the aircraft holds it "
            "as EAS and flies faster at altitude (ISA)"
        )
    return tuple(out)


def why(report: replay_mod.ReplayReport, missed: list[DryRunRow] | None = None) -> str:
    """Why the flight did not arrive ("" if it did): what the airframe cannot fly, else where
    the vehicle was lost and the corrections it missed."""
    limits = report.flight.limits if report.flight is not None else ()
    if limits:
        more = f" (and {len(limits) - 1} more)" if len(limits) > 1 else ""
        return f"the airframe cannot fly the mission: {limits[0]}{more}"
    return _why_flown(report, missed)


def _why_flown(report: replay_mod.ReplayReport, missed: list[DryRunRow] | None = None) -> str:
    """Where the vehicle was lost and which limit broke, with the numbers, and the corrections
    the flight missed on the way ("" if it arrived)."""
    run = report.run
    if run.arrived:
        return ""
    reason = _lost_reason(report)
    if missed:
        passes = ", ".join(
            f"{r.kind} point {r.point} (passed {r.miss:.1f} m away, {r.distance:,.0f} m from A)"
            for r in missed
        )
        reason += f"; the flight missed {passes}: outside the {report.capture_radius:g} m capture"
        reason += " radius"
    return reason


def _lost_reason(report: replay_mod.ReplayReport) -> str:
    run = report.run
    if run.corrections and not run.corrections[-1].within_limits:
        c = run.corrections[-1]
        broken = []
        if c.v_margin < 0:
            broken.append(f"vertical error {c.v_before:.3f} > limit {c.v_limit:g}")
        if c.h_margin < 0:
            broken.append(f"horizontal error {c.h_before:.3f} > limit {c.h_limit:g}")
        failed = [r.id for r in run.corrections if r.succeeded is False]
        cause = f" after the failed correction(s) at {', '.join(failed)}" if failed else ""
        return (
            f"lost at {c.kind} point {c.id}, {c.distance:,.1f} m from A: "
            f"{' and '.join(broken) or 'an error over its limit'}{cause}"
        )
    if not run.reached_b:
        return run.lost_reason or "the mission does not reach B"
    where = f"{run.flown_length:,.1f} m from A"
    broken = [
        f"{name} error {value:.3f} > theta {report.theta:g}"
        for name, value in (("vertical", run.v_at_end), ("horizontal", run.h_at_end))
        if value > report.theta
    ]
    failed = [r.id for r in run.corrections if r.succeeded is False]
    cause = f" after the failed correction(s) at {', '.join(failed)}" if failed else ""
    return f"lost at B, {where}: {' and '.join(broken) or 'an error over theta'}{cause}"
