"""Room to switch missions after a failed fix (docs/model.md, "Contingency policies").

A contingency policy is flown by switching missions in flight, and a switch takes time: the
vehicle reports its fix when the true track leaves the landmark's capture radius, then the
ground station uploads the branch's mission, reads it back and sets its resume item. All that
while the aircraft flies on along the primary mission. A branch planned from the failed point
assumes the aircraft is there, on its arrival heading; if the primary has already turned towards
its own next point when the branch is set current, the aircraft turns back and flies a leg no
plan accounted for (a dry run of dataset 2 within 15 deg/15 deg lost such switches at the next
point).

So a policy is planned with every run-out (the straight leg after each point, docs/model.md
"Straight at every landmark") at least the *switch distance*: the capture radius plus the
switch time at the largest ground speed. Primary and branch share that run-out (the same heading
from the same point), so the aircraft is still on it, on the branch's own path, when the branch
is set current at its departure waypoint (the switch's resume item). The run-out is flown and
counted in the errors like any other metre, so every figure of the policy includes it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs_planner.aircraft.profile import tas_from_eas
from gcs_planner.scenario.model import Scenario

# Seconds from the fix to the branch flying, switched on board (the default: the policy's
# onboard mission and applet, docs/flying-policies.md): the correction sensor's report to the
# autopilot (a PARAM_SET on its serial port, acknowledged, resent if lost), one tick of the
# applet (0.1 s) and the navigator's next cycle, with room for the report coming a flight
# model's step late (the mock's: 0.5 s).
ONBOARD_SWITCH_TIME_S = 1.0
DEFAULT_SWITCH_TIME_S = ONBOARD_SWITCH_TIME_S
# ... switched by the ground station (`fly` without --onboard): the report (sent three times,
# 0.5 s apart), the upload of a mission of ~150 items and its read-back over a telemetry radio
# with some loss (a SiK radio at 57,600 baud moves ~40 MISSION_ITEM_INT a second each way), and
# the set-current command with its acknowledgement.
GROUND_SWITCH_TIME_S = 10.0


@dataclass(frozen=True)
class SwitchRoom:
    """The straight run-out a policy keeps after every point so that a switch fits in it."""

    switch_time: float  # s, from the fix to the branch set current
    ground_speed: float  # m/s, the largest the aircraft flies at (TAS at the highest point + W)
    capture_radius: float  # m, the report comes as the track leaves it
    departure_before: float  # m, the run-out the envelope asked for on its own

    @property
    def distance(self) -> float:
        return self.capture_radius + self.switch_time * self.ground_speed

    @property
    def departure(self) -> float:
        return max(self.departure_before, self.distance)

    def describe(self) -> str:
        return (
            f"switch room: every run-out >= {self.distance:.0f} m = capture radius "
            f"{self.capture_radius:g} m + switch time {self.switch_time:g} s x ground speed "
            f"{self.ground_speed:.1f} m/s (run-out {self.departure:.0f} m, "
            f"{self.departure_before:.0f} m without a policy): a branch is set current while "
            "the aircraft is still on the run-out it shares with the primary"
        )

    def to_dict(self) -> dict[str, float]:
        return {
            "switch_time_s": self.switch_time,
            "ground_speed": self.ground_speed,
            "capture_radius_m": self.capture_radius,
            "distance_m": self.distance,
            "departure_m": self.departure,
        }


def switch_room(scenario: Scenario, switch_time: float) -> SwitchRoom:
    """The switch room of ``scenario``'s aircraft with ``switch_time`` seconds to switch.

    The ground speed is the derived envelope's largest (TAS at the highest point plus the
    design wind) or, for an envelope stated as angles and a radius, the cruise airspeed as TAS
    at the scenario's highest altitude (ISA)."""
    if not (math.isfinite(switch_time) and switch_time >= 0):
        raise ValueError(f"switch time must be a number of seconds >= 0, got {switch_time!r}")
    env = scenario.envelope
    if env is not None:
        speed = env.ground_speed_max
    else:
        top = float(scenario.xyz[:, 2].max()) + (scenario.origin.alt if scenario.origin else 0.0)
        speed = tas_from_eas(scenario.cruise_airspeed, top)
    return SwitchRoom(switch_time, speed, scenario.capture_radius, scenario.params.departure)


def applies(scenario: Scenario) -> bool:
    """Whether legs have run-outs at all: airplane legs with a turning radius (straight legs
    turn on the spot at each point, so the branch leaves from the point itself)."""
    return scenario.params.turn_radius > 0 and scenario.leg_model == "airplane"


def with_switch_room(scenario: Scenario, room: SwitchRoom) -> Scenario:
    """``scenario`` with every run-out at least the switch distance."""
    if not applies(scenario) or room.departure <= scenario.params.departure:
        return scenario
    return scenario.with_params(departure=room.departure)
