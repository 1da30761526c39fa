"""The autopilot's own parameters the navigators read, with each autopilot's shipped defaults.

Shipped defaults (read in the autopilots' parameter tables):

* ArduPlane: ROLL_LIMIT_DEG 45 (Parameters.cpp), TECS_CLMB_MAX 5 m/s and TECS_SINK_MAX 5 m/s
  (AP_TECS.cpp var_info), WP_RADIUS 90 m, NAVL1_LIM_BANK 0 (AP_L1_Control.cpp var_info: 0 scales
  every loiter radius by EAS2TAS^2, AP_L1_Control::loiter_radius).
* PX4: FW_R_LIM 50 deg, FW_T_CLMB_MAX 5 and FW_T_SINK_MAX 5 m/s, FW_T_CLMB_R_SP 3 and
  FW_T_SINK_R_SP 2 m/s (fw_pos_control_params.c: "the default rate at which the vehicle will
  climb in autonomous modes"), NAV_ACC_RAD 10 m, NPFG_PERIOD 10 s, NPFG_DAMPING 0.7,
  NPFG_SW_DST_MLT 0.32 (npfg_params.c).

A vehicle's parameters (the mock's PARAM table) override them name by name
(:meth:`AutopilotParams.from_parameters`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

SHIPPED: dict[str, dict[str, float]] = {
    "ardupilot": {
        "ROLL_LIMIT_DEG": 45.0,
        "TECS_CLMB_MAX": 5.0,
        "TECS_SINK_MAX": 5.0,
        "WP_RADIUS": 90.0,
        "NAVL1_LIM_BANK": 0.0,
        "AIRSPEED_MIN": 9.0,
        "AIRSPEED_MAX": 22.0,
    },
    "px4": {
        "FW_R_LIM": 50.0,
        "FW_T_CLMB_MAX": 5.0,
        "FW_T_SINK_MAX": 5.0,
        "FW_T_CLMB_R_SP": 3.0,
        "FW_T_SINK_R_SP": 2.0,
        "NAV_ACC_RAD": 10.0,
        "NPFG_PERIOD": 10.0,
        "NPFG_DAMPING": 0.7,
        "NPFG_SW_DST_MLT": 0.32,
        "FW_AIRSPD_MIN": 10.0,
        "FW_AIRSPD_MAX": 20.0,
    },
}


@dataclass(frozen=True)
class AutopilotParams:
    """What the navigator reads of its autopilot. Fields left None take ``flavour``'s shipped
    default (see the module docstring)."""

    flavour: str = "ardupilot"
    wp_radius: float = 90.0  # ArduPlane WP_RADIUS
    loiter_radius: float = 200.0  # ArduPlane WP_LOITER_RAD / PX4 NAV_LOITER_RAD (signed: + CW)
    acceptance_radius: float = 10.0  # PX4 NAV_ACC_RAD
    bank_limit: float | None = None  # deg: ROLL_LIMIT_DEG / FW_R_LIM
    climb_rate: float | None = None  # m/s: TECS_CLMB_MAX / min(FW_T_CLMB_R_SP, FW_T_CLMB_MAX)
    sink_rate: float | None = None  # m/s: TECS_SINK_MAX / min(FW_T_SINK_R_SP, FW_T_SINK_MAX)
    loiter_bank_limit: float = 0.0  # ArduPlane NAVL1_LIM_BANK
    npfg_period: float = 10.0  # PX4 NPFG_PERIOD
    npfg_damping: float = 0.7  # PX4 NPFG_DAMPING
    npfg_switch_multiplier: float = 0.32  # PX4 NPFG_SW_DST_MLT
    airspeed_min: float | None = None  # m/s: AIRSPEED_MIN / FW_AIRSPD_MIN
    airspeed_max: float | None = None  # m/s: AIRSPEED_MAX / FW_AIRSPD_MAX

    def __post_init__(self) -> None:
        shipped = _limits(self.flavour, SHIPPED[self.flavour])
        for name, value in shipped.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, value)

    @classmethod
    def from_parameters(cls, flavour: str, params: dict[str, float]) -> AutopilotParams:
        """The parameters a vehicle holds, under its autopilot's names, over the shipped
        defaults; values that are not finite and positive fall back to the default."""
        merged = dict(SHIPPED[flavour])
        merged.update({k: float(v) for k, v in params.items() if _usable(v)})
        limits = _limits(flavour, merged)
        if flavour == "ardupilot":
            return cls(
                flavour,
                wp_radius=merged["WP_RADIUS"],
                loiter_radius=float(params.get("WP_LOITER_RAD", 200.0)),
                acceptance_radius=merged["WP_RADIUS"],
                loiter_bank_limit=float(params.get("NAVL1_LIM_BANK", 0.0)),
                **limits,
            )
        return cls(
            flavour,
            wp_radius=merged["NAV_ACC_RAD"],
            loiter_radius=float(params.get("NAV_LOITER_RAD", 200.0)),
            acceptance_radius=merged["NAV_ACC_RAD"],
            npfg_period=merged["NPFG_PERIOD"],
            npfg_damping=merged["NPFG_DAMPING"],
            npfg_switch_multiplier=merged["NPFG_SW_DST_MLT"],
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
        if self.flavour == "ardupilot":
            return None
        return min(max(speed, low), high)

    def with_rates(self, climb: float, sink: float) -> AutopilotParams:
        """The same autopilot set to climb and sink at these rates (m/s)."""
        return replace(self, climb_rate=float(climb), sink_rate=float(sink))

    def describe(self) -> str:
        names = _NAMES[self.flavour]
        return (
            f"{names[0]} {self.bank_limit:g} deg, climb {self.climb_rate:g} m/s ({names[1]}), "
            f"sink {self.sink_rate:g} m/s ({names[2]})"
        )


_NAMES = {
    "ardupilot": ("ROLL_LIMIT_DEG", "TECS_CLMB_MAX", "TECS_SINK_MAX"),
    "px4": ("FW_R_LIM", "min(FW_T_CLMB_R_SP, FW_T_CLMB_MAX)", "min(FW_T_SINK_R_SP, FW_T_SINK_MAX)"),
}


def _usable(v: object) -> bool:
    try:
        f = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return math.isfinite(f) and f > 0


def _limits(flavour: str, p: dict[str, float]) -> dict[str, float]:
    """Roll limit and the climb and sink rates a mission flies at (see the module docstring:
    PX4's TECS takes the default rates in missions, capped by the maxima)."""
    if flavour == "ardupilot":
        return {
            "bank_limit": p["ROLL_LIMIT_DEG"],
            "climb_rate": p["TECS_CLMB_MAX"],
            "sink_rate": p["TECS_SINK_MAX"],
            "airspeed_min": p["AIRSPEED_MIN"],
            "airspeed_max": p["AIRSPEED_MAX"],
        }
    return {
        "bank_limit": p["FW_R_LIM"],
        "climb_rate": min(p["FW_T_CLMB_R_SP"], p["FW_T_CLMB_MAX"]),
        "sink_rate": min(p["FW_T_SINK_R_SP"], p["FW_T_SINK_MAX"]),
        "airspeed_min": p["FW_AIRSPD_MIN"],
        "airspeed_max": p["FW_AIRSPD_MAX"],
    }
