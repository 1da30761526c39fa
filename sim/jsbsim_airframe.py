"""A second flight model: JSBSim's flight dynamics under the mock vehicle's navigators.

The point mass (sim/aircraft.py) banks and climbs the instant its guidance asks. Here the same
navigators (sim/navigators/: L1 / npfg lateral acceleration, the climb-rate target of the glide
slope) fly a JSBSim airframe (``pip install '.[jsbsim]'``; the project's own aerosonde,
gcs_planner/aircraft/airframes, or an aircraft shipped with the ``jsbsim`` package, the c172r
by default; sim/jsbsim_trim.py loads and trims them) through the ISA atmosphere (JSBSim's own
standard atmosphere) and the dry run's wind, gusts and vertical turbulence (sim/wind.py, set as
JSBSim's wind every outer step). Between the navigator's steps an autopilot of the usual shape
runs at the FDM's rate (``RATE_HZ``):

* lateral: the lateral acceleration a becomes a bank command -atan(a / g) within the roll limit
  (ArduPlane ROLL_LIMIT_DEG, PX4 FW_R_LIM); a PD loop on the roll angle drives the ailerons, a
  sideslip loop the rudder (turn coordination);
* longitudinal, TECS-like (ArduPlane AP_TECS, PX4 TECS: throttle for the total energy rate,
  pitch for the balance between height and speed): the climb rate asked, clipped to the
  autopilot's climb and sink rates and slewed, and the airspeed error give a flight-path angle
  and an acceleration demand; throttle = trim + feed-forward of the climb + PI on the specific
  total energy rate; pitch = trim + the flight-path angle + PI on the energy balance; when the
  throttle is at its stop and the airspeed falls, the balance weighs speed only (TECS's
  underspeed protection); a PD loop on the pitch angle drives the elevator.

The aircraft is trimmed (JSBSim's full trim) at the cruise equivalent airspeed at the start
altitude on the start heading, in the start wind. The mission's legs are checked before the
flight against trims at their altitudes (``FlightModel.limits``): level flight at the cruise
airspeed, the leg's climb, the bank its turns need; what the airframe cannot do is reported
with where and why, and such a mission is not flown at all (sim/guidance.py ``fly``). In
flight, what it could not hold for long (airspeed, climb, bank) is reported too
(``JSBSimAirframe.shortfalls``).

Position: the local frame is flat (x east, y north, z up, metres), JSBSim's is the WGS84
ellipsoid. The horizontal position is the integral of JSBSim's NED ground velocity over each
FDM step, not its latitude and longitude converted, so that the flight lives in exactly the
frame the navigators and the landmarks use (no second projection to disagree with pyproj's);
over a 100 km mission the two differ by the frame's own flat-earth error only. The altitude is
JSBSim's altitude above sea level less the frame's origin altitude.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

from gcs_planner.sim import atmosphere
from gcs_planner.sim.aircraft import AircraftState, Envelope
from gcs_planner.sim.jsbsim_trim import (  # noqa: F401 - the flight's names, imported from here
    FT,
    AirframeLimit,
    Trim,
    _new_fdm,
    _quiet,
    available_aircraft,
    trim,
)

from gcs_planner.aircraft.profile import G

RATE_HZ = 60.0  # FDM and inner loops (the 50-120 Hz; ArduPlane's fast loop is 50 Hz)
# The c172r: the c172x's controls have hysteresis (0.05 rad on the elevator) that makes any
# inner loop limit-cycle; the c172r's have none.
DEFAULT_AIRCRAFT = "c172r"
OUTER_STEP_S = 0.5
# Inner loops (per radian of error): roll to aileron, pitch to elevator, sideslip to rudder.
ROLL_KP, ROLL_KI, ROLL_KD = 2.0, 1.0, 0.4
ROLL_RATE = math.radians(70.0)
ROLL_I_BAND = math.radians(10.0)
PITCH_KP, PITCH_KD = 4.0, 1.0
YAW_K = 0.5
# TECS-like energy loops.
SPEED_GAIN = 0.25  # 1/s: acceleration asked per m/s of airspeed error
ACCEL_LIMIT = 1.0  # m/s^2
THR_KP, THR_KI = 2.0, 0.5  # throttle per unit of specific energy rate error (rad)
PITCH_B_KP, PITCH_B_KI = 2.0, 0.3  # pitch (rad) per unit of balance rate error
# The airspeed rate the energy loops read, low-passed (s): gusts make it jump every step.
VDOT_TAU_S = 1.0
CLIMB_SLEW = 3.0  # m/s^2: how fast the climb demand may change (slower oscillated with the
# navigators' altitude loop when it was 1 s, at their 0.5 s step)
# In flight, a shortfall held this long is reported (seconds), and how far off counts.
SHORTFALL_S = 10.0
AIRSPEED_SHORT_MPS = 3.0
CLIMB_SHORT_MPS = 0.5
BANK_SHORT_DEG = 5.0
FULL_THROTTLE = 0.9
WATCH_S = 5.0


_NODES = {
    "phi": "attitude/phi-rad", "theta": "attitude/theta-rad", "vt": "velocities/vt-fps",
    "ve": "velocities/ve-fps", "vdown": "velocities/v-down-fps", "p": "velocities/p-rad_sec",
    "q": "velocities/q-rad_sec", "beta": "aero/beta-rad", "veast": "velocities/v-east-fps",
    "vnorth": "velocities/v-north-fps", "aileron": "fcs/aileron-cmd-norm",
    "rudder": "fcs/rudder-cmd-norm", "elevator": "fcs/elevator-cmd-norm",
    "throttle": "fcs/throttle-cmd-norm",
}  # fmt: skip


@dataclass
class Shortfall:
    """Something the airframe could not hold for ``SHORTFALL_S`` seconds in flight."""

    t: float
    x: float
    y: float
    z: float
    kind: str  # "airspeed" | "climb" | "bank"
    text: str


@dataclass
class _Held:
    since: float | None = None
    reported: bool = False


class JSBSimAirframe:
    """One flight's JSBSim aircraft with its inner loops, stepped by a navigator (the
    ``Airframe`` of sim/navigators/base.py)."""

    exact = False  # JSBSim's state cannot be rewound: no cut or lengthened outer steps

    def __init__(
        self,
        aircraft: str,
        start: AircraftState,
        airspeed: float,
        alt_offset: float,
        *,
        wind: tuple[float, float] = (0.0, 0.0),
        rate_hz: float = RATE_HZ,
    ) -> None:
        self.aircraft = aircraft
        self.alt_offset = alt_offset
        self.rate = rate_hz
        self.fdm = _new_fdm(aircraft, rate_hz)
        h = start.z + alt_offset
        got = trim(self.fdm, h, airspeed, course=start.course, wind=wind)
        if got is None:
            raise AirframeLimit(
                f"the {aircraft} cannot be trimmed level at {airspeed:g} m/s EAS at the start "
                f"altitude {h:,.0f} m (JSBSim finds no trim)"
            )
        self.trim = got
        # The climb feed-forward: throttle per radian of flight-path angle, from a trim 3
        # degrees up (or a c172-like 2.3 when that one fails).
        up = trim(self.fdm, h, airspeed, gamma_deg=3.0, course=start.course, wind=wind)
        self.thr_per_rad = (up.throttle - got.throttle) / math.radians(3.0) if up else 2.3
        trim(self.fdm, h, airspeed, course=start.course, wind=wind)  # back to level
        pm = self.fdm.get_property_manager()
        self._node = {key: pm.get_node(name) for key, name in _NODES.items()}
        self.i_roll = 0.0
        self.phi_demand = 0.0
        self.wind = (float(wind[0]), float(wind[1]), 0.0)
        self.x, self.y, self.t = start.x, start.y, start.t
        self.vz_demand = 0.0
        self.i_thr = 0.0
        self.i_pitch = 0.0
        self.v_prev = float(self.fdm["velocities/vt-fps"]) * FT
        self.vdot = 0.0
        self.throttle = got.throttle
        self.shortfalls: list[Shortfall] = []
        self._held = {k: _Held() for k in ("airspeed", "climb", "bank")}
        self._t_watch = start.t
        self._climb_avg = self._demand_avg = 0.0
        self._thr_avg = got.throttle

    # The inner loops, one FDM step ------------------------------------------------------------
    def _control(self, env: Envelope, phi_c: float, vz_c: float, dt: float) -> None:
        n = self._node
        phi = n["phi"].get_double_value()
        theta = n["theta"].get_double_value()
        v = max(n["vt"].get_double_value() * FT, 1.0)
        ve = max(n["ve"].get_double_value() * FT, 1.0)
        vz = -n["vdown"].get_double_value() * FT
        # Lateral: roll PID to the ailerons (the integral holds the propeller's torque),
        # sideslip to the rudder.
        # The bank command is slewed at the autopilot's roll-rate limit (ArduPlane
        # RLL_RATE_MAX / PX4 FW_R_RMAX: 70 deg/s here), the integral only near it.
        slew = ROLL_RATE * dt
        self.phi_demand += min(max(phi_c - self.phi_demand, -slew), slew)
        e_phi = self.phi_demand - phi
        if abs(e_phi) < ROLL_I_BAND:
            self.i_roll = min(max(self.i_roll + ROLL_KI * e_phi * dt, -0.5), 0.5)
        p = n["p"].get_double_value()
        n["aileron"].set_double_value(_clip(ROLL_KP * e_phi + self.i_roll - ROLL_KD * p))
        n["rudder"].set_double_value(_clip(-YAW_K * n["beta"].get_double_value()))
        # Longitudinal, TECS-like. The climb demand is slewed (no step in the flight path).
        step = CLIMB_SLEW * dt
        self.vz_demand += min(max(vz_c - self.vz_demand, -step), step)
        vt_c = env.airspeed * v / ve  # the EAS held, as a true airspeed here
        vdot_c = min(max(SPEED_GAIN * (vt_c - v), -ACCEL_LIMIT), ACCEL_LIMIT)
        self.vdot += (((v - self.v_prev) / dt) - self.vdot) * min(1.0, dt / VDOT_TAU_S)
        self.v_prev = v
        gamma_c = math.asin(min(max(self.vz_demand / v, -0.5), 0.5))
        gamma = math.asin(min(max(vz / v, -0.5), 0.5))
        e_total = (gamma_c + vdot_c / G) - (gamma + self.vdot / G)
        thr = self.trim.throttle + self.thr_per_rad * gamma_c + THR_KP * e_total + self.i_thr
        saturated = not 0.0 < thr < 1.0
        if not saturated or (thr >= 1.0) != (e_total > 0):  # no wind-up at the stops
            self.i_thr += THR_KI * e_total * dt
        self.throttle = min(max(thr, 0.0), 1.0)
        n["throttle"].set_double_value(self.throttle)
        # Underspeed (throttle at its stop and slow): the balance weighs speed only.
        under = thr >= 1.0 and v < vt_c - 1.0
        w_h, w_v = (0.0, 2.0) if under else (1.0, 1.0)
        e_bal = (w_h * gamma_c - w_v * vdot_c / G) - (w_h * gamma - w_v * self.vdot / G)
        self.i_pitch = min(max(self.i_pitch + PITCH_B_KI * e_bal * dt, -0.3), 0.3)
        # A banked wing needs more lift: a little more pitch in the turn.
        turn = (1.0 / max(math.cos(phi), 0.3) - 1.0) * max(self.trim.theta, 0.03)
        theta_c = self.trim.theta + w_h * gamma_c + PITCH_B_KP * e_bal + self.i_pitch + turn
        if env.pitch_limit_deg < 90.0:
            # TECS clips its pitch demand at the limit of auto flight (TECS_PITCH_MAX,
            # FW_P_LIM_MAX).
            theta_c = min(theta_c, math.radians(env.pitch_limit_deg))
        q = n["q"].get_double_value()
        n["elevator"].set_double_value(_clip(-(PITCH_KP * (theta_c - theta) - PITCH_KD * q)))

    def step(
        self,
        s: AircraftState,
        env: Envelope,
        lateral_accel: float,
        climb_rate: float,
        dt: float,
        wind: Sequence[float] = (0.0, 0.0),
        eas2tas: float = 1.0,
        heading: float | None = None,
    ) -> AircraftState:
        """Fly ``dt`` seconds (whole FDM steps) towards the navigator's demands through
        ``wind`` (east, north, and up in turbulence, m/s); ``s`` is the state returned last
        (JSBSim holds the truth)."""
        f = self.fdm
        limit = math.radians(min(env.bank_limit_deg, 89.0))
        phi_c = min(max(-math.atan(lateral_accel / G), -limit), limit)
        vz_c = min(max(climb_rate, -env.sink_rate), env.climb_rate)
        h = 1.0 / self.rate
        n = max(1, round(dt * self.rate))
        east, north = self._node["veast"], self._node["vnorth"]
        # The wind moves from the last step's to this one's over the step's FDM steps: set
        # at once, a gust's change would be a jump in airspeed that the energy loops (which
        # differentiate it) read as a violent deceleration.
        # The vertical air (sim/turbulence.py) reaches the airframe as JSBSim's wind down: it
        # changes the angle of attack and the lift, and the inner loops fly it out.
        w1 = (float(wind[0]), float(wind[1]), float(wind[2]) if len(wind) > 2 else 0.0)
        (w0x, w0y, w0z), self.wind = self.wind, w1
        for i in range(n):
            u = (i + 1) / n
            f["atmosphere/wind-east-fps"] = (w0x + (w1[0] - w0x) * u) / FT
            f["atmosphere/wind-north-fps"] = (w0y + (w1[1] - w0y) * u) / FT
            f["atmosphere/wind-down-fps"] = -(w0z + (w1[2] - w0z) * u) / FT
            self._control(env, phi_c, vz_c, h)
            f.run()
            self.x += east.get_double_value() * FT * h
            self.y += north.get_double_value() * FT * h
        self.t += n * h
        out = self.state()
        self._watch(env, phi_c, vz_c, out)
        return out

    def state(self) -> AircraftState:
        f = self.fdm
        ve, vn = f["velocities/v-east-fps"] * FT, f["velocities/v-north-fps"] * FT
        return AircraftState(
            self.x,
            self.y,
            f["position/h-sl-ft"] * FT - self.alt_offset,
            math.atan2(vn, ve),
            self.t,
            float(f["attitude/phi-deg"]),
            -f["velocities/v-down-fps"] * FT,
            _wrap(math.pi / 2 - f["attitude/psi-rad"]),
            f["velocities/vt-fps"] * FT,
            math.hypot(ve, vn),
        )

    def _watch(self, env: Envelope, phi_c: float, vz_c: float, s: AircraftState) -> None:
        """Record what could not be held for SHORTFALL_S seconds (once per kind and episode)."""
        ve = self.fdm["velocities/ve-fps"] * FT
        z = s.z + self.alt_offset
        # Judged on averages over WATCH_S: in gusts and turns the climb rate and the throttle
        # swing for a moment now and then, which must not restart the clock of a climb the
        # airframe cannot make.
        k = min(1.0, (s.t - self._t_watch) / WATCH_S)
        self._t_watch = s.t
        self._climb_avg += (s.climb_rate - self._climb_avg) * k
        self._demand_avg += (self.vz_demand - self._demand_avg) * k
        self._thr_avg += (self.throttle - self._thr_avg) * k
        full = self._thr_avg >= FULL_THROTTLE
        checks = {
            "airspeed": (
                ve < env.airspeed - AIRSPEED_SHORT_MPS,
                f"held {ve:.1f} m/s of the {env.airspeed:g} m/s EAS asked at {z:,.0f} m"
                + (f" at {self._thr_avg:.0%} throttle" if full else ""),
            ),
            "climb": (
                full
                and self._climb_avg < self._demand_avg - CLIMB_SHORT_MPS
                and self._demand_avg > 0,
                f"climbed {self._climb_avg:.1f} m/s of the {self._demand_avg:.1f} m/s asked at "
                f"{z:,.0f} m at {self._thr_avg:.0%} throttle (averages over {WATCH_S:g} s), "
                f"{abs(s.bank_deg):.0f} deg of bank",
            ),
            "bank": (
                abs(s.bank_deg) < abs(math.degrees(phi_c)) - BANK_SHORT_DEG,
                f"banked {abs(s.bank_deg):.0f} deg of the {abs(math.degrees(phi_c)):.0f} deg "
                f"asked at {z:,.0f} m",
            ),
        }
        for kind, (short, text) in checks.items():
            held = self._held[kind]
            if not short:
                held.since, held.reported = None, False
                continue
            if held.since is None:
                held.since = s.t
            if not held.reported and s.t - held.since >= SHORTFALL_S:
                held.reported = True
                self.shortfalls.append(Shortfall(s.t, s.x, s.y, s.z, kind, text))


@dataclass(frozen=True)
class LegNeed:
    """What one leg of the mission asks of the airframe (from the items, before the flight)."""

    seq: int  # the item the leg flies to
    top: float  # highest altitude of the leg, m above sea level
    gamma_deg: float  # flight-path angle asked (> 0 climbing)
    bank_deg: float  # bank its turns need at the top (0: none asked)


@dataclass
class FlightModel:
    """JSBSim as the dry run's flight model: which aircraft, at what rate."""

    aircraft: str = DEFAULT_AIRCRAFT
    rate_hz: float = RATE_HZ
    # The navigator's step (s). JSBSim cannot fly a step again to stop on a waypoint's
    # acceptance circle or finish line, so the autopilot switches up to one step late (23 m at
    # 0.5 s). A 0.1 s step was tried (docs/jsbsim.md, again after the wind fix): PX4 then
    # switches on time and is lost at B as the point mass is (8 m off); but in gusts the finer
    # step draws other gusts, in which the c172r cannot make its climbs at full throttle
    # (ArduPlane misses V2, PX4 circles a waypoint for altitude until the time limit), so the
    # default stays the dry run's.
    outer_step: float = OUTER_STEP_S
    _cache: dict = field(default_factory=dict, repr=False)

    def describe(self) -> str:
        return f"JSBSim {self.aircraft} (inner loops at {self.rate_hz:g} Hz)"

    def airframe(
        self,
        start: AircraftState,
        airspeed: float,
        alt_offset: float,
        wind: tuple[float, float] = (0.0, 0.0),
    ) -> JSBSimAirframe:
        return JSBSimAirframe(
            self.aircraft, start, airspeed, alt_offset, wind=wind, rate_hz=self.rate_hz
        )

    def _fdm(self):  # noqa: ANN202
        if "fdm" not in self._cache:
            self._cache["fdm"] = _new_fdm(self.aircraft, self.rate_hz)
        return self._cache["fdm"]

    def _trims(self, top: float, eas: float, gamma: float, bank: float) -> Trim | None:
        key = (round(top, 0), eas, round(gamma, 2), round(bank, 1))
        if key not in self._cache:
            self._cache[key] = trim(self._fdm(), top, eas, gamma_deg=gamma, bank_deg=bank)
        return self._cache[key]

    def trims_level(self, altitude: float, eas: float) -> bool:
        """Whether the aircraft trims in level flight at ``eas`` at ``altitude`` (m AMSL)."""
        return self._trims(altitude, eas, 0.0, 0.0) is not None

    def best_climb_deg(self, top: float, eas: float) -> float:
        """The steepest flight-path angle (degrees, 0.25 apart) trimmed at ``top``."""
        lo, hi = 0.0, 20.0
        if self._trims(top, eas, 0.0, 0.0) is None:
            return -math.inf
        while hi - lo > 0.25:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self._trims(top, eas, mid, 0.0) else (lo, mid)
        return lo

    def limits(self, needs: Sequence[LegNeed], eas: float) -> list[str]:
        """Where and why the airframe cannot fly the legs at ``eas``: no level trim at a leg's
        top, a climb beyond its best there, a turn beyond what it can bank."""
        out: list[str] = []
        for leg in needs:
            where = f"leg to item {leg.seq} (up to {leg.top:,.0f} m)"
            if self._trims(leg.top, eas, 0.0, 0.0) is None:
                out.append(
                    f"{where}: the {self.aircraft} cannot fly level at {eas:g} m/s EAS at "
                    f"{leg.top:,.0f} m (no trim: beyond its ceiling or speed range there)"
                )
                continue
            if leg.gamma_deg > 0 and self._trims(leg.top, eas, leg.gamma_deg, 0.0) is None:
                best = self.best_climb_deg(leg.top, eas)
                tas = eas * atmosphere.eas2tas(leg.top)
                out.append(
                    f"{where}: climbs {leg.gamma_deg:.1f} deg "
                    f"({tas * math.sin(math.radians(leg.gamma_deg)):.1f} m/s), the "
                    f"{self.aircraft} at full throttle climbs at most {best:.1f} deg "
                    f"({tas * math.sin(math.radians(best)):.1f} m/s) there at {eas:g} m/s EAS"
                )
            if leg.bank_deg > 0 and self._trims(leg.top, eas, 0.0, leg.bank_deg) is None:
                out.append(
                    f"{where}: its turns need {leg.bank_deg:.0f} deg of bank; the "
                    f"{self.aircraft} cannot hold a level turn at that bank at {eas:g} m/s "
                    f"EAS there (no trim)"
                )
        return out


@dataclass
class CheckedPointMass:
    """The dry run's point mass (sim/aircraft.py ``step``, the numba kernel) with each leg checked
    before the flight against a JSBSim aircraft's trims at its altitude, as ``FlightModel``
    checks them (``dry-run --aircraft NAME`` without ``--flight-model jsbsim``): the engine's
    power, speed range and ceiling judged at the speed of the point mass. ``airframe`` is None:
    the flight is the point mass's."""

    checker: FlightModel

    def describe(self) -> str:
        return (
            f"point mass (rolls into its turns; climbs at the autopilot's rates within its pitch "
            f"limit), each "
            f"leg checked before the flight against JSBSim {self.checker.aircraft}'s trims at "
            "its altitude (engine power, speed range, ceiling)"
        )

    def limits(self, needs: Sequence[LegNeed], eas: float) -> list[str]:
        return self.checker.limits(needs, eas)

    def airframe(
        self,
        start: AircraftState,
        airspeed: float,
        alt_offset: float,
        wind: tuple[float, float] = (0.0, 0.0),
    ) -> None:
        """None (the point mass flies), once the aircraft trims level where it starts."""
        h = start.z + alt_offset
        if not self.checker.trims_level(h, airspeed):
            raise AirframeLimit(
                f"the {self.checker.aircraft} cannot be trimmed level at {airspeed:g} m/s EAS "
                f"at the start altitude {h:,.0f} m (JSBSim finds no trim)"
            )
        return None


def _clip(u: float) -> float:
    return min(max(u, -1.0), 1.0)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi
