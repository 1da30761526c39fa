"""The aircraft and its autopilot, in one place: the flight envelope the planner plans with, the
mock vehicle flies with and the exporter writes for, and the autopilot words (firmwares, autopilot
ids, parameter names) the link and the mock vehicle speak.

This module imports nothing of the planner, the link or the simulator, so every room can import
it (``sim/`` included) without the flow of data turning back.

The flight envelope (docs/model.md, "Airplane legs"): a fixed wing turns by banking, so its turning
radius at airspeed V and bank limit phi is R = V^2 / (g tan phi); it climbs at most at gamma_c and
descends at most at gamma_d (degrees, 90 = unlimited, the contest's model). A user gives either R
or V and phi; :func:`turn_radius_from` and :func:`bank_angle_for` convert between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs_planner.aircraft.atmosphere import density_ratio
from gcs_planner.aircraft.autopilot import AUTOPILOTS

# MAV_PARAM_TYPE: INT16 = 4, REAL32 = 9 (re-exported: the link and the mock name them from here).
from gcs_planner.aircraft.autopilot import PARAM_TYPE_INT16 as PARAM_TYPE_INT16
from gcs_planner.aircraft.autopilot import PARAM_TYPE_REAL32 as PARAM_TYPE_REAL32

# Standard gravity (m/s^2), as both autopilots use for the bank/turn-rate relation.
G = 9.80665
# How the aircraft's bank follows the bank its autopilot asks: a first-order lag of this time
# constant (s). The autopilots' roll loops ask for it over ArduPlane RLL2SRV_TCONST 0.5 s and
# PX4 FW_R_TC 0.4 s; the airframe lags the rate asked (JSBSim's c172r under those loops: 0.8 s,
# sim/aircraft.py). The mock vehicle rolls at it, and a turn is entered about this long late
# (the derived reserve, gcs_planner/aircraft/reserve.py).
ROLL_RESPONSE_S = 0.8
# The gusts' scale length (m): MIL-F-8785C's Dryden model above 2,000 ft (1,750 ft). A gust
# stays correlated for this many metres of air flown through (its time, L / TAS); the dry run
# draws its gusts with it (sim/wind.py) and the derived reserve counts their wander with it
# (gcs_planner/aircraft/reserve.py).
DRYDEN_SCALE_LENGTH_M = 533.0

# The leg models (docs/model.md, "Leg geometry"). "airplane" is the default whenever R > 0;
# "cs3d" is the tilted-plane Dubins leg kept to reproduce earlier figures; with R = 0 legs are
# straight.
LEG_MODELS = ("airplane", "cs3d")
DEFAULT_LEG_MODEL = "airplane"

# 90 degrees = no limit: the contest's aircraft, and what the planner assumes when nobody says
# otherwise (the plan then says so and names its steepest leg).
UNLIMITED_ANGLE_DEG = 90.0

# A small maritime fixed wing: 25 m/s flies the contest's ~100 km in ~70 minutes.
DEFAULT_CRUISE_AIRSPEED = 25.0
# Bank limits the autopilots ship with (ArduPlane ROLL_LIMIT_DEG 45, PX4 FW_R_LIM 50): a user's
# profile that needs more than this to hold R at V is refused.
MAX_BANK_DEG = 60.0

# ---------------------------------------------------------------------------------------------
# Autopilot words

# Each firmware's rules live in its record (gcs_planner/aircraft/autopilot.py); these are the words
# the
# link, the exporters and the mock vehicle have always used, read from there.
FIRMWARES = tuple(AUTOPILOTS)
# MAV_AUTOPILOT enum values (common.xml): ARDUPILOTMEGA = 3, PX4 = 12.
AUTOPILOT_IDS = {fw: ap.autopilot_id for fw, ap in AUTOPILOTS.items()}
FIRMWARE_OF_AUTOPILOT = {v: k for k, v in AUTOPILOT_IDS.items()}
# The parameter that holds the loiter radius, and its type: ArduPlane WP_LOITER_RAD (int16,
# metres), PX4 NAV_LOITER_RAD (float, metres). The link sets it to R on upload.
LOITER_RADIUS_PARAM = {
    fw: (ap.loiter_radius_param, ap.loiter_radius_type) for fw, ap in AUTOPILOTS.items()
}
# Where each autopilot keeps the rest of the envelope (read by ``--vehicle-from``; served by the
# mock vehicle). ArduPlane: AIRSPEED_CRUISE (m/s), ROLL_LIMIT_DEG, TECS_CLMB_MAX / TECS_SINK_MAX
# (m/s, converted to angles at cruise airspeed), WP_RADIUS (acceptance, m). PX4: FW_AIRSPD_TRIM,
# FW_R_LIM, FW_T_CLMB_MAX / FW_T_SINK_MAX (m/s), NAV_ACC_RAD.
ENVELOPE_PARAMS = {fw: dict(ap.envelope) for fw, ap in AUTOPILOTS.items()}

# Arcs are densified into waypoints at most this far apart in angle, and close enough that a
# chord stays within MAX_CHORD_ERROR_M of the arc, so the autopilot flies the planned turn.
MAX_ARC_STEP_DEG = 16.0
MAX_CHORD_ERROR_M = 2.0

# Two different radii, two names:
# * the CAPTURE radius is the correction landmark's: the aircraft's INS is corrected only when it
#   passes within this 3D distance of the landmark (the vehicle's own database says so);
# * the ACCEPTANCE radius is the autopilot's: within it a waypoint counts as reached and the
#   autopilot moves on to the next item (MAV_CMD_NAV_WAYPOINT param2).
DEFAULT_CAPTURE_RADIUS_M = 5.0
# One error unit is 0.1 m of position error (the paper's Table 2 gives the limits in decimetres;
# sim/ins.py flies errors in the same unit).
DEFAULT_ERROR_UNIT_M = 0.1
# What the autopilot adds to the INS error at a correction point: it overflies the waypoint on
# a straight run-in, counting it reached at the 1 m acceptance radius the builder writes (or
# ArduPlane's finish line), plus the 1e-7 degree storage of the position (<= 2 cm per axis).
# 1 m: a fixed wing then counts a waypoint reached when it crosses the line through it square to
# its track (ArduPlane's finish line), so it overflies the landmark; a 50 m radius lets ArduPlane
# turn for the next item early and pass a correction point by more than the capture radius.
DEFAULT_ACCEPTANCE_RADIUS_M = 1.0
TRACKING_ALLOWANCE_M = DEFAULT_ACCEPTANCE_RADIUS_M + 0.02

# The flight reserve the airplane leg model plans with unless told (Parameters.reserve): the
# metres an aircraft under its autopilot may fly beyond the plan between two resets of an error.
# The mock vehicle's ArduPlane flies the contest routes' stretches up to ~125 m longer than
# planned (turns entered late at a bank that leaves nothing to catch up with; loiters left where
# the autopilot leaves them); a route planned to the metre is lost there.
DEFAULT_RESERVE_M = 200.0
# The default never takes more than this share of the tightest limit (a scenario with limits of
# a few kilometres keeps most of them).
DEFAULT_RESERVE_MAX_SHARE = 0.05


def turn_radius_from(airspeed: float, bank_deg: float) -> float:
    """R = V^2 / (g tan phi): the coordinated-turn radius at airspeed ``airspeed`` (m/s) and bank
    ``bank_deg`` (degrees)."""
    if not (math.isfinite(airspeed) and airspeed > 0):
        raise ValueError(f"airspeed must be a finite number > 0 m/s, got {airspeed!r}")
    if not (math.isfinite(bank_deg) and 0 < bank_deg < 90):
        raise ValueError(f"bank angle must lie in (0, 90) degrees, got {bank_deg!r}")
    return airspeed * airspeed / (G * math.tan(math.radians(bank_deg)))


def bank_angle_for(airspeed: float, radius: float) -> float:
    """The bank (degrees) that turns on ``radius`` metres at ``airspeed`` m/s; 90 for R = 0."""
    if radius <= 0:
        return 90.0
    return math.degrees(math.atan(airspeed * airspeed / (G * radius)))


@dataclass(frozen=True)
class VehicleProfile:
    """The aircraft's flight envelope.

    ``turn_radius`` 0 means straight legs (no turn modelled). Climb and descent angles are
    flight-path angles in degrees, 90 meaning unlimited. ``radius_source`` says where R came from:
    "turn_radius" (given) or "airspeed and bank" (R = V^2 / (g tan phi)).
    """

    turn_radius: float = 200.0
    max_climb_angle: float = UNLIMITED_ANGLE_DEG
    max_descent_angle: float = UNLIMITED_ANGLE_DEG
    cruise_airspeed: float = DEFAULT_CRUISE_AIRSPEED
    leg_model: str = DEFAULT_LEG_MODEL
    radius_source: str = "turn_radius"
    # Straight run-in and run-out at every landmark (m; airplane legs with turns only).
    approach: float = 0.0
    departure: float = 0.0

    @property
    def runs(self) -> bool:
        """Whether the legs carry a straight run-in or run-out (airplane legs with turns)."""
        return (
            self.turn_radius > 0
            and self.leg_model == "airplane"
            and (self.approach > 0 or self.departure > 0)
        )

    @property
    def bank_angle(self) -> float:
        """The bank (degrees) the aircraft needs to turn on its turning radius at cruise."""
        return bank_angle_for(self.cruise_airspeed, self.turn_radius)

    @property
    def climb_limited(self) -> bool:
        return self.max_climb_angle < UNLIMITED_ANGLE_DEG or (
            self.max_descent_angle < UNLIMITED_ANGLE_DEG
        )

    @property
    def climb_rate(self) -> float:
        """Largest climb rate (m/s) at cruise airspeed; inf when unlimited."""
        return _rate(self.cruise_airspeed, self.max_climb_angle)

    @property
    def sink_rate(self) -> float:
        """Largest sink rate (m/s) at cruise airspeed; inf when unlimited."""
        return _rate(self.cruise_airspeed, self.max_descent_angle)

    @property
    def turn_rate(self) -> float:
        """Turn rate (rad/s) on the turning radius at cruise airspeed; inf for R = 0."""
        return math.inf if self.turn_radius <= 0 else self.cruise_airspeed / self.turn_radius

    def validate(self) -> list[str]:
        """The names of bad fields with why, empty when the profile is valid."""
        bad = []
        if not (math.isfinite(self.turn_radius) and self.turn_radius >= 0):
            bad.append(f"turn_radius must be a finite number >= 0 (got {self.turn_radius!r})")
        for name in ("max_climb_angle", "max_descent_angle"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and 0 < v <= 90):
                bad.append(f"{name} must lie in (0, 90] degrees (got {v!r})")
        v = self.cruise_airspeed
        if not (math.isfinite(v) and 0 < v <= 300):
            bad.append(f"cruise_airspeed must lie in (0, 300] m/s (got {v!r})")
        if self.leg_model not in LEG_MODELS:
            bad.append(f"leg_model must be one of {', '.join(LEG_MODELS)} (got {self.leg_model!r})")
        return bad

    def describe(self) -> str:
        """One line for the plan's output: what the planner assumed of the aircraft."""
        if self.turn_radius <= 0:
            legs = "straight legs"
        else:
            legs = f"{self.leg_model} legs, turning radius {self.turn_radius:g} m"
            if self.radius_source == "derived":
                legs += " (derived: see the envelope lines)"
            elif self.radius_source != "turn_radius":
                legs += f" (from {self.cruise_airspeed:g} m/s at {self.bank_angle:.1f} deg bank)"
        if self.climb_limited:
            climb = (
                f"climb <= {self.max_climb_angle:g} deg, descent <= {self.max_descent_angle:g} deg"
            )
        else:
            climb = "unlimited climb and descent (90 deg, the contest's model)"
        if self.runs:
            legs += (
                f", straight at every landmark (run-in >= {self.approach:.0f} m, run-out "
                f"{self.departure:.0f} m)"
            )
        return f"{legs}; {climb}; cruise {self.cruise_airspeed:g} m/s"


def _rate(airspeed: float, angle_deg: float) -> float:
    if angle_deg >= UNLIMITED_ANGLE_DEG:
        return math.inf
    return airspeed * math.sin(math.radians(angle_deg))


# ---------------------------------------------------------------------------------------------
# The envelope derived from the autopilot's terms (issue 32; docs/model.md)


def isa_density_ratio(altitude_m: float) -> float:
    """sigma = rho / rho0 of the standard atmosphere at ``altitude_m`` metres (AMSL): the one
    the mock flies (:mod:`gcs_planner.aircraft.atmosphere`)."""
    return density_ratio(altitude_m)


def tas_from_eas(eas: float, altitude_m: float) -> float:
    """True airspeed (m/s) of equivalent airspeed ``eas`` at ``altitude_m``: EAS / sqrt(sigma).

    Both autopilots hold the airspeed they are given as EAS and scale by this ratio
    (ArduPilot ``AP_Baro::get_EAS2TAS``, PX4 ``airspeed`` module's ``calc_true_from_equivalent
    _airspeed``); with the ISA temperature profile both give this value."""
    return eas / math.sqrt(isa_density_ratio(altitude_m))


@dataclass(frozen=True)
class DerivedEnvelope:
    """Flight-path angles and turning radius derived from the autopilot's terms.

    The aircraft holds ``eas`` (m/s EAS), banks at most ``bank_deg``, climbs at ``climb_rate``
    and sinks at ``sink_rate`` m/s (inf: unlimited) under ``autopilot``. Over the ground, in a
    wind of ``wind`` m/s from any direction, it can fly as fast as V + W with V the TAS at
    ``altitude`` (the scenario's highest: the largest TAS; the parts named in ``per_leg`` each
    leg takes at its own highest point instead, geometry.airplane.LegEnvelope), so

    * climb angle <= atan(climb_rate / (V + W)), descent likewise;
    * turning radius R = (V + W)^2 / (g tan(bank)) (the ground-track radius of a turn flown
      downwind at full bank).

    ``wind_from`` (degrees, or None) is the design wind's direction. With it and
    ``along_track`` (both angles derived from the rates) each leg climbs and descends within
    the limits of the fastest ground speed along its own track, atan(rate / Vg_max), and a
    helix, which flies every heading, within those from any direction; the figures here stay
    the any-direction ones, and the turning radius stays one from any direction (a turn's
    headings depend on its radius; geometry.airplane.track_factor). ``sources`` names where
    each input came from (flag, scenario file, vehicle, firmware default).
    """

    eas: float
    bank_deg: float
    climb_rate: float
    sink_rate: float
    wind: float
    wind_from: float | None
    altitude: float
    autopilot: str | None
    sources: tuple[tuple[str, str], ...] = ()
    # The straight run-in and run-out at every landmark (m): the autopilot's settle distance at
    # the largest ground speed (autopilot.EffectiveParameters.settle_distance); 0 when no
    # autopilot is named or the user stated them.
    approach: float = 0.0
    departure: float = 0.0
    runs_source: str = ""
    # The scenario's lowest altitude (m; None: ``altitude``), where the TAS is slowest: gusts
    # wander the track most, and a headwind leaves least ground speed, there.
    low_altitude: float | None = None
    # The parts of the envelope each leg takes from the altitude of its own highest point
    # ("turn_radius", "max_climb_angle", "max_descent_angle": those derived here, not stated
    # directly); the figures above are the scenario's highest point's, the largest radius and
    # the shallowest angles (geometry.airplane.LegEnvelope).
    per_leg: tuple[str, ...] = ()
    # Each leg's angles along its own track in the design wind's stated direction.
    along_track: bool = False
    # The autopilot's ground-speed floor (m/s; 0: none) and largest airspeed (m/s EAS): into a
    # headwind that leaves less ground speed than the floor it raises its airspeed, and the
    # turns widen with it (``tas_flown``; derive.py ``with_ground_speed_floor``).
    ground_speed_floor: float = 0.0
    airspeed_max: float = math.inf

    @property
    def wind_rule(self) -> str:
        """How the design wind bounds the legs (the plan's words)."""
        if self.wind == 0:
            return "no design wind"
        if self.along_track:
            return (
                f"from {self.wind_from:g} deg: each leg's climb and descent along its own track "
                "(the fastest ground speed on it; a helix flies every heading, so from any "
                "direction), the turning radius from any direction"
            )
        if self.wind_from is not None:
            return (
                f"from {self.wind_from:g} deg, held from any direction (conservative: the "
                "angles are stated, not derived from the rates)"
            )
        return "from any direction"

    @property
    def tas(self) -> float:
        return tas_from_eas(self.eas, self.altitude)

    @property
    def lowest_altitude(self) -> float:
        """The scenario's lowest altitude (m AMSL; ``altitude`` when not given)."""
        return self.altitude if self.low_altitude is None else self.low_altitude

    @property
    def tas_low(self) -> float:
        """The TAS at the scenario's lowest altitude (the slowest over the ground)."""
        return tas_from_eas(self.eas, self.lowest_altitude)

    @property
    def tas_flown(self) -> float:
        """The most TAS flown at ``altitude`` in the design wind: the TAS, raised into a
        headwind stronger than TAS - floor to W + floor (at most the largest airspeed) by the
        autopilot's ground-speed floor (PX4 FW_GND_SPD_MIN, FixedwingPositionControl.cpp
        get_auto_airspeed_setpoint; ArduPlane MIN_GNDSPD_CM, ArduPlane/navigation.cpp
        calc_gndspeed_undershoot). Taken as held through a turn: the airspeed loop lags the
        heading, so a turn out of the headwind starts at the raised TAS."""
        tas = self.tas
        floor = self.ground_speed_floor
        if floor <= 0 or self.wind <= tas - floor:
            return tas
        return max(tas, min(self.wind + floor, tas_from_eas(self.airspeed_max, self.altitude)))

    @property
    def ground_speed_max(self) -> float:
        return self.tas_flown + self.wind

    @property
    def climb_angle(self) -> float:
        return _angle(self.climb_rate, self.ground_speed_max)

    @property
    def descent_angle(self) -> float:
        return _angle(self.sink_rate, self.ground_speed_max)

    @property
    def turn_radius(self) -> float:
        """0 with no bank (straight legs)."""
        if self.bank_deg <= 0:
            return 0.0
        v = self.ground_speed_max
        return v * v / (G * math.tan(math.radians(self.bank_deg)))

    def low_envelope(self) -> tuple[float, float, float]:
        """(turning radius, climb angle, descent angle) at the scenario's lowest point: those
        of its lowest legs when the envelope is derived per leg."""
        v = self.tas_low + self.wind
        radius = v * v / (G * math.tan(math.radians(self.bank_deg))) if self.bank_deg > 0 else 0
        return radius, _angle(self.climb_rate, v), _angle(self.sink_rate, v)

    def refusals(self) -> list[tuple[str, str]]:
        """(field, why) for each input the envelope cannot be derived from; empty when sound."""
        bad = []
        if not (math.isfinite(self.eas) and 0 < self.eas <= 300):
            bad.append(("cruise_airspeed", f"must lie in (0, 300] m/s (got {self.eas!r})"))
        if not (math.isfinite(self.bank_deg) and 0 < self.bank_deg < 90):
            bad.append(("max_bank_angle", f"must lie in (0, 90) degrees (got {self.bank_deg!r})"))
        for name, v in (("max_climb_rate", self.climb_rate), ("max_sink_rate", self.sink_rate)):
            if not (v > 0) or math.isnan(v):
                bad.append((name, f"must be a rate > 0 m/s (got {v!r})"))
        if not (math.isfinite(self.wind) and self.wind >= 0):
            bad.append(("wind", f"must be a speed >= 0 m/s (got {self.wind!r})"))
        elif math.isfinite(self.eas) and self.eas > 0 and self.wind >= self.tas_low:
            # The slowest TAS: at the lowest point a headwind leaves the least ground speed.
            bad.append(
                (
                    "wind",
                    f"{self.wind:g} m/s is not below the true airspeed {self.tas_low:.1f} m/s "
                    f"({self.eas:g} m/s EAS at {self.lowest_altitude:.0f} m, the scenario's "
                    "lowest point): the "
                    "aircraft cannot make way against it",
                )
            )
        return bad

    def describe(self) -> list[str]:
        """Lines for the plan's output: each figure with how it was derived."""
        v = self.ground_speed_max
        wind = (
            "no design wind" if self.wind == 0
            else f"design wind {self.wind:g} m/s {self.wind_rule}"
        )  # fmt: skip
        src = ", ".join(f"{k} from {v}" for k, v in self.sources)
        where = (
            "the scenario's highest altitude; each leg flies within the figures of its own "
            "highest point, these at the top"
            if self.per_leg
            else "the scenario's highest altitude: conservative for every leg"
        )
        lines = [
            f"envelope derived for {self.autopilot or 'the aircraft'}: {self.eas:g} m/s EAS = "
            f"{self.tas:.2f} m/s TAS at {self.altitude:.0f} m (ISA, {where}); {wind}; ground "
            f"speed <= {v:.2f} m/s"
            + (
                f" (TAS raised to {self.tas_flown:.2f} m/s by the ground-speed floor of "
                f"{self.ground_speed_floor:g} m/s into the headwind)"
                if self.tas_flown > self.tas
                else ""
            ),
            (
                f"  turning radius R = (TAS + W)^2 / (g tan {self.bank_deg:.4g} deg) = "
                f"{self.turn_radius:.1f} m"
                if self.bank_deg > 0
                else "  straight legs (no turning radius)"
            ),
            "  climb <= atan(" + _rate_text(self.climb_rate) + " / (TAS + W)) = "
            f"{self.climb_angle:.2f} deg; descent <= atan("
            + _rate_text(self.sink_rate)
            + f" / (TAS + W)) = {self.descent_angle:.2f} deg",
        ]
        if self.per_leg:
            low = self.low_envelope()
            parts = {
                "turn_radius": f"R {low[0]:.1f} m",
                "max_climb_angle": f"climb {low[1]:.2f} deg",
                "max_descent_angle": f"descent {low[2]:.2f} deg",
            }
            lines.append(
                f"  per leg, from the TAS at its highest point: at the lowest point "
                f"({self.lowest_altitude:.0f} m, TAS {self.tas_low:.2f} m/s) "
                + ", ".join(parts[k] for k in self.per_leg)
            )
        if self.approach > 0 or self.departure > 0:
            lines.append(
                f"  straight at every landmark: run-in >= {self.approach:.0f} m, run-out "
                f"{self.departure:.0f} m ({self.runs_source})"
            )
        if src:
            lines.append(f"  inputs: {src}")
        return lines

    def to_dict(self) -> dict[str, object]:
        def num(x: float) -> float | None:
            return None if math.isinf(x) else float(x)

        low_radius, low_climb, low_descent = self.low_envelope()
        return {
            "autopilot": self.autopilot,
            "cruise_eas": self.eas,
            "altitude_m": self.altitude,
            "tas": self.tas,
            "low_altitude_m": self.lowest_altitude,
            "tas_low": self.tas_low,
            "bank_limit_deg": self.bank_deg,
            "climb_rate": num(self.climb_rate),
            "sink_rate": num(self.sink_rate),
            "design_wind": self.wind,
            "design_wind_from_deg": self.wind_from,
            "wind_rule": self.wind_rule,
            "along_track": self.along_track,
            "per_leg": list(self.per_leg),
            # at the lowest point: the lowest legs' figures when they are derived per leg
            "low_turn_radius": low_radius,
            "low_max_climb_angle": low_climb,
            "low_max_descent_angle": low_descent,
            "ground_speed_max": self.ground_speed_max,
            "turn_radius": self.turn_radius,
            "max_climb_angle": self.climb_angle,
            "max_descent_angle": self.descent_angle,
            "approach_m": self.approach,
            "departure_m": self.departure,
            "runs_source": self.runs_source,
            "derivation": (
                "TAS from EAS through ISA at each leg's highest altitude (the figures here at "
                "the scenario's highest); "
                if self.per_leg
                else "TAS from EAS through ISA at the scenario's highest altitude; "
            )
            + "angle = atan(rate / (TAS + W)); R = (TAS + W)^2 / (g tan(bank))",
            "sources": dict(self.sources),
        }


def _angle(rate: float, ground_speed: float) -> float:
    if math.isinf(rate):
        return UNLIMITED_ANGLE_DEG
    return math.degrees(math.atan2(rate, ground_speed))


def _rate_text(rate: float) -> str:
    return "unlimited" if math.isinf(rate) else f"{rate:g} m/s"


def parse_wind(text: str) -> tuple[float, float | None]:
    """``SPEED[@FROM_DEG]`` -> (speed m/s, direction it blows from in degrees or None);
    ValueError with the reason otherwise."""
    speed_text, _, from_text = str(text).partition("@")
    try:
        speed = float(speed_text)
        direction = float(from_text) if from_text else None
    except ValueError:
        raise ValueError(f"expected SPEED[@FROM_DEG], got {text!r}") from None
    if not (math.isfinite(speed) and speed >= 0):
        raise ValueError(f"wind speed must be a number >= 0 m/s, got {text!r}")
    if direction is not None and not math.isfinite(direction):
        raise ValueError(f"wind direction must be a number of degrees, got {text!r}")
    return speed, (None if direction is None else direction % 360.0)
