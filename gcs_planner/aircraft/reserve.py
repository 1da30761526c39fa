"""The flight reserve derived from what it must cover (docs/model.md, "Flight in the real
world", its flight reserve).

An aircraft under its autopilot flies more than the planned legs between two resets of an error:

* **Turn entry.** It begins a turn late and ends it on a line parallel to the planned one; a
  turn of theta entered ``d`` metres late flies d (1 - cos theta) metres more than the plan
  before it is back on the plan's line (d straight on past the tangent point, the same arc, and
  along the new line only d cos theta gained; the rejoin is a shallow S flown at once). The most
  is 2 d, for a U-turn. The planned arcs are flown at the roll limit at the largest ground speed
  (R = (V + W)^2 / (g tan phi)), so nothing is left to catch up with. How late is the
  autopilot's: ArduPlane's L1 controller steers at a point L1 = NAVL1_PERIOD * NAVL1_DAMPING *
  Vg / pi ahead on the chord of the densified arc it is flying (AP_L1_Control::update_waypoint),
  so it trails the arc by L1 / 2, and the aircraft's bank follows the bank asked as a lag of
  tau = ROLL_RESPONSE_S (gcs_planner/aircraft/profile.py), which starts each turn about tau late:
  d = L1 / 2 + tau Vg. (L1 / 2 alone fell short once the mock rolled into its turns: dataset 2
  at 10 m/s needed 0.55 L1 in its turns; benchmarks/turn_entry.py.)
  PX4's npfg (npfg.cpp) steers along the path within its track error bound and turns within a
  few metres of the arc, rolling in included (the mock: d up to 0.14 R): d = R / 2.
  An autopilot not named: the larger of the two. The start at A (the aircraft's own heading)
  and each helix (a loiter entered and left where its guidance does; the mock: up to 0.9 R)
  count as one U-turn each.
* **Gusts.** A cross gust moves the aircraft off its line at up to its own speed, and the
  guidance brings it back: the track's slope off the line is its cross-track rate over the
  *ground* speed Vg, and the wandering track is longer than its line by the mean of 1/cos of
  that slope, E[(y' / Vg)^2] / 2 of its length. The cross-track rate is the gust filtered by
  the closed loop (:func:`track_wander`): the autopilot's path follower is a second-order loop
  of natural frequency 2 pi / period and its damping (ArduPlane's L1 with NAVL1_PERIOD and
  NAVL1_DAMPING: linearised, y'' = -(2 pi / P)^2 y - 2 zeta (2 pi / P) y'; PX4's npfg with
  NPFG_PERIOD and NPFG_DAMPING), which acts through the aircraft's roll response
  (ROLL_RESPONSE_S), on a gust of Dryden's first-order spectrum (standard deviation sigma,
  correlation time L / TAS, L = DRYDEN_SCALE_LENGTH_M), so E[y'^2] = F sigma^2 with F the
  loop's share of the gust (0.07-0.15 at the shipped loops, F at the fastest TAS taken). The
  share taken is GUST_MARGIN F (sigma / Vg)^2 / 2 (0.25 for ArduPlane, 0.29 for PX4 at the
  workbooks' 10 km): the mock vehicle's straight legs flew 0.11-0.15 (sigma / Vg)^2 / 2 on
  average in every band of ground speed, above the factor on four legs of 867 (0.26-0.30)
  (benchmarks/gust_wander.py). Vg is the slowest: the TAS at the scenario's lowest point into
  a headwind of the design wind (in the leg-by-leg check, each leg's own lowest point), over
  the longest stretch the limits allow. (sigma / TAS)^2 / 2, the rule before, held in still
  air but fell to half the wander of a leg flown into the wind.

The planner keeps one reserve rho for every stretch (every limit becomes limit / delta - rho:
exact and cheap), so rho covers the turns of ``TURNS_PER_STRETCH`` legs (a stretch between two
resets of one error spans the leg to a point of the other kind and the leg from it; the first
one the start at A and one turn) and gusts over the longest stretch. A route whose stretches
hold more (two points of one kind in a row, helices) is checked leg by leg after the search
(:meth:`DerivedReserve.route_check`): the plan says so when a stretch needs more than rho.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from gcs_planner.aircraft.autopilot import AUTOPILOTS, autopilot_for, effective
from gcs_planner.aircraft.profile import (
    DEFAULT_RESERVE_MAX_SHARE,
    DRYDEN_SCALE_LENGTH_M,
    ROLL_RESPONSE_S,
    tas_from_eas,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Sequence


# What the reserve reads of a route (gcs_planner.core.route.Route is one): the aircraft's
# terms sit below the planner, so they name the shape, not the planner's class.
class _Kind(Protocol):
    name: str


class _Leg(Protocol):
    length: float
    turn_angle: float
    helix_turns: int


class _Stop(Protocol):
    id: str
    kind: _Kind
    leg: _Leg | None


class Route(Protocol):
    """A route as the reserve reads it: its stops, each with the leg that reaches it."""

    @property
    def stops(self) -> Sequence[_Stop]: ...


# The turns a stretch between two resets of one error is planned to hold (see the docstring).
TURNS_PER_STRETCH = 2
# The gusts' wander is taken at this many times the closed loop's estimate (module docstring).
GUST_MARGIN = 2.0
# The derived reserve, like the constant default, never takes more than this share of the
# tightest limit.
MAX_SHARE = DEFAULT_RESERVE_MAX_SHARE


@dataclass(frozen=True)
class DerivedReserve:
    """The reserve derived from turn entry and gusts (all metres, m/s, degrees).

    ``turn_radius``: the radius the arcs are flown at, at the roll limit ``bank_deg`` and the
    largest ground speed ``ground_speed`` (TAS ``tas`` plus the design wind); ``gust``: the
    design gust (standard deviation per horizontal axis); ``stretch``: the longest stretch the
    limits allow (the largest limit over delta); ``cap``: MAX_SHARE of the tightest limit.
    Gusts wander the track by ``wander`` (sigma / Vg)^2 / 2 of its length (track_wander() with
    GUST_MARGIN), Vg the TAS less the design ``wind``: ``slowest_tas`` (the scenario's lowest
    point; 0: ``tas``) for rho, each leg's own (from ``eas``) in the leg-by-leg check.
    """

    turn_radius: float
    tas: float
    ground_speed: float
    bank_deg: float
    autopilot: str | None
    gust: float
    stretch: float
    cap: float
    # d: how late a turn is entered (m), and the rule it came from (late_entry()).
    late: float = 0.0
    late_rule: str = ""
    turns: int = TURNS_PER_STRETCH
    wind: float = 0.0
    slowest_tas: float = 0.0
    eas: float = 0.0
    wander: float = 1.0
    wander_rule: str = ""

    @property
    def per_turn(self) -> float:
        """The most one turn adds: 2 d (a U-turn entered d late)."""
        return 2.0 * self.late

    @property
    def turn_term(self) -> float:
        return self.turns * self.per_turn

    @property
    def lowest_tas(self) -> float:
        """The TAS at the scenario's lowest point (``tas`` when not given)."""
        return self.slowest_tas or self.tas

    @property
    def slowest_ground_speed(self) -> float:
        """The TAS at the scenario's lowest point into a headwind of the design wind."""
        return self.lowest_tas - self.wind

    def gust_share_at(self, tas: float) -> float:
        """The share of a length flown at ``tas`` into a headwind that gusts add:
        wander (sigma / Vg)^2 / 2; infinite when the wind leaves no way over the ground."""
        if self.gust <= 0:
            return 0.0
        ground = tas - self.wind
        if ground <= 0:
            return math.inf
        return self.wander * 0.5 * (self.gust / ground) ** 2

    @property
    def gust_share(self) -> float:
        """The share of a stretch's length that gusts add, at the slowest ground speed."""
        return self.gust_share_at(self.lowest_tas)

    @property
    def gust_term(self) -> float:
        return self.gust_share * self.stretch

    @property
    def needed(self) -> float:
        return self.turn_term + self.gust_term

    @property
    def metres(self) -> float:
        """The reserve planned with: what it must cover, at most the cap."""
        return min(self.needed, self.cap)

    @property
    def capped(self) -> bool:
        return self.needed > self.cap

    def turn_extra(self, turn_rad: float) -> float:
        """What one turn of ``turn_rad`` radians adds: d (1 - cos theta)."""
        return self.late * (1.0 - math.cos(min(abs(turn_rad), math.pi)))

    def stretch_need(
        self,
        turns_rad: list[float],
        helices: int,
        starts: bool,
        length: float,
        gust_m: float | None = None,
    ) -> float:
        """What one stretch needs: its turns, its helices and the start at A (each one U-turn)
        and gusts over its ``length`` metres (``gust_m``: their metres worked out leg by leg;
        None: the share at the slowest ground speed)."""
        n_whole = helices + (1 if starts else 0)
        gusts = self.gust_share * length if gust_m is None else gust_m
        return sum(self.turn_extra(t) for t in turns_rad) + n_whole * self.per_turn + gusts

    def leg_gusts(self, length: float, low_altitude: float | None) -> float:
        """What gusts add to a leg of ``length`` metres whose lowest point is at
        ``low_altitude`` (None: the scenario's lowest), flown into the design wind."""
        if low_altitude is None or self.eas <= 0:
            return self.gust_share * length
        return self.gust_share_at(tas_from_eas(self.eas, low_altitude)) * length

    def route_gusts(
        self, route: Route, altitude_of: Callable[[str], float] | None = None
    ) -> list[float]:
        """What gusts add to each leg of ``route``, by the stop it leads to (0 at A), each at
        its own lowest point (``altitude_of`` a point's altitude; None: the scenario's
        lowest)."""
        stops = route.stops
        gusts = [0.0] * len(stops)
        for k in range(1, len(stops)):
            leg = stops[k].leg
            if leg is not None:
                low = (
                    None
                    if altitude_of is None
                    else min(altitude_of(stops[k - 1].id), altitude_of(stops[k].id))
                )
                gusts[k] = self.leg_gusts(leg.length, low)
        return gusts

    def route_check(
        self, route: Route, altitude_of: Callable[[str], float] | None = None
    ) -> tuple[float, str, str]:
        """(the most one stretch of ``route`` needs, its first and last point): each stretch
        between a reset of an error (or A) and a check of it, leg by leg; ``altitude_of`` a
        point's altitude (m, above sea level) for each leg's own gusts."""
        stops = route.stops
        gusts = self.route_gusts(route, altitude_of)
        worst, frm, to = 0.0, stops[0].id, stops[0].id
        last = {"V": 0, "H": 0}  # index of the stop where each error was last reset
        for k in range(1, len(stops)):
            for start in set(last.values()):
                legs = [s.leg for s in stops[start + 1 : k + 1] if s.leg is not None]
                # The leg from A has no turn of its own (its heading is free): the start counts.
                need = self.stretch_need(
                    [leg.turn_angle for leg in legs],
                    sum(1 for leg in legs if leg.helix_turns > 0),
                    start == 0,
                    sum(leg.length for leg in legs),
                    sum(gusts[start + 1 : k + 1]),
                )
                if need > worst:
                    worst, frm, to = need, stops[start].id, stops[k].id
            kind = stops[k].kind.name
            if kind in last:
                last[kind] = k
        return worst, frm, to

    def describe(self) -> str:
        """The reserve with how it was derived, for the plan's summary."""
        who = self.autopilot or "the aircraft"
        text = (
            f"derived for {who}: turn entry {self.turns} x {self.per_turn:.0f} m (a U-turn "
            f"entered d = {self.late:.0f} m late flies 2d more; {self.late_rule}; R = "
            f"{self.turn_radius:.0f} m at {self.ground_speed:.1f} m/s ground speed, "
            f"{self.tas:.1f} m/s TAS, {self.bank_deg:.4g} deg bank)"
        )
        if self.gust > 0:
            text += (
                f" + gusts {self.gust:g} m/s over {self.stretch / 1000:,.1f} km at "
                f"{self.slowest_ground_speed:.1f} m/s ground speed ({self.lowest_tas:.1f} m/s "
                f"TAS at the lowest point into {self.wind:g} m/s; {self.wander:.2f} "
                f"(sigma/Vg)^2/2 = {100 * self.gust_share:.3g} %: {self.gust_term:.0f} m; "
                f"{self.wander_rule})"
            )
        else:
            text += " + no gusts (--gust SPEED adds them)"
        if self.capped:
            text += f" = {self.needed:.0f} m, capped at 5 % of the tightest limit"
        return text

    def to_dict(self) -> dict[str, object]:
        return {
            "source": "derived",
            "metres": self.metres,
            "needed": self.needed,
            "cap": self.cap,
            "capped": self.capped,
            "turn_radius": self.turn_radius,
            "tas": self.tas,
            "ground_speed": self.ground_speed,
            "bank_limit_deg": self.bank_deg,
            "autopilot": self.autopilot,
            "late_entry_m": self.late,
            "late_entry_rule": self.late_rule,
            "per_turn_m": self.per_turn,
            "turns": self.turns,
            "turn_term_m": self.turn_term,
            "gust": self.gust,
            "design_wind": self.wind,
            "slowest_tas": self.lowest_tas,
            "slowest_ground_speed": self.slowest_ground_speed,
            "gust_wander": self.wander,
            "gust_wander_rule": self.wander_rule,
            "gust_share": self.gust_share,
            "stretch_m": self.stretch,
            "gust_term_m": self.gust_term,
            "derivation": "turns x 2d + wander (gust / Vg)^2 / 2 x longest stretch, Vg the "
            "slowest ground speed (a turn of theta entered d late flies d (1 - cos theta) "
            "more), at most 5 % of the tightest limit",
        }


def late_entry(
    autopilot: str | None,
    turn_radius: float,
    ground_speed: float,
    values: Mapping[str, float] | None = None,
) -> tuple[float, str]:
    """(d, its rule): how late ``autopilot`` enters a turn of ``turn_radius`` metres flown at
    ``ground_speed`` m/s (see the module docstring); None: the larger of every autopilot's.
    ``values``: the vehicle's own parameters (``--vehicle-from``; its NAVL1_PERIOD and
    NAVL1_DAMPING), else the shipped defaults."""
    # ArduPlane's L1 trails the arc; both autopilots' aircraft roll in over ROLL_RESPONSE_S,
    # which npfg's R/2 already holds (it turns within a few metres of the arc).
    found = {}
    for name, ap in AUTOPILOTS.items():
        if ap.path_follower == "L1":
            own = dict(values or {}) if autopilot == name else {}
            l1 = effective(name, own).settle_distance(ground_speed)
            found[name] = (
                l1 / 2.0 + ROLL_RESPONSE_S * ground_speed,
                f"{ap.code_name}'s L1 = {l1:.0f} m{_tuned(name, own)}, d = L1/2 + "
                f"{ROLL_RESPONSE_S:g} s of roll-in x {ground_speed:.1f} m/s",
            )
        else:
            found[name] = (turn_radius / 2.0, f"{ap.code_name}'s npfg, d = R/2")
    if autopilot in found:
        return found[autopilot]
    d, rule = max(found.values())
    return d, f"the autopilot not named: the larger of {_every_code_name()}, {rule}"


def _every_code_name() -> str:
    names = [f"{ap.code_name}'s" for ap in AUTOPILOTS.values()]
    return ", ".join(names[:-1]) + " and " + names[-1]


def track_wander(
    period: float, damping: float, correlation_time: float, roll_response: float = ROLL_RESPONSE_S
) -> float:
    """E[y'^2] / sigma^2: the share of a gust's power that reaches the cross-track rate y' of an
    aircraft whose path follower is the linear loop y'' = -w^2 y - 2 zeta w y' (w = 2 pi /
    ``period``, zeta = ``damping``), its lateral acceleration following the command as a
    first-order lag of ``roll_response`` s, in a gust of first-order (Dryden) spectrum with
    ``correlation_time`` s. The gust enters the ground velocity directly, so y' / v =
    s^2 (1 + T s) / (T s^3 + s^2 + 2 zeta w s + w^2); infinite when that loop is unstable."""
    from scipy.integrate import quad

    w0 = 2.0 * math.pi / period
    tr, tau = roll_response, correlation_time
    if 2.0 * damping * w0 <= tr * w0 * w0:  # Routh: the lagged loop does not settle
        return math.inf

    def power(w: float) -> float:
        s = 1j * w
        h = s * s * (1 + tr * s) / (tr * s**3 + s * s + 2 * damping * w0 * s + w0 * w0)
        return abs(h) ** 2 * 2.0 * tau / (1.0 + (w * tau) ** 2) / math.pi

    # Split where the loop and the gust live: quad meets both peaks.
    knees = sorted({1.0 / tau, w0, 1.0 / tr if tr > 0 else w0})
    edges = [0.0, *knees, 10.0 * knees[-1]]
    total = sum(quad(power, a, b, limit=200)[0] for a, b in zip(edges, edges[1:], strict=False))
    return total + quad(power, edges[-1], math.inf, limit=200)[0]


def gust_wander(
    autopilot: str | None, tas: float, values: Mapping[str, float] | None = None
) -> tuple[float, str]:
    """(the factor on (sigma / Vg)^2 / 2, its rule) for ``autopilot``'s path follower at
    ``tas`` (the fastest TAS: the gust's correlation time L / TAS is then shortest and the
    loop passes most of it); None: the larger of every autopilot's. ``values``: the vehicle's
    own parameters (its NAVL1_PERIOD / NAVL1_DAMPING or NPFG_PERIOD / NPFG_DAMPING), else the
    shipped defaults."""
    tau = DRYDEN_SCALE_LENGTH_M / max(tas, 1.0)
    found = {}
    for name, ap in AUTOPILOTS.items():
        own = values if autopilot == name else None
        period, damping = effective(name, dict(own or {})).guidance_loop()
        found[name] = (
            track_wander(period, damping, tau),
            f"{ap.code_name}'s {ap.path_follower}" + _tuned(name, own),
        )
    if autopilot in found:
        f, who = found[autopilot]
    else:
        f, who = max(found.values())
    rule = f"{who} passes F = {f:.3f} of the gust's power at {tas:.1f} m/s TAS, x {GUST_MARGIN:g}"
    return GUST_MARGIN * f, rule


def _tuned(firmware: str, values: Mapping[str, float] | None) -> str:
    """The text ``" (the vehicle's NAVL1_PERIOD 20, ...)"`` for the guidance parameters
    ``values`` gives, ``""`` when it gives none (the shipped defaults)."""
    given = [f"{k} {float(values[k]):g}" for k in autopilot_for(firmware).guidance
             if values and k in values]  # fmt: skip
    return f" (the vehicle's {', '.join(given)})" if given else ""
