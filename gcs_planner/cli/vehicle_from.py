"""The aircraft in its autopilot's terms, for the commands that plan: cruise EAS, bank limit,
climb and sink rates and the autopilot, from flags, ``--vehicle-from CONNECT`` (the autopilot's
own parameters) or the autopilot's shipped defaults (``--firmware``), and the design wind
(``--wind``). From them the envelope the legs use (turning radius, climb and descent angles) is
derived (:class:`gcs_planner.vehicle.DerivedEnvelope`); ``--turn-radius``, ``--max-climb-angle``
and ``--max-descent-angle`` remain direct statements of the envelope and win over derivation.
Flags given on the command line win over what the autopilot says."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Mapping
from dataclasses import replace

from gcs_planner.autopilot import autopilot_for, effective
from gcs_planner.errors import InputError
from gcs_planner.flight_reserve import MAX_SHARE, DerivedReserve, gust_wander, late_entry
from gcs_planner.scenario.model import Scenario
from gcs_planner.vehicle import FIRMWARES, DerivedEnvelope, bank_angle_for, parse_wind


def add_vehicle_from_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--vehicle-from",
        metavar="CONN",
        help="read cruise airspeed, bank limit and climb/sink rates from the autopilot on this "
        "connection (its ArduPlane or PX4 parameters; PX4: the mission rates); flags given win",
    )


def add_envelope_arguments(
    p: argparse.ArgumentParser, *, wind: bool = True, firmware: bool = True
) -> None:
    """The autopilot's terms the envelope is derived from (plan; dry-run has its own --wind and
    --firmware, which it passes in)."""
    g = p.add_argument_group("the aircraft in its autopilot's terms (derive the envelope)")
    g.add_argument(
        "--max-climb-rate", type=float, metavar="M/S", help="climb rate a mission climbs at"
    )
    g.add_argument(
        "--max-sink-rate", type=float, metavar="M/S", help="sink rate a mission descends at"
    )
    g.add_argument(
        "--per-leg-envelope",
        action="store_true",
        help="each leg on the turning radius (ArduPlane: and the climb and descent angles) of "
        "the TAS at its own highest point, not the scenario's highest: shorter routes that the "
        "derived flight reserve does not yet cover everywhere (docs/model.md); dry-run them",
    )
    if firmware:
        g.add_argument(
            "--firmware",
            choices=FIRMWARES,
            help="the autopilot that flies the plan: its shipped defaults fill the cruise "
            "airspeed, bank limit and climb/sink rates not given otherwise",
        )
    if wind:
        g.add_argument(
            "--wind",
            metavar="SPEED[@FROM_DEG]",
            help="design wind, m/s: the envelope holds in a wind of this speed from any "
            "direction; with @FROM_DEG and the angles from rates, each leg climbs and "
            "descends within the limits of its own ground track",
        )
        g.add_argument(
            "--gust",
            type=float,
            metavar="SPEED",
            help="design gusts, m/s per horizontal axis: the derived flight reserve covers the "
            "track they lengthen (default 0)",
        )


def apply_vehicle_from(args: argparse.Namespace) -> None:
    """Fill the autopilot-term flags the user left unset from the vehicle on
    ``args.vehicle_from``: cruise airspeed, bank limit and the rates a mission flies with
    (:func:`gcs_planner.autopilot.effective`: ArduPlane TECS_CLMB_MAX / TECS_SINK_MAX; PX4
    min(FW_T_CLMB_R_SP, FW_T_CLMB_MAX) and min(FW_T_SINK_R_SP, FW_T_SINK_MAX), the rates its
    position controller gives TECS in missions)."""
    if not getattr(args, "vehicle_from", None):
        return
    # The link (pymavlink) loads only when an autopilot is asked: plan starts fast without it.
    from gcs_planner.cli.upload import connect_client
    from gcs_planner.errors import LinkError
    from gcs_planner.link.params import read_parameter

    link_args = argparse.Namespace(
        connect=args.vehicle_from,
        baud=57600,
        signing_key=None,
        source_system=255,
        source_component=190,
        target_system=None,
        target_component=None,
        firmware=None,
        timeout=1.5,
        retries=5,
        wait=15.0,
        quiet=True,
    )
    client = connect_client(link_args)
    try:
        firmware = client.firmware if client.firmware in FIRMWARES else None
        if firmware is None:
            raise LinkError(
                f"the vehicle's autopilot is {client.firmware!r}: its parameter names are known "
                f"for {' and '.join(FIRMWARES)} only"
            )
        ap = autopilot_for(firmware)
        names = [ap.envelope["cruise_airspeed"], ap.envelope["bank_limit"]]
        names += [*ap.mission_climb, *ap.mission_climb_bounds, *ap.guidance]
        target = client._target()
        values = {
            name: read_parameter(
                client.link, target, name, timeout=client.timeout, retries=client.retries
            )
            for name in names
        }
    finally:
        client.link.close()
    eff = effective(firmware, values)
    for name in ap.guidance:
        spec = ap.spec(name)
        assert spec is not None  # every guidance parameter is in the autopilot's table
        if not (math.isfinite(values[name]) and spec.low <= values[name] <= spec.high):
            raise LinkError(
                f"the vehicle's {name} {values[name]!r} lies outside {spec.low:g}..{spec.high:g}"
            )
    overrides = {
        "cruise_airspeed": eff.cruise_airspeed,
        "max_bank_angle": eff.bank_limit,
        "max_climb_rate": eff.climb_rate,
        "max_sink_rate": eff.sink_rate,
    }
    for key, value in overrides.items():
        if not (math.isfinite(value) and value > 0):
            raise LinkError(f"the vehicle's {key.replace('_', ' ')} {value!r} is not usable")
    if getattr(args, "turn_radius", None) is not None:
        overrides.pop("max_bank_angle")  # a radius given here wins over the autopilot's bank
    used = []
    for key, value in overrides.items():
        if getattr(args, key, None) is None:
            setattr(args, key, value)
            used.append(f"{key} {value:.4g}")
    if getattr(args, "firmware", None) is None:
        args.firmware = firmware
    args.vehicle_source = f"the {firmware} vehicle"
    # Its path follower's tuning: the runs and the reserve are derived from it, not from the
    # shipped defaults, when the plan is for this autopilot.
    args.vehicle_values = (firmware, {name: values[name] for name in ap.guidance})
    tuning = ", ".join(f"{name} {values[name]:g}" for name in ap.guidance)
    print(
        f"gcs-planner: from the {firmware} vehicle: {', '.join(used)}; guidance {tuning}",
        file=sys.stderr,
    )


def derive_envelope(
    args: argparse.Namespace,
    scenario: Scenario,
    *,
    wind_text: str | None = None,
    wind_field: str = "--wind",
    firmware: str | None = None,
    firmware_defaults: bool = True,
    flown_by: str | None = None,
    gust: float | None = None,
) -> Scenario:
    """The scenario with its envelope derived from the autopilot's terms, when any is given
    (rates, bank, firmware or a design wind); else ``scenario`` unchanged (today's envelope).

    Direct statements on the command line (``--turn-radius``, ``--max-climb-angle``,
    ``--max-descent-angle``) win; a figure that nothing derives keeps the scenario's value.
    ``firmware_defaults`` False: no autopilot's shipped defaults fill what flags leave open (the
    dry run, whose --firmware names the flown autopilot and must not change its plan).
    ``flown_by``: the autopilot that will fly the plan when no firmware fills the envelope (the
    dry run's): its settle distance gives the straight run-in and run-out at every landmark.
    ``gust``: the design gust (m/s per axis; None: ``--gust``, else the scenario's
    [environment] gust, else 0), which the derived flight reserve covers.
    Bad values are InputError naming the flag."""
    terms, environment, toml = _toml_terms(scenario)
    if "error_unit" in environment or "capture_radius" in environment:
        scenario = scenario.with_vehicle(
            error_unit=float(environment.get("error_unit", scenario.error_unit)),  # type: ignore[arg-type]
            capture_radius=float(
                environment.get("capture_radius", scenario.capture_radius)  # type: ignore[arg-type]
            ),
        )
    if wind_text is None:
        if "wind" in environment:
            wind_text, wind_field = str(environment["wind"]), f"{toml}: environment.wind"
    wind, wind_from = 0.0, None
    if wind_text is not None:
        try:
            wind, wind_from = parse_wind(wind_text)
        except ValueError as exc:
            raise InputError(str(exc), field=wind_field) from None
    if firmware_defaults:
        firmware = firmware if firmware is not None else getattr(args, "firmware", None)
    else:
        firmware = None
    if firmware is None and firmware_defaults and "firmware" in terms:
        firmware = str(terms["firmware"])
    climb = getattr(args, "max_climb_rate", None)
    sink = getattr(args, "max_sink_rate", None)
    file_terms = []
    if climb is None and "max_climb_rate" in terms:
        climb = float(terms["max_climb_rate"])  # type: ignore[arg-type]
        file_terms.append("max_climb_rate")
    if sink is None and "max_sink_rate" in terms:
        sink = float(terms["max_sink_rate"])  # type: ignore[arg-type]
        file_terms.append("max_sink_rate")
    flag_bank = getattr(args, "max_bank_angle", None)
    file_bank = (
        bank_angle_for(scenario.cruise_airspeed, scenario.params.turn_radius)
        if scenario.radius_source == "airspeed and bank"
        else None
    )
    if climb is None and sink is None and firmware is None and wind == 0 and file_bank is None:
        return scenario
    origin = getattr(args, "vehicle_source", None) or "flag"
    sources: list[tuple[str, str]] = []
    tuned_for, tuning = getattr(args, "vehicle_values", None) or (None, {})
    own = dict(tuning) if firmware is not None and firmware == tuned_for else {}
    shipped = effective(firmware, own) if firmware is not None else None

    def pick(name: str, given: float | None, default: float | None) -> float | None:
        if given is not None:
            sources.append((name, toml if name in file_terms else origin))
            return float(given)
        if default is not None:
            sources.append((name, f"{firmware}'s shipped default"))
            return float(default)
        return None

    base = scenario.origin.alt if scenario.origin else 0.0
    altitude = float(scenario.xyz[:, 2].max()) + base
    low_altitude = float(scenario.xyz[:, 2].min()) + base
    eas_flag = getattr(args, "cruise_airspeed", None)
    if eas_flag is None and shipped is None:
        eas = scenario.cruise_airspeed
        sources.append(("cruise_airspeed", "scenario"))
    else:
        eas = pick("cruise_airspeed", eas_flag, shipped.cruise_airspeed if shipped else None)
    if flag_bank is None and file_bank is not None:
        bank: float | None = file_bank
        sources.append(("max_bank_angle", "scenario"))
    else:
        bank = pick("max_bank_angle", flag_bank, shipped.bank_limit if shipped else None)
    climb = pick("max_climb_rate", climb, shipped.climb_rate if shipped else None)
    sink = pick("max_sink_rate", sink, shipped.sink_rate if shipped else None)
    for name, value in (("--max-climb-rate", climb), ("--max-sink-rate", sink)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise InputError(f"must be a rate > 0 m/s (got {value:g})", field=name)
    if bank is not None and not (math.isfinite(bank) and 0 < bank < 90):
        raise InputError(f"must lie in (0, 90) degrees (got {bank:g})", field="--max-bank-angle")
    assert eas is not None
    given_radius = getattr(args, "turn_radius", None) is not None
    r_stated = scenario.params.turn_radius
    if bank is None and r_stated > 0:
        # No bank given: the stated radius is the still-air radius at cruise; its bank at TAS
        # turns the same way, and the wind widens the ground-track radius as (V + W)^2.
        tas = DerivedEnvelope(eas, 45.0, 1.0, 1.0, 0.0, None, altitude, firmware).tas
        bank = bank_angle_for(tas, r_stated)
        sources.append(("max_bank_angle", f"implied by the turning radius {r_stated:g} m at TAS"))
    env = DerivedEnvelope(
        eas=float(eas),
        bank_deg=float(bank) if bank is not None else 0.0,
        climb_rate=math.inf if climb is None else climb,
        sink_rate=math.inf if sink is None else sink,
        wind=wind,
        wind_from=wind_from,
        altitude=altitude,
        autopilot=firmware,
        sources=tuple(sources),
        low_altitude=low_altitude,
    )
    flier = shipped if shipped is not None or flown_by is None else effective(flown_by, {})
    env = _with_runs(env, args, scenario, flier)
    for field, why in env.refusals():
        if field == "max_bank_angle" and bank is None:
            continue  # straight legs: no bank to derive a radius from
        flag = {"wind": wind_field}.get(field, "--" + field.replace("_", "-"))
        raise InputError(why, field=flag)
    changes: dict[str, float] = {}
    if bank is not None and not given_radius:
        changes["turn_radius"] = env.turn_radius
    if climb is not None and getattr(args, "max_climb_angle", None) is None:
        changes["max_climb_angle"] = env.climb_angle
    if sink is not None and getattr(args, "max_descent_angle", None) is None:
        changes["max_descent_angle"] = env.descent_angle
    if env.runs_source.startswith("derived") and changes:
        changes["approach"], changes["departure"] = env.approach, env.departure
    if not changes:
        # Everything stated directly: the plan is today's, and says nothing it did not use.
        print(
            "gcs-planner: note: the envelope is stated directly (--turn-radius, "
            "--max-climb-angle, --max-descent-angle): the autopilot's terms and the design "
            "wind do not change it",
            file=sys.stderr,
        )
        return scenario
    # Each leg on the envelope of its own highest point, asked for only (--per-leg-envelope): at
    # the legs' own limits the mock's flights overran what the derived reserve covers (tight
    # turns low down entered late, more per stretch than the reserve's two; PX4 an extra lap on
    # a helix in 10 m/s). The radius always; the angles under ArduPlane only: PX4 ends a helix's
    # NAV_LOITER_TO_ALT on the altitude, and only on its last turn's exit course, and a helix at
    # the leg's own limit reaches it there with nothing to spare (the dry run of dataset 1 in
    # still air lost 30 of 200 flights, each a lap of 245 m more).
    varies = []
    if getattr(args, "per_leg_envelope", False):
        varies = ["turn_radius"]
        if (env.autopilot or flown_by) == "ardupilot":
            varies += ["max_climb_angle", "max_descent_angle"]
    # A stated direction: each leg's angles along its own track, where both come from the rates.
    along = (
        wind_from is not None and wind > 0
        and "max_climb_angle" in changes and "max_descent_angle" in changes
    )  # fmt: skip
    env = replace(env, per_leg=tuple(k for k in varies if k in changes), along_track=along)
    out = scenario.with_params(**changes)
    out = out.with_vehicle(
        cruise_airspeed=float(eas),
        envelope=env,
        radius_source="derived" if "turn_radius" in changes else out.radius_source,
    )
    if gust is None:
        gust = getattr(args, "gust", None)
    gust_field = "--gust"
    if gust is None and "gust" in environment:
        gust, gust_field = float(environment["gust"]), f"{toml}: environment.gust"  # type: ignore[arg-type]
    gust = 0.0 if gust is None else float(gust)
    if not (math.isfinite(gust) and 0.0 <= gust <= 50.0):
        raise InputError(f"must be a speed in [0, 50] m/s (got {gust:g})", field=gust_field)
    return with_derived_reserve(out, env, gust, env.autopilot or flown_by, own)


def with_derived_reserve(
    scenario: Scenario,
    env: DerivedEnvelope,
    gust: float,
    autopilot: str | None = None,
    values: Mapping[str, float] | None = None,
) -> Scenario:
    """The scenario planning with the reserve derived from what it must cover (turn entry at
    the envelope's radius, the design ``gust`` over the longest stretch: flight_reserve.py),
    when nobody stated one and the reader gave airplane legs its constant default; else
    unchanged. The cap on the default (5 % of the tightest limit) holds for it too."""
    p = scenario.params
    if (
        scenario.reserve_source != "default"
        or scenario.leg_model != "airplane"
        or p.turn_radius <= 0
        or env.bank_deg <= 0
    ):
        return scenario
    limits = [getattr(p, k) for k in ("alpha1", "alpha2", "beta1", "beta2", "theta")]
    # The arcs are flown at the larger of the planned radius and the roll limit's at V + W.
    radius = max(p.turn_radius, env.turn_radius)
    late, rule = late_entry(autopilot, radius, env.ground_speed_max, values)
    wander, wander_rule = gust_wander(autopilot, env.tas, values) if gust > 0 else (0.0, "")
    basis = DerivedReserve(
        turn_radius=radius,
        late=late,
        late_rule=rule,
        tas=env.tas,
        ground_speed=env.ground_speed_max,
        bank_deg=env.bank_deg,
        autopilot=autopilot,
        gust=gust,
        stretch=max(limits) / p.delta,
        cap=MAX_SHARE * min(limits) / p.delta,
        wind=env.wind,
        slowest_tas=env.tas_low,
        eas=env.eas,
        wander=wander,
        wander_rule=wander_rule,
    )
    out = scenario.with_params(reserve=basis.metres)
    return out.with_vehicle(reserve_source="derived", reserve_basis=basis)


def _with_runs(
    env: DerivedEnvelope, args: argparse.Namespace, scenario: Scenario, shipped: object
) -> DerivedEnvelope:
    """The envelope with its straight run-in and run-out at every landmark: as stated (flags or
    the scenario), else the autopilot's settle distance at the largest ground speed (docs/
    model.md, "Straight at every landmark"), else none (no autopilot named)."""
    p = scenario.params
    stated = (
        getattr(args, "approach", None) is not None
        or getattr(args, "departure", None) is not None
        or p.approach > 0
        or p.departure > 0
    )
    if stated:
        return replace(env, approach=p.approach, departure=p.departure, runs_source="stated")
    if shipped is None or env.bank_deg <= 0:
        return env
    d = shipped.settle_distance(env.ground_speed_max)  # type: ignore[attr-defined]
    firmware = shipped.firmware  # type: ignore[attr-defined]
    why = f"derived: {firmware}'s settle distance at {env.ground_speed_max:.1f} m/s ground " + (
        "speed, the L1 distance NAVL1_PERIOD * NAVL1_DAMPING * V / pi"
        if firmware == "ardupilot"
        else "speed, npfg's track error bound NPFG_PERIOD * NPFG_DAMPING * V"
    )
    values = shipped.values  # type: ignore[attr-defined]
    names = autopilot_for(firmware).guidance[:2]
    why += " (" + ", ".join(f"{n} {values[n]:g}" for n in names) + ")"
    return replace(env, approach=d, departure=d, runs_source=why)


def _toml_terms(scenario: Scenario) -> tuple[dict[str, object], dict[str, object], str]:
    """A scenario TOML's [vehicle] autopilot terms and [environment] values (empty for other
    files), and the file's name; flags given on the command line win over them."""
    if not scenario.source.lower().endswith(".toml"):
        return {}, {}, ""
    from pathlib import Path

    from gcs_planner.scenario.toml_reader import read_scenario_toml

    spec = read_scenario_toml(Path(scenario.source))
    terms = {k: v for k, (v, _) in spec.autopilot_terms.items()}
    environment = {k: v for k, (v, _) in spec.environment.items()}
    return terms, environment, scenario.source
