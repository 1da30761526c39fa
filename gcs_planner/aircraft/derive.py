"""The aircraft the plan is for, derived from its autopilot's terms: cruise EAS, bank limit,
climb and sink rates, the autopilot, the design wind and gust. From them the envelope the legs
use (turning radius, climb and descent angles), the straight runs at every landmark and the
flight reserve are derived (:class:`gcs_planner.aircraft.profile.DerivedEnvelope`); what the
scenario
states of its aircraft (turn_radius, the climb angles, cruise_airspeed) wins over an
autopilot's shipped defaults. The command line and the library build the planning problem
here, the same way (``gcs-planner plan`` and :func:`gcs_planner.load_scenario`).

``terms`` is any object with the attributes of :class:`AircraftTerms` (the command line passes
its parsed flags); a missing attribute is not given."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from gcs_planner.aircraft.autopilot import EffectiveParameters, autopilot_for, effective
from gcs_planner.aircraft.profile import DerivedEnvelope, bank_angle_for, parse_wind
from gcs_planner.aircraft.reserve import MAX_SHARE, DerivedReserve, gust_wander, late_entry
from gcs_planner.errors import InputError
from gcs_planner.scenario.model import Scenario


@dataclass(frozen=True)
class AircraftTerms:
    """What a caller states of the aircraft beyond the scenario file (None: not stated): the
    command line's flags, the library's keyword overrides."""

    cruise_airspeed: float | None = None
    max_bank_angle: float | None = None
    max_climb_rate: float | None = None
    max_sink_rate: float | None = None
    autopilot: str | None = None
    turn_radius: float | None = None
    max_climb_angle: float | None = None
    max_descent_angle: float | None = None
    approach: float | None = None
    departure: float | None = None
    per_leg_envelope: bool = False
    gust: float | None = None
    # the vehicle the terms were read from (plan --vehicle-from) and its guidance tuning
    vehicle_source: str | None = None
    vehicle_values: tuple[str, Mapping[str, float]] | None = field(default=None)


def derive_envelope(
    args: object,
    scenario: Scenario,
    *,
    wind_text: str | None = None,
    wind_field: str = "--wind",
    autopilot: str | None = None,
    autopilot_defaults: bool = True,
    flown_by: str | None = None,
    gust: float | None = None,
) -> Scenario:
    """The scenario with its envelope derived from the autopilot's terms, when any is given
    (rates, bank, autopilot or a design wind); else ``scenario`` unchanged (today's envelope).

    Direct statements on the command line (``--turn-radius``, ``--max-climb-angle``,
    ``--max-descent-angle``) win; a figure that nothing derives keeps the scenario's value.
    ``autopilot_defaults`` False: no autopilot's shipped defaults fill what flags leave open (the
    dry run, whose --autopilot names the flown autopilot and must not change its plan).
    ``flown_by``: the autopilot that will fly the plan when no autopilot fills the envelope (the
    dry run's): its settle distance gives the straight run-in and run-out at every landmark.
    ``gust``: the design gust (m/s per axis; None: ``--gust``, else the scenario's
    [environment] gust, else 0), which the derived flight reserve covers.
    Bad values are InputError naming the flag."""
    terms, environment, toml, stated = _toml_terms(scenario)
    stated |= {k for k in _AIRCRAFT_FIGURES if getattr(args, k, None) is not None}
    scenario = _with_environment_units(scenario, environment)
    if wind_text is None and "wind" in environment:
        wind_text, wind_field = str(environment["wind"]), f"{toml}: environment.wind"
    wind, wind_from = 0.0, None
    if wind_text is not None:
        try:
            wind, wind_from = parse_wind(wind_text)
        except ValueError as exc:
            raise InputError(str(exc), field=wind_field) from None
    chosen = None
    if autopilot_defaults:
        chosen = autopilot if autopilot is not None else getattr(args, "autopilot", None)
        named = terms.get("autopilot", terms.get("firmware"))  # the key's former name
        if chosen is None and named is not None:
            chosen = str(named)
    climb = getattr(args, "max_climb_rate", None)
    sink = getattr(args, "max_sink_rate", None)
    file_terms = []
    if climb is None and "max_climb_rate" in terms:
        climb = float(terms["max_climb_rate"])  # type: ignore[arg-type]
        file_terms.append("max_climb_rate")
    if sink is None and "max_sink_rate" in terms:
        sink = float(terms["max_sink_rate"])  # type: ignore[arg-type]
        file_terms.append("max_sink_rate")
    file_bank = (
        bank_angle_for(scenario.cruise_airspeed, scenario.params.turn_radius)
        if scenario.radius_source == "airspeed and bank"
        else None
    )
    # The runs alone: an aircraft with stated climb limits and turns, planned for the
    # autopilot that flies it, keeps straight at every landmark for as long as its path
    # follower needs to settle (docs/model.md, "Straight at every landmark"); the contest's
    # model (unlimited climbs) is no aircraft's and is planned as the paper states it.
    target = chosen or flown_by
    runs_only = (
        climb is None and sink is None and chosen is None and wind == 0 and file_bank is None
    )
    if runs_only and not (
        target is not None
        and scenario.vehicle.climb_limited
        and scenario.leg_model == "airplane"
        and scenario.params.turn_radius > 0
    ):
        return scenario
    tuned_for, tuning = getattr(args, "vehicle_values", None) or (None, {})
    own = dict(tuning) if chosen is not None and chosen == tuned_for else {}
    picked = _Picker(
        chosen,
        effective(chosen, own) if chosen is not None else None,
        origin=getattr(args, "vehicle_source", None) or "flag",
        toml=toml,
        file_terms=file_terms,
    )
    env = _envelope(args, scenario, picked, stated, climb, sink, file_bank, wind, wind_from)
    env = within_pitch_limit(env, picked.shipped, stated)
    flier = picked.shipped
    if flier is None and flown_by is not None:
        flier = effective(flown_by, {})
    env = with_ground_speed_floor(env, flier)
    env = _with_runs(env, args, scenario, flier)
    for name, why in env.refusals():
        if name == "max_bank_angle" and env.bank_deg <= 0:
            continue  # straight legs: no bank to derive a radius from
        flag = {"wind": wind_field}.get(name, "--" + name.replace("_", "-"))
        raise InputError(why, field=flag)
    changes = _changes(env, stated)
    runs = env.runs_source.startswith("derived")
    if runs and changes:
        changes["approach"], changes["departure"] = env.approach, env.departure
    elif runs and scenario.vehicle.climb_limited and target is not None:
        # A stated envelope flown by a named autopilot: the plan is the stated one, with the
        # straight runs its path follower needs (and the reserve as stated or defaulted); the
        # plan's optimality statement names them.
        return scenario.with_params(approach=env.approach, departure=env.departure)
    if not changes:
        # Everything stated directly: the plan is today's, and says nothing it did not use.
        print(
            "gcs-planner: note: the envelope is stated directly (--turn-radius, "
            "--max-climb-angle, --max-descent-angle): the autopilot's terms and the design "
            "wind do not change it",
            file=sys.stderr,
        )
        return scenario
    env = _with_leg_variation(env, args, changes, env.autopilot or flown_by)
    out = scenario.with_params(**changes)
    out = out.with_vehicle(
        cruise_airspeed=float(env.eas),
        envelope=env,
        radius_source="derived" if "turn_radius" in changes else out.radius_source,
    )
    gust = _design_gust(args, gust, environment, toml)
    return with_derived_reserve(out, env, gust, env.autopilot or flown_by, own)


def _with_environment_units(scenario: Scenario, environment: Mapping[str, object]) -> Scenario:
    """The scenario with the [environment] table's error unit and capture radius, if given."""
    if "error_unit" not in environment and "capture_radius" not in environment:
        return scenario
    return scenario.with_vehicle(
        error_unit=float(environment.get("error_unit", scenario.error_unit)),  # type: ignore[arg-type]
        capture_radius=float(
            environment.get("capture_radius", scenario.capture_radius)  # type: ignore[arg-type]
        ),
    )


@dataclass
class _Picker:
    """Each figure of the envelope from what was given, else the autopilot's shipped default,
    with where it came from (``sources``, the plan's account of its envelope)."""

    autopilot: str | None
    shipped: EffectiveParameters | None
    origin: str
    toml: str
    file_terms: list[str]
    sources: list[tuple[str, str]] = field(default_factory=list)

    def __call__(self, name: str, given: float | None, default: float | None) -> float | None:
        if given is not None:
            self.sources.append((name, self.toml if name in self.file_terms else self.origin))
            return float(given)
        if default is not None:
            self.sources.append((name, f"{self.autopilot}'s shipped default"))
            return float(default)
        return None


def _envelope(
    args: object,
    scenario: Scenario,
    pick: _Picker,
    stated: set[str],
    climb: float | None,
    sink: float | None,
    file_bank: float | None,
    wind: float,
    wind_from: float | None,
) -> DerivedEnvelope:
    """The envelope of the figures given (flags, the scenario's [vehicle]) or shipped, checked."""
    shipped = pick.shipped
    base = scenario.origin.alt if scenario.origin else 0.0
    altitude = float(scenario.xyz[:, 2].max()) + base
    low_altitude = float(scenario.xyz[:, 2].min()) + base
    eas_flag = getattr(args, "cruise_airspeed", None)
    if eas_flag is None and (shipped is None or "cruise_airspeed" in stated):
        eas: float | None = scenario.cruise_airspeed
        pick.sources.append(("cruise_airspeed", "scenario"))
    else:
        eas = pick("cruise_airspeed", eas_flag, shipped.cruise_airspeed if shipped else None)
    flag_bank = getattr(args, "max_bank_angle", None)
    if flag_bank is None and file_bank is not None:
        bank: float | None = file_bank
        pick.sources.append(("max_bank_angle", "scenario"))
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
    r_stated = scenario.params.turn_radius
    if bank is None and r_stated > 0:
        # No bank given: the stated radius is the still-air radius at cruise; its bank at TAS
        # turns the same way, and the wind widens the ground-track radius as (V + W)^2.
        tas = DerivedEnvelope(eas, 45.0, 1.0, 1.0, 0.0, None, altitude, pick.autopilot).tas
        bank = bank_angle_for(tas, r_stated)
        pick.sources.append(
            ("max_bank_angle", f"implied by the turning radius {r_stated:g} m at TAS")
        )
    return DerivedEnvelope(
        eas=float(eas),
        bank_deg=float(bank) if bank is not None else 0.0,
        climb_rate=math.inf if climb is None else climb,
        sink_rate=math.inf if sink is None else sink,
        wind=wind,
        wind_from=wind_from,
        altitude=altitude,
        autopilot=pick.autopilot,
        sources=tuple(pick.sources),
        low_altitude=low_altitude,
    )


def pitch_limit(flier: EffectiveParameters) -> float:
    """The pitch limit of auto flight (deg; 90: none) of ``flier``'s table: ArduPlane
    TECS_PITCH_MAX, 0 taking PTCH_LIM_MAX_DEG's value and any other capped by it
    (``libraries/AP_TECS/AP_TECS.cpp``, ``AP_TECS::update_pitch_throttle``); PX4 FW_P_LIM_MAX
    (``src/modules/fw_pos_control/fw_path_navigation_params.c``), the limit of its pitch
    setpoint (``TECS.cpp``)."""
    names = autopilot_for(flier.firmware).altitude_loop
    if len(names) < 2:
        return 90.0
    pitch = float(flier.values[names[1]])
    if len(names) > 2:
        cap = float(flier.values[names[2]])
        pitch = cap if pitch <= 0 else min(pitch, cap)
    return pitch if 0 < pitch < 90 else 90.0


def within_pitch_limit(
    env: DerivedEnvelope, flier: EffectiveParameters | None, stated: set[str]
) -> DerivedEnvelope:
    """The envelope with its climb rate within the autopilot's pitch limit: TECS asks for the
    pitch of the climb's flight path in the air, asin(rate / TAS), and clips it at the limit,
    so no climb steeper than the limit is flown (docs/model.md, "The pitch limit and the
    ground-speed floor"). The rate is capped at TAS sin(limit) at the slowest TAS (the
    scenario's lowest point): every leg's derived angle, atan(rate / (TAS + W)) at its own
    TAS, is then within the limit. Only where the climb angle is derived (not stated) and the
    autopilot's table is known."""
    if flier is None or "max_climb_angle" in stated or not math.isfinite(env.climb_rate):
        return env
    limit = pitch_limit(flier)
    if limit >= 90.0:
        return env
    most = env.tas_low * math.sin(math.radians(limit))
    if env.climb_rate <= most:
        return env
    name = autopilot_for(flier.firmware).altitude_loop[1]
    why = f"capped by {name} {limit:g} deg at {env.tas_low:.1f} m/s TAS (the lowest point)"
    sources = tuple((k, f"{v}, {why}" if k == "max_climb_rate" else v) for k, v in env.sources)
    return replace(env, climb_rate=most, sources=sources)


def with_ground_speed_floor(
    env: DerivedEnvelope, flier: EffectiveParameters | None
) -> DerivedEnvelope:
    """The envelope with the autopilot's ground-speed floor and largest airspeed (its record's
    ``ground_speed_floor``; AIRSPEED_MAX / FW_AIRSPD_MAX): into a headwind stronger than
    TAS - floor it flies faster, and the turning radius and angles take that TAS
    (``DerivedEnvelope.tas_flown``)."""
    if flier is None:
        return env
    ap = autopilot_for(flier.firmware)
    name, scale = ap.ground_speed_floor
    if not name:
        return env
    floor = float(flier.values[name]) * scale
    most = float(flier.values[ap.airspeed_range[1]])
    return replace(env, ground_speed_floor=floor, airspeed_max=max(most, env.eas))


def _changes(env: DerivedEnvelope, stated: set[str]) -> dict[str, float]:
    """The scenario's figures the envelope derives: those nobody stated directly."""
    changes: dict[str, float] = {}
    if env.bank_deg > 0 and "turn_radius" not in stated:
        changes["turn_radius"] = env.turn_radius
    if math.isfinite(env.climb_rate) and "max_climb_angle" not in stated:
        changes["max_climb_angle"] = env.climb_angle
    if math.isfinite(env.sink_rate) and "max_descent_angle" not in stated:
        changes["max_descent_angle"] = env.descent_angle
    return changes


def _with_leg_variation(
    env: DerivedEnvelope, args: object, changes: Mapping[str, float], flier: str | None
) -> DerivedEnvelope:
    """The envelope with what varies leg by leg: the figures each leg takes at its own highest
    point (asked for only, --per-leg-envelope) and the angles along each leg's own track."""
    # Each leg on the envelope of its own highest point, asked for only: at the legs' own
    # limits the mock's flights overran what the derived reserve covers (tight turns low down
    # entered late, more per stretch than the reserve's two). The radius always; the angles
    # only where a helix has something to spare: PX4 ends a helix's NAV_LOITER_TO_ALT on the
    # altitude, and only on its last turn's exit course (helix_exits_on_course), and a helix
    # at the leg's own limit reaches it there with nothing to spare (docs/measurements.md).
    varies = []
    if getattr(args, "per_leg_envelope", False):
        varies = ["turn_radius"]
        if flier is not None and not autopilot_for(flier).helix_exits_on_course:
            varies += ["max_climb_angle", "max_descent_angle"]
    # A stated direction: each leg's angles along its own track, where both come from the rates.
    along = (
        env.wind_from is not None and env.wind > 0
        and "max_climb_angle" in changes and "max_descent_angle" in changes
    )  # fmt: skip
    return replace(env, per_leg=tuple(k for k in varies if k in changes), along_track=along)


def _design_gust(
    args: object, gust: float | None, environment: Mapping[str, object], toml: str
) -> float:
    """The design gust (m/s per axis): the caller's, else --gust, else [environment] gust."""
    if gust is None:
        gust = getattr(args, "gust", None)
    gust_field = "--gust"
    if gust is None and "gust" in environment:
        gust, gust_field = float(environment["gust"]), f"{toml}: environment.gust"  # type: ignore[arg-type]
    gust = 0.0 if gust is None else float(gust)
    if not (math.isfinite(gust) and 0.0 <= gust <= 50.0):
        raise InputError(f"must be a speed in [0, 50] m/s (got {gust:g})", field=gust_field)
    return gust


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
    env: DerivedEnvelope, args: object, scenario: Scenario, shipped: EffectiveParameters | None
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
    d = shipped.settle_distance(env.ground_speed_max)
    name = shipped.firmware
    ap = autopilot_for(name)
    why = f"derived: {name}'s settle distance at {env.ground_speed_max:.1f} m/s ground " + (
        "speed, the L1 distance NAVL1_PERIOD * NAVL1_DAMPING * V / pi"
        if ap.path_follower == "L1"
        else "speed, npfg's track error bound NPFG_PERIOD * NPFG_DAMPING * V"
    )
    values = shipped.values
    names = ap.guidance[:2]
    why += " (" + ", ".join(f"{n} {values[n]:g}" for n in names) + ")"
    return replace(env, approach=d, departure=d, runs_source=why)


def _toml_terms(
    scenario: Scenario,
) -> tuple[dict[str, object], dict[str, object], str, set[str]]:
    """A scenario TOML's [vehicle] autopilot terms and [environment] values (empty for other
    files), the file's name, and the aircraft's figures it states (turn_radius, the climb
    angles, cruise_airspeed, in [vehicle] or [parameters]); flags given on the command line win
    over them."""
    if not scenario.source.lower().endswith(".toml"):
        return {}, {}, "", set()
    from pathlib import Path

    from gcs_planner.scenario.toml_reader import read_scenario_toml

    spec = read_scenario_toml(Path(scenario.source))
    terms = {k: v for k, (v, _) in spec.autopilot_terms.items()}
    environment = {k: v for k, (v, _) in spec.environment.items()}
    stated = (set(spec.vehicle) | set(spec.parameters)) & set(_AIRCRAFT_FIGURES)
    return terms, environment, scenario.source, stated


# What a scenario may state of its aircraft; each one stated wins over an autopilot's shipped
# defaults (the aircraft is the scenario's; the vehicle setup makes the autopilot fly it).
_AIRCRAFT_FIGURES = ("turn_radius", "max_climb_angle", "max_descent_angle", "cruise_airspeed")


def design_wind_speed(args: object, scenario: Scenario) -> float:
    """The design wind's speed (m/s) the caller gives (``args.wind``) or the scenario TOML's
    ``[environment] wind``; 0 without either. What the vehicle setup must hold in when the
    envelope is stated rather than derived."""
    text = getattr(args, "wind", None)
    field = "--wind"
    if text is None:
        _, environment, toml, _ = _toml_terms(scenario)
        if "wind" not in environment:
            return 0.0
        text, field = str(environment["wind"]), f"{toml}: environment.wind"
    try:
        return float(parse_wind(str(text))[0])
    except ValueError as exc:
        raise InputError(str(exc), field=field) from None
