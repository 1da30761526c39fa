"""The autopilot's own parameters the navigators read, over each autopilot's shipped defaults.

The shipped defaults are the autopilots' records' (gcs_planner/aircraft/autopilot.py
``Autopilot.defaults``, read in the autopilots' parameter tables): ArduPlane's ROLL_LIMIT_DEG,
TECS_CLMB_MAX and TECS_SINK_MAX, WP_RADIUS, NAVL1_LIM_BANK (0 scales every loiter radius by
EAS2TAS^2, AP_L1_Control::loiter_radius), AIRSPEED_MIN and AIRSPEED_MAX; PX4's FW_R_LIM,
FW_T_CLMB_MAX and FW_T_SINK_MAX, FW_T_CLMB_R_SP and FW_T_SINK_R_SP (fw_pos_control_params.c:
"the default rate at which the vehicle will climb in autonomous modes"), NAV_ACC_RAD,
NPFG_PERIOD, NPFG_DAMPING, NPFG_SW_DST_MLT (npfg_params.c), FW_AIRSPD_MIN and FW_AIRSPD_MAX;
and each one's altitude loop (the record's ``altitude_loop``): the time constant its TECS flies
a height error out over (ArduPlane TECS_TIME_CONST, PX4 FW_T_ALT_TC: 5 s) and the pitch limit
of auto flight (ArduPlane TECS_PITCH_MAX 15 deg, capped by PTCH_LIM_MAX_DEG 20 and replaced by
it when 0; PX4 FW_P_LIM_MAX 30 deg).

A vehicle's parameters (the mock's PARAM table) override them name by name
(:meth:`AutopilotParams.from_parameters`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from gcs_planner.aircraft.autopilot import (
    ARDUPLANE,
    DEFAULT_AUTOPILOT,
    PX4,
    Autopilot,
    autopilot_for,
)

# ArduPlane's NAVL1_LIM_BANK: the bank limit its loiter radii are held to (0: none).
LOITER_BANK_PARAM = "NAVL1_LIM_BANK"
# The loiter radius (m) when the vehicle's table does not hold one: the mock's own, not shipped.
DEFAULT_LOITER_RADIUS_M = 200.0
# The TECS time constant both autopilots ship (TECS_TIME_CONST, FW_T_ALT_TC), for a record
# without an altitude loop.
DEFAULT_TIME_CONSTANT_S = 5.0


@dataclass(frozen=True)
class AutopilotParams:
    """What the navigator reads of its autopilot. Fields left None take ``flavour``'s shipped
    default (see the module docstring)."""

    flavour: str = DEFAULT_AUTOPILOT  # the autopilot's name (gcs_planner.aircraft.autopilot)
    wp_radius: float = ARDUPLANE.defaults["WP_RADIUS"]  # ArduPlane WP_RADIUS
    # ArduPlane WP_LOITER_RAD / PX4 NAV_LOITER_RAD (signed: + CW)
    loiter_radius: float = DEFAULT_LOITER_RADIUS_M
    acceptance_radius: float = PX4.defaults["NAV_ACC_RAD"]  # PX4 NAV_ACC_RAD
    bank_limit: float | None = None  # deg: ROLL_LIMIT_DEG / FW_R_LIM
    climb_rate: float | None = None  # m/s: TECS_CLMB_MAX / min(FW_T_CLMB_R_SP, FW_T_CLMB_MAX)
    sink_rate: float | None = None  # m/s: TECS_SINK_MAX / min(FW_T_SINK_R_SP, FW_T_SINK_MAX)
    loiter_bank_limit: float = ARDUPLANE.defaults[LOITER_BANK_PARAM]  # ArduPlane NAVL1_LIM_BANK
    npfg_period: float = PX4.defaults["NPFG_PERIOD"]  # PX4 NPFG_PERIOD
    npfg_damping: float = PX4.defaults["NPFG_DAMPING"]  # PX4 NPFG_DAMPING
    npfg_switch_multiplier: float = PX4.defaults["NPFG_SW_DST_MLT"]  # PX4 NPFG_SW_DST_MLT
    airspeed_min: float | None = None  # m/s: AIRSPEED_MIN / FW_AIRSPD_MIN
    airspeed_max: float | None = None  # m/s: AIRSPEED_MAX / FW_AIRSPD_MAX
    altitude_time_constant: float | None = None  # s: TECS_TIME_CONST / FW_T_ALT_TC
    pitch_limit: float | None = None  # deg: TECS_PITCH_MAX (PTCH_LIM_MAX_DEG) / FW_P_LIM_MAX
    ground_speed_floor: float | None = None  # m/s: MIN_GNDSPD_CM / 100, FW_GND_SPD_MIN

    def __post_init__(self) -> None:
        shipped = _limits(self.autopilot, self.autopilot.defaults)
        for name, value in shipped.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, value)

    @property
    def autopilot(self) -> Autopilot:
        """The record of the autopilot these parameters are of."""
        return autopilot_for(self.flavour)

    @classmethod
    def from_parameters(cls, flavour: str, params: dict[str, float]) -> AutopilotParams:
        """The parameters a vehicle holds, under its autopilot's names, over the shipped
        defaults; values that are not finite and positive fall back to the default."""
        ap = autopilot_for(flavour)
        merged = dict(ap.defaults)
        merged.update({k: float(v) for k, v in params.items() if _usable(v)})
        # A pitch limit may be 0 (ArduPlane: TECS_PITCH_MAX 0 takes PTCH_LIM_MAX_DEG).
        merged.update({k: float(params[k]) for k in ap.altitude_loop[1:] if _at_least_0(params, k)})
        # So may the ground-speed floor (0: off).
        floor = ap.ground_speed_floor[0]
        if floor and _at_least_0(params, floor):
            merged[floor] = float(params[floor])
        limits = _limits(ap, merged)
        radius = float(params.get(ap.loiter_radius_param, DEFAULT_LOITER_RADIUS_M))
        acceptance = merged[ap.acceptance_param]
        if ap.switches_early:
            # PX4: npfg's switch distance from its period, damping and multiplier.
            period, damping, multiplier = (merged[name] for name in ap.guidance)
            return cls(
                flavour,
                wp_radius=acceptance,
                loiter_radius=radius,
                acceptance_radius=acceptance,
                npfg_period=period,
                npfg_damping=damping,
                npfg_switch_multiplier=multiplier,
                **limits,
            )
        return cls(
            flavour,
            wp_radius=acceptance,
            loiter_radius=radius,
            acceptance_radius=acceptance,
            loiter_bank_limit=float(params.get(LOITER_BANK_PARAM, 0.0)),
            **limits,
        )

    def commanded_airspeed(self, speed: float) -> float | None:
        """The airspeed flown after DO_CHANGE_SPEED to ``speed`` m/s; None when the autopilot
        ignores it (ArduPlane, outside AIRSPEED_MIN..AIRSPEED_MAX: ``Plane::do_change_speed``
        in ArduPlane/commands_logic.cpp); PX4 constrains it to FW_AIRSPD_MIN..FW_AIRSPD_MAX
        (``FixedwingPositionControl::adapt_airspeed_setpoint``)."""
        low, high = float(self.airspeed_min or 0.0), float(self.airspeed_max or math.inf)
        if low <= speed <= high:
            return speed
        if self.autopilot.speed_outside_range == "ignored":
            return None
        return min(max(speed, low), high)

    def with_rates(self, climb: float, sink: float) -> AutopilotParams:
        """The same autopilot set to climb and sink at these rates (m/s)."""
        return replace(self, climb_rate=float(climb), sink_rate=float(sink))

    def describe(self) -> str:
        ap = self.autopilot
        climb, sink = ap.mission_climb
        if ap.mission_climb_bounds:
            climb_max, sink_max = ap.mission_climb_bounds
            climb, sink = f"min({climb}, {climb_max})", f"min({sink}, {sink_max})"
        out = (
            f"{ap.envelope['bank_limit']} {self.bank_limit:g} deg, climb {self.climb_rate:g} m/s "
            f"({climb}), sink {self.sink_rate:g} m/s ({sink})"
        )
        if ap.altitude_loop:
            time_constant, pitch = ap.altitude_loop[0], ap.altitude_loop[1]
            out += (
                f", height errors flown out over {self.altitude_time_constant:g} s "
                f"({time_constant}), pitch up to {self.pitch_limit:g} deg ({pitch})"
            )
        return out


def _at_least_0(params: dict[str, float], name: str) -> bool:
    try:
        value = float(params[name])
    except (KeyError, TypeError, ValueError):
        return False
    return math.isfinite(value) and value >= 0


def _usable(v: object) -> bool:
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return math.isfinite(f) and f > 0


def _limits(ap: Autopilot, p: dict[str, float]) -> dict[str, float]:
    """Roll limit, the climb and sink rates a mission flies at (PX4's TECS takes the default
    rates in missions, capped by the maxima) and the airspeed range of ``ap`` from the table
    ``p``."""
    climb, sink = (p[name] for name in ap.mission_climb)
    if ap.mission_climb_bounds:
        climb_max, sink_max = (p[name] for name in ap.mission_climb_bounds)
        climb, sink = min(climb, climb_max), min(sink, sink_max)
    low, high = ap.airspeed_range
    return {
        "bank_limit": p[ap.envelope["bank_limit"]],
        "climb_rate": climb,
        "sink_rate": sink,
        "airspeed_min": p[low],
        "airspeed_max": p[high],
        **_altitude_loop(ap, p),
        "ground_speed_floor": p[ap.ground_speed_floor[0]] * ap.ground_speed_floor[1]
        if ap.ground_speed_floor[0]
        else 0.0,
    }


def _altitude_loop(ap: Autopilot, p: dict[str, float]) -> dict[str, float]:
    """The altitude loop's time constant (s) and pitch limit (deg) of ``ap`` from the table
    ``p``: its ``altitude_loop`` names, a pitch limit of 0 taking the cap's value and any
    other capped by it (ArduPlane AP_TECS::update_pitch_throttle). Without them: TECS's 5 s
    and no pitch limit (90 deg)."""
    names = ap.altitude_loop
    if not names:
        return {"altitude_time_constant": DEFAULT_TIME_CONSTANT_S, "pitch_limit": 90.0}
    pitch = p[names[1]] if len(names) > 1 else 90.0
    if len(names) > 2:
        cap = p[names[2]]
        pitch = cap if pitch <= 0 else min(pitch, cap)
    return {"altitude_time_constant": p[names[0]], "pitch_limit": pitch}
