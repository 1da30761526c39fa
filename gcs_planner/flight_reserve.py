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
  so it trails the arc: d = L1 / 2 (the mock ArduPlane, rolling into its turns, needs up to
  0.42 L1 on the contest routes at winds 0-10 m/s and 0.55 L1 on dataset 2 at 10 m/s, where
  the rule falls short: benchmarks/turn_entry.py). PX4's npfg (npfg.cpp) steers along the path
  within its track error bound and turns within a few metres of the arc (the mock: d up to
  0.14 R): d = R / 2.
  An autopilot not named: the larger of the two. The start at A (the aircraft's own heading)
  and each helix (a loiter entered and left where its guidance does; the mock: up to 0.9 R)
  count as one U-turn each.
* **Gusts.** A cross gust of sigma m/s turns the track by about sigma / V, and the guidance
  brings it back: the wandering track is longer than its line by the mean of 1/cos of that
  angle, (sigma / V)^2 / 2 of its length, over the longest stretch the limits allow.

The planner keeps one reserve rho for every stretch (every limit becomes limit / delta - rho:
exact and cheap), so rho covers the turns of ``TURNS_PER_STRETCH`` legs (a stretch between two
resets of one error spans the leg to a point of the other kind and the leg from it; the first
one the start at A and one turn) and gusts over the longest stretch. A route whose stretches
hold more (two points of one kind in a row, helices) is checked leg by leg after the search
(:meth:`DerivedReserve.route_check`): the plan says so when a stretch needs more than rho.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from gcs_planner.vehicle import DEFAULT_RESERVE_MAX_SHARE

if TYPE_CHECKING:
    from gcs_planner.core.route import Route

# The turns a stretch between two resets of one error is planned to hold (see the docstring).
TURNS_PER_STRETCH = 2
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

    @property
    def per_turn(self) -> float:
        """The most one turn adds: 2 d (a U-turn entered d late)."""
        return 2.0 * self.late

    @property
    def turn_term(self) -> float:
        return self.turns * self.per_turn

    @property
    def gust_share(self) -> float:
        """The share of a stretch's length that gusts add: (sigma / V)^2 / 2."""
        return 0.5 * (self.gust / self.tas) ** 2 if self.tas > 0 else 0.0

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
        self, turns_rad: list[float], helices: int, starts: bool, length: float
    ) -> float:
        """What one stretch needs: its turns, its helices and the start at A (each one U-turn)
        and gusts over its ``length`` metres."""
        n_whole = helices + (1 if starts else 0)
        return (
            sum(self.turn_extra(t) for t in turns_rad)
            + n_whole * self.per_turn
            + self.gust_share * length
        )

    def route_check(self, route: Route) -> tuple[float, str, str]:
        """(the most one stretch of ``route`` needs, its first and last point): each stretch
        between a reset of an error (or A) and a check of it, leg by leg."""
        stops = route.stops
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
                f" + gusts {self.gust:g} m/s over {self.stretch / 1000:,.1f} km "
                f"((sigma/V)^2/2 = {100 * self.gust_share:.3g} %: {self.gust_term:.0f} m)"
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
            "gust_share": self.gust_share,
            "stretch_m": self.stretch,
            "gust_term_m": self.gust_term,
            "derivation": "turns x 2d + (gust / TAS)^2 / 2 x longest stretch (a turn of theta "
            "entered d late flies d (1 - cos theta) more), at most 5 % of the tightest limit",
        }


def late_entry(autopilot: str | None, turn_radius: float, ground_speed: float) -> tuple[float, str]:
    """(d, its rule): how late ``autopilot`` enters a turn of ``turn_radius`` metres flown at
    ``ground_speed`` m/s (see the module docstring); None: the larger of both autopilots'."""
    from gcs_planner.autopilot import effective

    l1 = effective("ardupilot", {}).settle_distance(ground_speed)
    ardupilot = (l1 / 2.0, f"ArduPlane's L1 = {l1:.0f} m, d = L1/2")
    px4 = (turn_radius / 2.0, "PX4's npfg, d = R/2")
    if autopilot == "ardupilot":
        return ardupilot
    if autopilot == "px4":
        return px4
    d, rule = max(ardupilot, px4)
    return d, f"the autopilot not named: the larger of ArduPlane's L1/2 and PX4's R/2, {rule}"
