"""The vehicle setup a plan relies on: the autopilot parameters that make ArduPlane or PX4 fly the
aircraft the plan was made for (docs/model.md, "The vehicle setup").

A plan states its aircraft: a cruise airspeed (EAS), a turning radius, climb and descent angles
(stated in the scenario, or derived from the autopilot's rates and bank). An autopilot flies what
its parameters allow, whatever the mission says, so the setup names, for the target autopilot,
each parameter with the least (or most) value the plan needs and the reason:

* the cruise airspeed: ArduPlane AIRSPEED_CRUISE, PX4 FW_AIRSPD_TRIM equal to the plan's EAS, and
  the airspeed range containing it: ArduPlane ignores a mission's DO_CHANGE_SPEED outside
  AIRSPEED_MIN..AIRSPEED_MAX (``Plane::do_change_speed``, ArduPlane/commands_logic.cpp; shipped
  9..22 m/s, ArduPlane/Parameters.cpp), PX4 constrains every airspeed setpoint to
  FW_AIRSPD_MIN..FW_AIRSPD_MAX (``FixedwingPositionControl::adapt_airspeed_setpoint``; shipped
  10..20 m/s, fw_pos_control params);
* the climb and sink rates: a leg at the plan's steepest angle flown at the largest ground speed
  (TAS at the highest point plus the design wind) climbs at Vg tan(angle). ArduPlane
  TECS_CLMB_MAX / TECS_SINK_MAX (``AP_TECS``); PX4 missions climb at FW_T_CLMB_R_SP /
  FW_T_SINK_R_SP bounded by FW_T_CLMB_MAX / FW_T_SINK_MAX (``FixedwingPositionControl``), so all
  four. A plan with unlimited angles (the contest's model) needs the rate of its chosen route's
  steepest leg, which no autopilot may allow: the setup then says so;
* the pitch limit of auto flight: TECS clips the pitch it asks for, the climb rate over the TAS,
  so the plan's climb rate needs asin(rate / TAS) at the slowest TAS (ArduPlane TECS_PITCH_MAX,
  shipped 15 deg, and PTCH_LIM_MAX_DEG, 20, which caps it; PX4 FW_P_LIM_MAX, 30);
* the roll limit: a turn of radius R at ground speed Vg banks atan(Vg^2 / (g R)) (ROLL_LIMIT_DEG;
  FW_R_LIM);
* ArduPlane's NAVL1_LIM_BANK: ``AP_L1_Control::loiter_radius`` widens every loiter by EAS2TAS^2
  unless it is set, and keeps the radius once TAS^2 / (g tan(NAVL1_LIM_BANK)) <= R;
* the loiter radius equal to the turning radius (WP_LOITER_RAD; NAV_LOITER_RAD), which the
  helices fly.

:func:`needs` lists them for a plan JSON and an autopilot; :mod:`gcs_planner.mission.param_files`
writes and reads them as the files ground stations load; ``link.vehicle_check`` reads a
vehicle's values and returns what falls short.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from gcs_planner.aircraft.autopilot import Autopilot, autopilot_for, effective
from gcs_planner.aircraft.profile import UNLIMITED_ANGLE_DEG, G, tas_from_eas

# Slack for rates and angles written and read back as float32.
_SLACK = 1e-4
# An airspeed or a radius read back within this of the plan's counts as equal.
_SPEED_SLACK = 0.05
_RADIUS_SLACK = 0.5


@dataclass(frozen=True)
class ParameterNeed:
    """The plan needs parameter ``name`` to lie in ``least``..``most`` (either may be None: no
    bound; in the parameter's unit) for the reason ``why``; ``set_to`` is the value the setup
    file holds and an upload writes. ``magnitude``: the sign carries another meaning (a loiter
    radius's sign is the turn's sense), so the bounds hold for the absolute value."""

    name: str
    least: float | None
    set_to: float
    why: str
    most: float | None = None
    magnitude: bool = False
    # The autopilot cannot take the value at all (outside the parameter's range): the plan
    # cannot be flown by this autopilot, whatever it is set to.
    impossible: str = ""

    def met_by(self, value: float) -> bool:
        if self.impossible or not math.isfinite(value):
            return False
        if self.magnitude:
            value = abs(value)
        slack = _RADIUS_SLACK if self.magnitude else _SLACK
        if self.least is not None and value < self.least - slack * max(1.0, abs(self.least)):
            return False
        if self.most is not None and value > self.most + slack * max(1.0, abs(self.most)):
            return False
        return True

    def wanted(self) -> str:
        """What the plan needs, in words: "at least 7.94", "at most 25", "25"."""
        if self.least is not None and self.most is not None:
            if abs(self.least - self.most) <= 1e-9 * max(1.0, abs(self.least)):
                return f"{self.set_to:.4g}"
            return f"{self.least:.4g}..{self.most:.4g}"
        if self.least is not None:
            return f"at least {self.least:.4g}"
        return f"at most {self.most:.4g}"


def needs(plan: dict, firmware: str, wind: float = 0.0) -> list[ParameterNeed]:
    """What ``plan`` (a plan JSON) needs of a ``firmware`` autopilot's parameters (see the
    module docstring); empty for a plan of straight legs at no stated airspeed. ``wind`` (m/s):
    a wind the setup must also hold in (the design wind of a plan whose envelope was stated, or
    the wind a dry run flies); the larger of it and the derived envelope's design wind counts."""
    ap = autopilot_for(firmware)
    vehicle = plan.get("vehicle") if isinstance(plan.get("vehicle"), dict) else {}
    env = vehicle.get("envelope") if isinstance(vehicle.get("envelope"), dict) else None
    params = plan.get("parameters") if isinstance(plan.get("parameters"), dict) else {}
    eas = _number(env.get("cruise_eas") if env else vehicle.get("cruise_airspeed"))
    if eas is None or eas <= 0:
        return []
    wind = max((_number(env.get("design_wind")) if env else None) or 0.0, wind)
    tas = _number(env.get("tas")) if env else None
    if tas is None:
        tas = tas_from_eas(eas, _altitudes(plan)[1])
    ground = tas + wind
    out = _airspeed_needs(ap, eas)
    pitch: list[ParameterNeed] = []
    # climb and sink: the derived rates, else the stated angles at the largest ground speed
    rates = (("climb_rate", "max_climb_angle", "climbs", 1.0), ("sink_rate", "max_descent_angle",
             "sinks", -1.0))  # fmt: skip
    for i, (rate_key, angle_key, verb, sign) in enumerate(rates):
        rate = _number(env.get(rate_key)) if env else None
        if rate is not None:
            why = f"the plan {verb} at up to {rate:.3g} m/s (its envelope's {rate_key[:-5]} rate)"
        else:
            angle = _number(params.get(angle_key))
            source = f"its {angle_key.replace('_', ' ')} {angle:g} deg" if angle else ""
            if angle is None or angle >= UNLIMITED_ANGLE_DEG:
                angle = _steepest_leg(plan, sign)
                source = f"its chosen route's steepest leg, {angle:.3g} deg (no limit stated)"
            if angle <= 0:
                continue
            rate = ground * math.tan(math.radians(min(angle, 89.9)))
            why = f"the plan {verb} at up to {rate:.3g} m/s: {source} at {ground:.1f} m/s"
        if ap.climbs_at_once:
            leg_rate, leg = _px4_leg_rate(ap, plan, sign, ground)
            if leg_rate > rate:
                rate = leg_rate
                why = (
                    f"leg {leg} {verb} at {rate:.3g} m/s: PX4 holds the landmark's altitude on "
                    f"the run-out and leaves npfg's switch distance early, so the leg's climb "
                    f"is flown over what is left at {ground:.1f} m/s"
                )
        names = [ap.mission_climb[i], *ap.mission_climb_bounds[i : i + 1]]
        for name in names:
            out.append(_at_least(ap, name, rate, why))
        if sign > 0:
            # Listed last: a shortfall in it loses a flight only on its steepest climbs.
            pitch = _pitch_needs(ap, rate, tas_from_eas(eas, _altitudes(plan)[0]))
    radius = _number(env.get("turn_radius")) if env else None
    if radius is None:
        radius = _number(params.get("turn_radius"))
    if radius is None or radius <= 0:
        return out + pitch + _altitude_loop_need(plan)
    bank = _number(env.get("bank_limit_deg")) if env else None
    if bank is None or not 0 < bank < 90:
        bank = math.degrees(math.atan(ground * ground / (G * radius)))
    out.append(
        _at_least(
            ap,
            ap.envelope["bank_limit"],
            bank,
            f"a {radius:.1f} m turn at {ground:.1f} m/s over the ground banks {bank:.3g} deg",
        )
    )
    if ap.loiter_widens_with_tas:
        # the least bank for which loiter_radius keeps R at the highest point's TAS
        least = math.degrees(math.atan(tas * tas / (G * radius)))
        out.append(
            ParameterNeed(
                "NAVL1_LIM_BANK",
                least,
                min(89.0, _round_up(max(least, bank))),
                f"loiters must keep the plan's {radius:.1f} m radius at {tas:.1f} m/s TAS "
                "(0 widens every loiter by EAS2TAS^2)",
            )
        )
    loiter = float(round(radius))
    out.append(
        ParameterNeed(
            ap.loiter_radius_param,
            loiter,
            loiter,
            f"the helices fly the plan's {radius:.1f} m turning radius",
            most=loiter,
            magnitude=True,
        )
    )
    if ap.switches_early:
        out.append(_px4_acceptance(ap, plan, eas, wind))
    return out + pitch + _altitude_loop_need(plan)


def _altitude_loop_need(plan: dict) -> list[ParameterNeed]:
    """A plan for a design turbulence gave each capture a vertical allowance for the altitude
    loop's height error at its time constant (core/capture.py, aircraft/altitude_hold.py): a
    slower loop holds the altitude less closely (ArduPlane TECS_TIME_CONST, AP_TECS.cpp
    ``_update_pitch``; PX4 FW_T_ALT_TC, TECS.cpp), so the setup holds it at most there."""
    capture = plan.get("capture") if isinstance(plan.get("capture"), dict) else {}
    loop = capture.get("turbulence") if isinstance(capture.get("turbulence"), dict) else None
    if not loop or not loop.get("loop_param"):
        return []
    tau = _number(loop.get("time_constant_s"))
    if tau is None or tau <= 0:
        return []
    why = (
        f"the captures' vertical allowance is for the height error of a {tau:g} s loop in the "
        "plan's design turbulence"
    )
    return [ParameterNeed(str(loop["loop_param"]), None, tau, why, most=tau)]


def _pitch_needs(ap: Autopilot, rate: float, slowest_tas: float) -> list[ParameterNeed]:
    """The pitch limit a climb at ``rate`` m/s needs: TECS asks for a pitch of the climb rate over
    the TAS and clips it at the limit of auto flight, so the climb needs asin(rate / TAS) at
    the slowest TAS, the scenario's lowest point's (ArduPlane TECS_PITCH_MAX and the
    PTCH_LIM_MAX_DEG that caps it, AP_TECS::update_pitch_throttle; PX4 FW_P_LIM_MAX)."""
    if rate <= 0 or len(ap.altitude_loop) < 2:
        return []
    pitch = math.degrees(math.asin(min(rate / max(slowest_tas, 1e-6), 1.0)))
    why = (
        f"the plan climbs at up to {rate:.3g} m/s, {pitch:.3g} deg at {slowest_tas:.1f} m/s TAS "
        "(its lowest point): TECS clips its pitch there"
    )
    out = []
    for name in ap.altitude_loop[1:]:
        # Whole degrees: ArduPlane stores TECS_PITCH_MAX as an integer (AP_Int8).
        spec = ap.spec(name)
        shipped = spec.default if spec is not None else 0.0
        need = _at_least(ap, name, pitch, why)
        out.append(replace(need, set_to=max(float(math.ceil(pitch - 1e-9)), shipped)))
    return out


def _px4_acceptance(ap: Autopilot, plan: dict, eas: float, wind: float) -> ParameterNeed:
    """PX4 takes a fixed wing's waypoint as reached at the larger of NAV_ACC_RAD and npfg's
    switch distance (``Navigator::get_acceptance_radius``): the plan's turns and run-outs are
    laid for the switch distance, so NAV_ACC_RAD must not exceed it where it is shortest, at the
    slowest ground speed (the lowest point's TAS into the design wind)."""
    slowest = max(tas_from_eas(eas, _altitudes(plan)[0]) - wind, 1.0)
    switch = effective(ap.firmware, {}).switch_distance(slowest)
    spec = ap.spec(ap.acceptance_param)
    default = spec.default if spec is not None else switch
    return ParameterNeed(
        ap.acceptance_param, None, min(default, math.floor(switch * 10.0) / 10.0),
        f"PX4 accepts a waypoint at the larger of it and npfg's switch distance, {switch:.1f} m "
        f"at the slowest {slowest:.1f} m/s ground speed, which the plan's turns are laid for",
        most=switch,
    )  # fmt: skip


def _airspeed_needs(ap: Autopilot, eas: float) -> list[ParameterNeed]:
    why = f"the plan flies {eas:g} m/s EAS"
    cruise = ap.envelope["cruise_airspeed"]
    low_name, high_name = ap.airspeed_range
    out = [ParameterNeed(cruise, eas, eas, why + " (the cruise airspeed)", most=eas)]
    rule = "ignores" if ap.speed_outside_range == "ignored" else "clamps"
    low = ap.spec(low_name)
    high = ap.spec(high_name)
    assert low is not None and high is not None
    out.append(
        ParameterNeed(
            low_name,
            None,
            min(low.default, eas),
            f"{why}; the autopilot {rule} a commanded airspeed below it",
            most=eas,
        )  # fmt: skip
    )
    out.append(
        _at_least(ap, high_name, eas, f"{why}; the autopilot {rule} a commanded airspeed above it")
    )
    for need in out:
        spec = ap.spec(need.name)
        if spec is not None and spec.refusal(eas) is not None:
            return [_impossible(need, spec.refusal(eas) or "")]
    return out


def _at_least(ap: Autopilot, name: str, least: float, why: str) -> ParameterNeed:
    """``name`` at least ``least``; the setup writes the larger of the need (rounded up) and the
    shipped default, so it never lowers a limit the autopilot ships with."""
    spec = ap.spec(name)
    default = spec.default if spec is not None else least
    need = ParameterNeed(name, least, max(_round_up(least), default), why)
    if spec is not None and spec.refusal(need.set_to) is not None:
        return _impossible(need, spec.refusal(need.set_to) or "")
    return need


def _impossible(need: ParameterNeed, why: str) -> ParameterNeed:
    return ParameterNeed(
        need.name, need.least, need.set_to, need.why, need.most, need.magnitude,
        impossible=f"{why}: the autopilot cannot take the value the plan needs",
    )  # fmt: skip


def _round_up(x: float) -> float:
    """Up to the next 0.1 (a value a person reads and types), never below ``x``."""
    return math.ceil(x * 10.0 - 1e-9) / 10.0


def _number(x: object) -> float | None:
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        return None
    return float(x)


def _altitudes(plan: dict) -> tuple[float, float]:
    """The scenario's lowest and highest points above mean sea level (the TAS is slowest at the
    one, fastest at the other)."""
    points = plan.get("points") if isinstance(plan.get("points"), list) else []
    zs = [z for z in (_number(p.get("z")) for p in points if isinstance(p, dict)) if z is not None]
    scenario = plan.get("scenario") if isinstance(plan.get("scenario"), dict) else {}
    origin = scenario.get("origin") if isinstance(scenario.get("origin"), dict) else {}
    base = _number(origin.get("alt")) or 0.0
    return min(zs, default=0.0) + base, max(zs, default=0.0) + base


def _chosen(plan: dict) -> dict:
    """The chosen route's entry of the plan's front ({} when the plan names none)."""
    front = plan.get("front") if isinstance(plan.get("front"), list) else []
    chosen = plan.get("chosen")
    if not isinstance(chosen, int) or not 0 <= chosen < len(front):
        return {}
    return front[chosen] if isinstance(front[chosen], dict) else {}


def _steepest_leg(plan: dict, sign: float) -> float:
    """The chosen route's steepest climb (``sign`` 1) or descent (-1) in degrees, 0 if none."""
    by_id = {p.get("id"): p for p in plan.get("points", []) if isinstance(p, dict)}
    route = _chosen(plan).get("route", [])
    steepest = 0.0
    for a, b in zip(route, route[1:]):
        pa, pb = by_id.get(a), by_id.get(b)
        if pa is None or pb is None:
            continue
        try:
            dz = sign * (float(pb["z"]) - float(pa["z"]))
            dh = math.hypot(float(pb["x"]) - float(pa["x"]), float(pb["y"]) - float(pa["y"]))
        except (KeyError, TypeError, ValueError):
            continue
        if dz > 0:
            steepest = max(steepest, math.degrees(math.atan2(dz, dh)))
    return steepest


def setup_to_dict(needs_: list[ParameterNeed], firmware: str) -> dict:
    """The setup as plan.json lists it (docs/plan-json.md, ``setup``)."""
    return {
        "autopilot": firmware,
        "parameters": [
            {
                "name": n.name,
                "value": n.set_to,
                "least": n.least,
                "most": n.most,
                "why": n.why,
                **({"cannot_be_met": n.impossible} if n.impossible else {}),
            }
            for n in needs_
        ],
        "flyable": not any(n.impossible for n in needs_),
    }


def setup_lines(needs_: list[ParameterNeed], firmware: str) -> list[str]:
    """The setup in words, a line a parameter, for the plan's report."""
    out = [f"vehicle setup for {firmware} (the parameters the mission relies on):"]
    for n in needs_:
        line = f"  {n.name:<16} {n.set_to:>8.6g}   needs {n.wanted()}: {n.why}"
        if n.impossible:
            line += f"; CANNOT BE MET: {n.impossible}"
        out.append(line)
    return out


def _px4_leg_rate(ap: Autopilot, plan: dict, sign: float, ground: float) -> tuple[float, str]:
    """The climb (``sign`` 1) or sink (-1) rate PX4 needs on the chosen route's most demanding
    leg, and that leg ("FROM-TO"): the mission's run-out is level at the landmark (builder), and
    the aircraft takes up the next item npfg's switch distance early, so a leg's height change
    is flown over its length less the run-out and the switch distance
    (``FixedwingPositionControl``: TECS climbs at the rate towards the current item's
    altitude; npfg.cpp ``switchDistance``, at the shipped NPFG_PERIOD, NPFG_DAMPING and
    NPFG_SW_DST_MLT)."""
    switch = effective(ap.firmware, {}).switch_distance(ground)
    best, where = 0.0, ""
    for leg in _chosen(plan).get("legs", []):
        geo = leg.get("geometry") if isinstance(leg, dict) else None
        if not isinstance(geo, dict):
            continue
        try:
            dz = sign * (float(geo["end"][2]) - float(geo["start"][2]))
            length = float(geo["length"])
            run_out = float(geo.get("run_out") or 0.0)
        except (KeyError, TypeError, ValueError, IndexError):
            continue
        left = length - run_out - switch
        if dz <= 0 or left <= 0:
            continue
        rate = ground * dz / left
        helix = float(geo.get("helix_length") or 0.0)
        limit = geo.get("climb_limit_deg" if sign > 0 else "descent_limit_deg")
        if helix > 0 and isinstance(limit, (int, float)) and 0 < limit < UNLIMITED_ANGLE_DEG:
            # A helix (NAV_LOITER_TO_ALT) must also gain what the level run-out did not, in its
            # own laps, or PX4 flies another lap to finish it: its climb at the limit over the
            # helix, stretched by the run-out and the switch distance.
            steep = ground * math.tan(math.radians(limit))
            rate = max(rate, steep * (helix + run_out + switch) / helix)
        if rate > best:
            best, where = rate, f"{leg.get('from')}-{leg.get('to')}"
    return best, where
