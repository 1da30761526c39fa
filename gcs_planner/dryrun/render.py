"""The dry run's report as text: the verdict an operator acts on (:func:`safety_line`), why a
verdict failed (:func:`verdict_line`) and the whole report (:func:`render`): the upload, the
corrections met, the stored mission's length, the flight against the plan, the envelope in the
wind flown, the world flown and the success rate of the runs."""

from __future__ import annotations

from gcs_planner.dryrun.flight import LostRunRow
from gcs_planner.dryrun.report import DryRunReport
from gcs_planner.sim.guidance import ENDURANCE_ENDED
from gcs_planner.sim.replay import CHORD_SHORTFALL, QUANTISATION_M

# Runs lost by the flight named one by one in the text report (all of them in --json).
SHOWN_FLIGHT_LOSSES = 5
# Legs outside the envelope in the wind flown named one by one (all of them in --json).
SHOWN_ENVELOPE_SHORTFALLS = 8


def safety_line(r: DryRunReport, floor: float, allow_risky: bool) -> str:
    """The verdict an operator acts on, in one line: verified, flown, and the route's arrival
    probability against the planner's threshold."""
    if not r.verified:
        return "VERDICT: NOT VERIFIED: the upload failed; nothing flew"
    flown = "flown: " + ("OK" if r.ok else "FAILED (" + verdict_line(r) + ")")
    if r.demonstration:
        flown += " (one seeded flight: a demonstration, --runs N for a verdict)"
    p = r.planned_probability
    if p >= floor:
        odds = f"arrives with P {p:.4f} >= {floor:g} (--min-probability)"
    elif allow_risky:
        odds = f"RISKY: arrives with P {p:.4f} < {floor:g} (--min-probability), accepted by "
        odds += "--allow-risky"
    else:
        odds = f"RISKY: arrives with P {p:.4f} < {floor:g} (--min-probability)"
    good = r.ok and (p >= floor or allow_risky) and not r.demonstration
    head = "VERDICT: GO" if good else "VERDICT: NO GO"
    if r.ok and r.demonstration and (p >= floor or allow_risky):
        head = "VERDICT: DEMONSTRATION ONLY"
    return f"{head}: verified; {flown}; {odds}"


def verdict_line(r: DryRunReport) -> str:
    """Why the verdict failed, in one line."""
    if r.airframe_limits:
        return r.why
    parts = []
    if r.envelope_shortfalls:
        first = r.envelope_shortfalls[0]
        legs = len({s.leg for s in r.envelope_shortfalls})
        parts.append(
            f"{legs} leg(s) do not fit the aircraft's envelope in the {r.envelope_wind:g} m/s wind "
            f"flown (first: {first.describe()})"
        )
    if r.runs == 0:
        if not r.arrived:
            parts.append(f"lost: {r.why}")
            if r.setup_shortfalls:
                parts.append(_first_cause(r))
        return "; ".join(parts)
    if r.flight_losses:
        parts.append(f"{r.flight_losses} of {r.runs} runs lost by the flight")
    if r.endurance_losses:
        parts.append(
            f"{r.endurance_losses} of them out of the {r.endurance:g} min endurance before B"
        )
    if (r.flight_losses or r.missed) and r.setup_shortfalls:
        parts.append(_first_cause(r))
    if not r.probability_within_ci:
        parts.append("the success rate is not consistent with the planned probability")
    return "verdict failed: " + "; ".join(parts or ["see the report"])


def _first_cause(r: DryRunReport) -> str:
    """What the vehicle was not set up for, first of all (the setup's order: airspeed, then
    climb and sink, roll, loiters)."""
    return "first cause: the vehicle is not set up for the plan: " + r.setup_shortfalls[0]


def render(r: DryRunReport) -> str:
    """The whole report: the upload, then (when it verified) the setup, the corrections met,
    the stored mission's length, the flight, the world flown, the runs and the result."""
    out = _upload_lines(r)
    if not r.verified:
        return "\n".join(out)  # nothing flew: nothing more to say
    out += _setup_lines(r)
    out += ["", _table(r), ""]
    out += _flight_lines(r)
    out += _envelope_lines(r)
    out += _met_lines(r)
    out += _runs_lines(r)
    out += _notes(r)
    out.append(_result_line(r))
    return "\n".join(out)


def _upload_lines(r: DryRunReport) -> list[str]:
    """The dry run, its route, and what the upload did (each failed attempt's error)."""
    corrections = len(r.route) - 2
    out = [
        f"dry run of {r.scenario} on a mock {r.flavour} vehicle over UDP 127.0.0.1 "
        f"(loss {r.loss:g}, seed {r.seed})",
        f"route: {' '.join(r.route)} ({corrections} corrections, planned "
        f"{r.planned_length:,.1f} m, planned probability {r.planned_probability:.4f})",
    ]
    if r.verified:
        out.append(
            f"upload: {r.items} items, read back and equal (verified) in {r.upload_seconds:.2f} s"
            f", {r.resends} resends, {r.messages_dropped} messages dropped"
        )
    else:
        out.append(f"upload: NOT verified after {r.upload_attempts} attempt(s): {r.link_error}")
    for n, error in enumerate(r.upload_errors[: r.upload_attempts - 1 if r.verified else -1], 1):
        out.append(f"  attempt {n} failed: {error}")
    return out


def _setup_lines(r: DryRunReport) -> list[str]:
    """The vehicle setup set with the mission, and what the vehicle fell short of it."""
    out = []
    if r.vehicle_as_is:
        out.append("setup: none set: the vehicle flies at its own parameters (--vehicle-as-is)")
    elif r.setup:
        out.append(
            f"setup: the plan's vehicle setup set with the mission ({len(r.setup)} parameters: "
            + ", ".join(r.setup)
            + ")"
        )
    for short in r.setup_shortfalls:
        out.append(f"  NOT SET UP: {short}")
    return out


def _flight_lines(r: DryRunReport) -> list[str]:
    """The stored mission's length and the flight against the plan, its overrun, its notes and
    the flight model (with what the airframe could not fly or hold)."""
    within = "within" if r.length_within_tolerance else "OUTSIDE"
    if r.length_within_tolerance is None:
        within = f"not measured ({r.helices} helices: the chords skip them) against"
    out = [
        f"length: the stored mission flies {r.mission_length:,.1f} m from A to B, planned "
        f"{r.planned_length:,.1f} m: difference {r.length_difference:+.2f} m, {within} the "
        f"tolerance {r.length_tolerance:.2f} m ({CHORD_SHORTFALL:.3%} of {r.arc_length:,.1f} m "
        f"of arcs + {QUANTISATION_M * 100:g} cm x {r.waypoints} waypoints)",
        f"flight: {r.flavour} mode AUTO with the scenario's vehicle profile flies "
        f"{r.flown_to_b:,.1f} m to B in {r.flight_seconds / 60:.1f} min, planned "
        f"{r.planned_length:,.1f} m: difference {r.flown_difference:+.1f} m; largest deviation "
        f"from the planned path {r.max_deviation:.1f} m (3D), {r.max_deviation_at:,.0f} m from "
        f"A; acceptance radius {r.acceptance_radius:g} m, capture radius {r.capture_radius:g} m",
    ]
    if r.airframe_limits:
        # Refused before it started (sim/guidance.py fly): nothing flown, met or missed.
        out[-1] = (
            f"flight: NOT FLOWN: {r.flavour} refused the mission before the flight started "
            f"(the airframe cannot fly it: below); planned {r.planned_length:,.1f} m"
        )
    if r.endurance is not None:
        left = r.endurance - r.flight_seconds / 60
        judged = f"had {left:.1f} min to spare"
        if r.flight_ended == ENDURANCE_ENDED and not r.arrived:
            judged = "ran out of it before B (the low-battery failsafe ends the mission)"
        out.append(f"endurance: {r.endurance:g} min; this flight {judged}")
    if r.max_overrun is not None:
        covered = (
            "within the plan's flight reserve"
            if r.max_overrun <= r.reserve
            else "MORE than the plan's flight reserve"
        )
        out.append(
            f"overrun: at most {r.max_overrun:+,.1f} m flown beyond the plan between two "
            f"corrections of an error, {covered} of {r.reserve:,.0f} m"
        )
    for note in r.flight_notes:
        out.append(f"  note: {note}")
    if r.flight_model != "point mass":
        out.append(f"flight model: {r.flight_model}")
    else:
        # What the point mass cannot tell (docs/jsbsim.md, the cross-check's disagreements).
        out.append(
            "flight model: point mass (rolls into its turns; climbs and sinks at the autopilot's "
            "rates within its pitch limit, flying height errors out on its TECS time constant, "
            "at any altitude: no engine power, ceiling or speed-height coupling; "
            "--flight-model jsbsim flies an airframe)"
        )
    for limit in r.airframe_limits:
        out.append(f"  CANNOT FLY: {limit}")
    for shortfall in r.airframe_shortfalls:
        out.append(f"  could not hold: {shortfall}")
    return out


def _met_lines(r: DryRunReport) -> list[str]:
    """What the flight missed, where it was lost, whether it met the planned points, and the
    world it flew in with what the plan assumed of it."""
    out = []
    if r.airframe_limits:
        pass  # never flown: nothing missed, nothing lost on the way
    elif r.missed:
        out.append(
            "missed: "
            + ", ".join(f"{m.kind} {m.point} by {m.miss:.1f} m" for m in r.missed)
            + f" (outside the {r.capture_radius:g} m capture radius: no correction)"
        )
    if not r.arrived and not r.airframe_limits:
        out.append(f"flown {r.flown_length:,.1f} m before the vehicle was lost")
    if not r.corrections_as_planned and not r.airframe_limits:
        out.append("corrections: NOT the planned points in the planned order (see the rows)")
    out.append(
        f"world: {r.wind}; autopilot {r.autopilot}; the aircraft steers its "
        + ("INS estimate (corrections where the true track passes within the capture radius)"
           if r.navigate_on_estimate else "true position")
    )  # fmt: skip
    for assumption in r.assumptions:
        out.append(f"  assumed: {assumption}")
    return out


def _runs_lines(r: DryRunReport) -> list[str]:
    """The success rate of the runs against the planned probability, and their losses (none
    without runs)."""
    if not (r.runs > 0 and r.success_rate is not None and r.success_ci is not None):
        return []
    if r.airframe_limits:
        return [f"runs: none of the {r.runs} flown: the airframe cannot fly the mission (above)"]
    low, high = r.success_ci
    if r.reserve > 0:  # the plan's probability is a floor: held to limits less the reserve
        verdict = "kept" if r.probability_within_ci else "NOT kept (above the interval)"
        said = f"planned at least {r.planned_probability:.4f} (with the reserve): {verdict}"
    else:
        verdict = "within" if r.probability_within_ci else "OUTSIDE"
        said = f"planned probability {r.planned_probability:.4f}: {verdict} the interval"
    how = "flights, each with its own draws" if r.runs_flown else "replays of one flight"
    out = [
        f"success rate {r.success_rate:.3f} over {r.runs} {how} "
        f"({(r.confidence or 0) * 100:g} % Wilson interval {low:.3f}-{high:.3f}); {said}",
        f"losses: {r.flight_losses} by the flight (a missed landmark, or lost where the plan "
        "flown as planned with the same correction outcomes arrives), "
        f"{r.correction_losses} by failed corrections",
    ]
    flight = [lost for lost in r.lost_runs if lost.by_the_flight]
    for lost in flight[:SHOWN_FLIGHT_LOSSES]:
        out.append(f"  run {lost.run} lost by the flight: {_lost_run(lost)}")
    if len(flight) > SHOWN_FLIGHT_LOSSES:
        out.append(f"  ... {len(flight) - SHOWN_FLIGHT_LOSSES} more (lost_runs in --json)")
    return out


def _notes(r: DryRunReport) -> list[str]:
    """What one seeded draw, or one seeded flight, can and cannot say."""
    out = []
    if r.planned_probability < 1.0:
        out.append(
            f"note: the planned probability is {r.planned_probability:.4f} < 1: this replay is "
            f"one seeded draw (--seed {r.seed})"
            + ("" if r.runs else "; --runs N gives the success rate")
        )
    if r.demonstration:
        out.append(
            "note: one seeded flight is a demonstration, not a verdict: --runs N flies N, each "
            "with its own draws"
        )
    return out


def _result_line(r: DryRunReport) -> str:
    """The report's last line: what the dry run came to."""
    if not r.verified:
        return "result: the upload did not verify"
    if r.airframe_limits:
        return f"result: the mission cannot be flown: {r.why}"
    if r.envelope_shortfalls:
        return "result: NOT verified: " + verdict_line(r).removeprefix("verdict failed: ")
    if r.demonstration:
        return "result: verified and arrived" if r.arrived else f"result: LOST: {r.why}"
    if r.ok:
        return (
            f"result: verified; no run lost by the flight; success rate consistent with the "
            f"planned probability (this draw: {'arrived' if r.arrived else 'lost'})"
        )
    return f"result: NOT verified by the flight: {verdict_line(r)}"


def _envelope_lines(r: DryRunReport) -> list[str]:
    """The plan's legs against its aircraft's envelope in the wind flown (checked before the
    flight): a summary per limit, then the shortfalls one by one."""
    if r.envelope_wind is None:
        return []
    where = (
        "from any direction" if r.envelope_wind_from is None
        else f"from {r.envelope_wind_from:g} deg, climbs along each leg's track"
    )  # fmt: skip
    head = f"envelope in the wind flown ({r.envelope_wind:g} m/s {where}, per leg at "
    head += "the TAS of its highest point): "
    if not r.envelope_shortfalls:
        return [head + "every leg fits"]
    by_limit: dict[str, list] = {}
    for s in r.envelope_shortfalls:
        by_limit.setdefault(s.limit, []).append(s)
    summary = []
    for limit, rows in by_limit.items():
        worst = max(rows, key=lambda s: abs(s.needs - s.can))
        summary.append(
            f"{limit} on {len(rows)} leg(s) (worst leg {worst.leg}: planned {worst.needs:.2f} "
            f"{worst.unit}, in this wind {worst.can:.2f} {worst.unit})"
        )
    out = [head + "DOES NOT FIT: " + "; ".join(summary)]
    for s in r.envelope_shortfalls[:SHOWN_ENVELOPE_SHORTFALLS]:
        out.append(f"  DOES NOT FIT: {s.describe()}")
    more = len(r.envelope_shortfalls) - SHOWN_ENVELOPE_SHORTFALLS
    if more > 0:
        out.append(f"  ... {more} more (envelope_shortfalls in --json)")
    return out


def _lost_run(lost: LostRunRow) -> str:
    parts = [lost.reason or "lost"]
    if lost.missed:
        parts.append("missed " + ", ".join(lost.missed))
    if lost.failed:
        parts.append("failed corrections at " + ", ".join(lost.failed))
    return "; ".join(parts)


def _table(r: DryRunReport) -> str:
    head = (
        f"{'point':>6} {'kind':>4} {'flown m':>10} {'v err':>7} {'h err':>7} "
        f"{'v margin':>8} {'h margin':>8} {'planned v':>9} {'planned h':>9}  outcome"
    )
    lines = [head]
    if r.airframe_limits:
        return "corrections: none: the flight never started (the airframe cannot fly the mission)"
    for row in r.rows:
        kind = row.kind + ("*" if row.unreliable else "")
        if row.outcome == "missed":
            lines.append(
                f"{row.point:>6} {kind:>4} {row.distance:>10.1f} {'-':>7} {'-':>7} {'-':>8} "
                f"{'-':>8} {'-':>9} {'-':>9}  MISSED by {row.miss:.1f} m (3D)"
            )
            continue
        pv = "-" if row.planned_v is None else f"{row.planned_v:.3f}"
        ph = "-" if row.planned_h is None else f"{row.planned_h:.3f}"
        outcome = row.outcome + ("" if row.on_route else " (not on route)")
        lines.append(
            f"{row.point:>6} {kind:>4} {row.distance:>10.1f} {row.v_before:>7.3f} "
            f"{row.h_before:>7.3f} {row.v_margin:>8.3f} {row.h_margin:>8.3f} {pv:>9} {ph:>9}"
            f"  {outcome}"
        )
    if r.arrived or not any(row.outcome == "lost" for row in r.rows):
        b = r.route[-1]
        lines.append(
            f"{b:>6} {'B':>4} {r.flown_length:>10.1f} {r.v_at_b:>7.3f} {r.h_at_b:>7.3f} "
            f"{r.theta - r.v_at_b:>8.3f} {r.theta - r.h_at_b:>8.3f} {'':>9} {'':>9}  "
            + ("arrived" if r.arrived else "lost")
        )
    lines.append("* unreliable point; errors on arrival, before the correction")
    return "\n".join(lines)
