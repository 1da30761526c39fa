"""``gcs-planner fly --onboard``: a contingency policy switched on board by a companion computer,
for an autopilot that runs no applets (PX4), or beside one that does.

The companion sits on the vehicle's local link (a serial port or UDP to the autopilot), so no
ground link is needed. It makes sure the autopilot holds the onboard mission
(mission/onboard_mission.py: the primary and each branch's own items behind it), uploading and
verifying it when it does not, starts it (or waits for the operator to), then follows the same
rules as ArduPilot's applet (mission/onboard_applet.py): on a report that the fix at a switch
point did not take (the correction report, gcs_planner/link/correction_report.py, FAILED or
MISSED) it makes the branch's first item current (MAV_CMD_DO_SET_MISSION_CURRENT, confirmed);
a switch point whose run-out the aircraft leaves without a report is taken as failed; a branch
with the same items is followed without a jump. Nothing is uploaded in flight.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.errors import LinkError
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import mission_differences
from gcs_planner.mission.onboard_mission import OnboardMission, OnboardSwitch, onboard_mission
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.policies.flight import DEFAULT_SILENCE_S, PolicyFlight, PolicyOutcome

UPLOAD_ATTEMPTS = 3


@dataclass
class OnboardRules:
    """The applet's rules (policy.lua's ``switch``), for a companion: which switch is due."""

    onboard: OnboardMission
    flying: str = ""
    reported: dict[str, str] = field(default_factory=dict)  # point -> its report's outcome
    taken: set[int] = field(default_factory=set)  # switches acted on

    def __post_init__(self) -> None:
        self.flying = self.flying or self.onboard.primary

    def report(self, point: str, outcome: str) -> None:
        """A correction report (its first copy counts: a landmark is used once per flight)."""
        self.reported.setdefault(point, outcome)

    def due(self, index: int | None) -> tuple[int, OnboardSwitch, int, str] | None:
        """(switch number, switch, onboard item to make current, why) of the switch to take now
        with the vehicle at onboard item ``index`` (None: not known yet), or None."""
        for k, s in enumerate(self.onboard.switches):
            if s.mission != self.flying or k in self.taken:
                continue
            outcome = self.reported.get(s.point)
            if outcome in ("FAILED", "MISSED"):
                why = "failed" if outcome == "FAILED" else "missed"
            elif outcome is None and index is not None and index > s.item + 1:
                why = "no report"
            else:
                continue
            late = index is not None and index > s.item + 1
            return k, s, s.late if late else s.resume, why
        return None

    def took(self, k: int) -> None:
        self.taken.add(k)
        self.flying = self.onboard.switches[k].to_mission


class CompanionFlight(PolicyFlight):
    """Fly ``policy`` switched on board from the vehicle's local link (module docstring)."""

    def __init__(
        self,
        client: MissionClient,
        policy: PolicyMissions,
        *,
        say: Callable[[str], None] = print,
        silence: float = DEFAULT_SILENCE_S,
    ) -> None:
        super().__init__(client, policy, say=say, silence=silence, attempts=UPLOAD_ATTEMPTS)
        self.onboard = onboard_mission(policy)
        self.rules = OnboardRules(self.onboard)

    def run(self, *, start: bool = True, start_wait: float = 600.0) -> PolicyOutcome:
        self._hold_onboard()
        if start:
            self._start()
        else:
            self._line("waiting for the operator to start the mission (mode AUTO, armed)")
        self._wait_armed(start_wait)
        self._line(f"flying the onboard mission, on {self.flown!r}")
        switches = 0
        while True:
            while self.reports:
                r = self.reports.popleft()
                self.seen.append(r)
                self._line(f"{r.kind} fix {r.point} {r.outcome}")
                self.rules.report(r.point, r.outcome)
            due = self.rules.due(self.current)
            if due is not None:
                switches += self._take(*due)
            if self.ended:  # disarmed after it was seen flying (PolicyFlight._observe)
                self._line(f"the vehicle disarmed: flight over on mission {self.flown!r}")
                return PolicyOutcome(tuple(self.flown_names), tuple(self.seen), switches, "landed")
            self._listen(0.05)

    def _hold_onboard(self) -> None:
        """The vehicle holds the onboard mission: read back, else uploaded and verified (a
        companion restarted in flight finds it there and uploads nothing)."""
        items = list(self.onboard.mission.items)
        try:
            held = self.client.download()
            skip_home = keeps_home_item(self.client.firmware)
            same = not mission_differences(items, held, skip_home=skip_home)
        except LinkError:
            same = False
        if same:
            self._line(f"the vehicle holds the onboard mission ({len(items)} items, read back)")
            return
        report = self._upload("onboard", items)
        self._line(
            f"uploaded and verified the onboard mission ({len(items)} items) in "
            f"{report.seconds:.2f} s"
        )

    def _wait_armed(self, start_wait: float) -> None:
        deadline = time.monotonic() + start_wait
        while not self.flew:  # any sign of flight, not the armed HEARTBEAT alone
            if time.monotonic() > deadline:
                raise LinkError(f"the vehicle did not start the mission within {start_wait:g} s")
            self._listen(0.2)

    def _take(self, k: int, s: OnboardSwitch, target: int, why: str) -> int:
        """Take switch ``k`` (``why``: failed, missed, no report); 1 when an item was set."""
        self.rules.took(k)
        self.flown = s.to_mission
        self.flown_names.append(s.to_mission)
        if not s.jump:
            self._line(f"{s.point} {why}: following {s.to_mission!r}, the same items")
            return 0
        self._set_current(target)
        self._line(f"{s.point} {why}: item {target} current (confirmed), flying {s.to_mission!r}")
        return 1
