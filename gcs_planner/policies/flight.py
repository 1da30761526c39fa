"""The ground station in the loop: fly a contingency policy (docs/model.md, "Contingency
policies") by switching missions in flight.

Upload and verify the primary mission, start it (or wait for the operator to), then watch the
vehicle's correction reports (gcs_planner/link/correction_report.py). When a fix fails (or is
missed) at a point where the policy switches, upload the branch's mission, verify it as
``upload`` does (read back, or the vehicle's CRC over MAVFTP), set its resume item current and
see it confirmed (COMMAND_ACK accepted and MISSION_CURRENT at that item). Each event is one
line.

What the vehicle holds if a branch cannot be uploaded: PX4 receives into the storage it is not
flying and keeps flying its mission until an upload completes, so it still holds the mission
flown, whole; ArduPilot writes each item in place as it arrives (sim/live_flight.py), so a
failed upload leaves it holding the branch's first items and the old mission's last ones, which
it would fly. The ground station therefore reads the mission back after a failed branch upload
and, if it is not the mission flown, uploads that mission again (its items before the failed
point are the branch's own, so nothing behind the aircraft changes). Only if that fails too is
the vehicle left on a mission that is not whole, and the error says so.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gcs_planner.aircraft.autopilot import AUTOPILOTS, keeps_home_item
from gcs_planner.errors import InputError, LinkError, UploadRefused
from gcs_planner.link.connection import mavlink
from gcs_planner.link.correction_report import CorrectionReport, parse_report
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import mission_differences
from gcs_planner.mission.policy_missions import PolicyMissions, Switch

MAV_MODE_FLAG_SAFETY_ARMED = 128
# How long the vehicle may stay silent (no message of any kind) before the flight is given up
# as unwatched: a telemetry link streams several messages a second.
DEFAULT_SILENCE_S = 10.0


class VehicleSilent(LinkError):
    """The vehicle stopped reporting."""


class _ReportTap:
    """The link as MissionClient sees it, handing every message it receives to ``observe``
    first: reports that arrive during a transfer are not lost to the transfer's own wait."""

    def __init__(self, link: Any, observe: Callable[[Any], None]) -> None:
        self._link = link
        self._observe = observe

    def recv(self, timeout: float) -> Any | None:
        msg = self._link.recv(timeout)
        if msg is not None:
            self._observe(msg)
        return msg

    def __getattr__(self, name: str) -> Any:
        return getattr(self._link, name)


@dataclass(frozen=True)
class PolicyOutcome:
    """How the flight went, as the ground station saw it."""

    missions_flown: tuple[str, ...]  # the primary, then each branch switched to
    reports: tuple[CorrectionReport, ...]
    switches: int
    ended: str  # "landed" (the vehicle disarmed: its flight is over)


class PolicyFlight:
    """Fly ``policy`` on the vehicle of ``client`` (connected), saying each event to ``say``."""

    def __init__(
        self,
        client: MissionClient,
        policy: PolicyMissions,
        *,
        say: Callable[[str], None] = print,
        silence: float = DEFAULT_SILENCE_S,
        attempts: int = 3,
    ) -> None:
        self.client = client
        self.policy = policy
        self.say = say
        self.silence = silence
        self.attempts = attempts
        self.flown = policy.primary
        self.flown_names = [policy.primary]
        self.reports: deque[CorrectionReport] = deque()
        self.seen: list[CorrectionReport] = []
        self.reported: set[str] = set()
        self.unreported_warned: set[str] = set()
        self.armed: bool | None = None
        # Whether the vehicle has been seen flying (an armed HEARTBEAT, an item reached, a
        # correction report) and, after that, disarmed: the flight is over. A flight is known by
        # any of these, not by its armed HEARTBEAT alone: a flight in the dry run's time warp can
        # start and end between two heartbeats (1 Hz), and the one that said armed may be lost.
        self.flew = False
        self.ended = False
        self.current: int | None = None
        self.heard = time.monotonic()
        self.t0 = time.monotonic()
        client.link = _ReportTap(client.link, self._observe)  # type: ignore[assignment]

    # Listening -------------------------------------------------------------------------------
    def _observe(self, msg: Any) -> None:
        if msg.get_srcSystem() != self.client.target_system:
            return
        self.heard = time.monotonic()
        kind = msg.get_type()
        if kind == "STATUSTEXT":
            report = parse_report(getattr(msg, "text", None))
            # Each report comes in copies (a STATUSTEXT is not acknowledged); a landmark is
            # used once per flight, so the first copy for a point is the report.
            if report is not None:
                self.flew = True  # a fix is made in flight only
            if report is not None and report.point not in self.reported:
                self.reported.add(report.point)
                self.reports.append(report)
        elif kind == "HEARTBEAT" and msg.get_srcComponent() == self.client.target_component:
            self.armed = bool(msg.base_mode & MAV_MODE_FLAG_SAFETY_ARMED)
            if self.armed:
                self.flew = True
            elif self.flew:
                # Disarmed after it flew: over. A disarmed HEARTBEAT from before the flight
                # (sent as the start was taken) comes before any sign of flight on the link.
                self.ended = True
        elif kind == "MISSION_ITEM_REACHED":
            self.flew = True
        elif kind == "MISSION_CURRENT":
            self.current = int(msg.seq)

    def _line(self, text: str) -> None:
        self.say(f"t+{time.monotonic() - self.t0:6.1f} s  {text}")

    def _listen(self, seconds: float) -> None:
        """Read the link for ``seconds``; a vehicle silent for longer than ``silence`` is an
        error."""
        end = time.monotonic() + seconds
        while (left := end - time.monotonic()) > 0:
            self.client.link.recv(min(left, 0.2))
            self._check_heard()

    def _check_heard(self) -> None:
        quiet = time.monotonic() - self.heard
        if quiet > self.silence:
            raise VehicleSilent(
                f"the vehicle stopped reporting: nothing heard for {quiet:.0f} s while it flies "
                f"mission {self.flown!r}; it holds that mission (whole, verified) and flies on "
                "without the ground station: watch it on another link"
            )

    # Flying ----------------------------------------------------------------------------------
    def run(self, *, start: bool = True, start_wait: float = 600.0) -> PolicyOutcome:
        """Upload the primary, start it (``start``; else wait up to ``start_wait`` s for the
        operator to), and follow the policy until the vehicle disarms."""
        primary = self.policy.missions[self.policy.primary]
        report = self._upload(self.policy.primary, primary.items)
        self._line(
            f"uploaded and verified mission {self.policy.primary!r} "
            f"({len(primary.items)} items) in {report.seconds:.2f} s"
        )
        if start:
            self._start()
        else:
            self._line("waiting for the operator to start the mission (mode AUTO, armed)")
        deadline = time.monotonic() + start_wait
        while not self.flew:
            if time.monotonic() > deadline:
                raise LinkError(f"the vehicle did not start the mission within {start_wait:g} s")
            self._listen(0.2)
        self._line(f"flying mission {self.flown!r}")
        switches = 0
        while True:
            while self.reports:
                r = self.reports.popleft()
                self.seen.append(r)
                self._line(f"{r.kind} fix {r.point} {r.outcome}")
                switch = self.policy.switch_for(self.flown, r.point) if r.no_fix else None
                if switch is not None:
                    self._switch(switch, r.point)
                    switches += 1
            self._warn_unreported()
            if self.ended:
                self._line(f"the vehicle disarmed: flight over on mission {self.flown!r}")
                return PolicyOutcome(tuple(self.flown_names), tuple(self.seen), switches, "landed")
            self._listen(0.2)

    def _warn_unreported(self) -> None:
        """A switch point the vehicle has flown well past (two items on) without a report: its
        reports were all lost or it sends none; the policy cannot act on it. Said once."""
        if self.current is None:
            return
        for s in self.policy.switches:
            if s.mission != self.flown or s.point in self.reported:
                continue
            if self.current >= s.item + 2 and s.point not in self.unreported_warned:
                self.unreported_warned.add(s.point)
                self._line(
                    f"WARNING: no correction report for point {s.point} (item {s.item}), "
                    f"now at item {self.current}: the policy cannot switch there"
                )

    def _start(self) -> None:
        start_mission(self.client, flying=lambda: self.flew)
        self._line("mission started (MAV_CMD_MISSION_START accepted)")

    def _upload(self, name: str, items: Any) -> Any:
        errors = []
        for _ in range(self.attempts):
            try:
                return self.client.upload_verified(items)
            except LinkError as exc:
                errors.append(str(exc))
                if isinstance(exc, UploadRefused):
                    break  # the vehicle said no: asking again gets the same answer
        raise LinkError(f"mission {name!r} could not be uploaded: {errors[-1]}")

    def _switch(self, switch: Switch, point: str) -> None:
        to = switch.to_mission
        mission = self.policy.missions[to]
        if not self.policy.changes_items(switch):
            # The same items (only switches further on differ): nothing to upload, and no item
            # set current that would turn the aircraft back to it.
            self._line(
                f"following mission {to!r} after the failed fix at {point}: the same items as "
                f"{self.flown!r}, nothing to upload"
            )
            self.flown = to
            self.flown_names.append(to)
            return
        self._line(f"switching to mission {to!r} after the failed fix at {point}")
        old = self.policy.missions[self.flown].items
        try:
            report = self._upload(to, mission.items)
        except LinkError as exc:
            raise self._keep_flown(str(exc)) from None
        self._line(
            f"uploaded and verified mission {to!r} ({len(mission.items)} items) in "
            f"{report.seconds:.2f} s"
        )
        self.flown = to  # the vehicle holds it now, whole
        self.flown_names.append(to)
        resume = _resume_item(switch.resume_item, self.current, old, mission.items)
        self._set_current(resume)
        self._line(f"item {resume} current (confirmed): flying mission {to!r}")

    def _set_current(self, seq: int) -> None:
        """MAV_CMD_DO_SET_MISSION_CURRENT until the vehicle accepts it and says MISSION_CURRENT
        ``seq``. The acknowledgement is required: the item number alone may already be current
        in the old mission (a branch resumes at the number the primary had there)."""
        ts, tc = self.client._target()
        cmd = self.client.mav.command_long_encode(
            ts, tc, mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 0, seq, 0, 0, 0, 0, 0, 0
        )
        # The vehicle may say MISSION_CURRENT before its COMMAND_ACK (the mock does, as
        # ArduPilot's handler sends it on the way): both, in either order and from any copy
        # (they are the same command), confirm. Each copy sent while unconfirmed is one more
        # the vehicle takes, so none is sent once both have come.
        accepted = current = False
        for _ in range(2 * (self.client.retries + 1)):
            self.client.link.send(cmd)
            end = time.monotonic() + self.client.timeout
            while (left := end - time.monotonic()) > 0:
                msg = self.client._recv(left, {"COMMAND_ACK", "MISSION_CURRENT"}, None)
                if msg is None:
                    break
                if msg.get_type() == "COMMAND_ACK":
                    if msg.command != mavlink.MAV_CMD_DO_SET_MISSION_CURRENT:
                        continue
                    if msg.result != mavlink.MAV_RESULT_ACCEPTED:
                        raise LinkError(
                            f"the vehicle refused to make item {seq} current "
                            f"(result {msg.result}): it holds mission "
                            f"{self.flown!r} but may fly its old item"
                        )
                    accepted = True
                else:
                    current = current or int(msg.seq) == seq
                if accepted and current:
                    return
            self._check_heard()
        raise LinkError(
            f"setting item {seq} of mission {self.flown!r} current was not "
            "confirmed: the vehicle holds that mission, whole"
        )

    def _keep_flown(self, why: str) -> LinkError:
        """After a branch upload failed: make sure the vehicle holds the mission it was flying,
        whole (see the module docstring); the error to raise, saying what it holds."""
        flown = self.policy.missions[self.flown]
        skip_home = keeps_home_item(self.client.firmware)
        try:
            held = self.client.download()
            whole = not mission_differences(list(flown.items), held, skip_home=skip_home)
        except LinkError:
            whole = False
        if whole:
            return LinkError(
                f"{why}; the vehicle still holds mission {self.flown!r}, whole "
                "(read back), and flies it"
            )
        if not writes_in_place(self.client.firmware):
            # PX4 receives into the storage it is not flying: it still flies the mission it had.
            return LinkError(f"{why}; the vehicle (PX4) keeps mission {self.flown!r} until an "
                            "upload completes, and flies it (not read back)")  # fmt: skip
        try:
            self._upload(self.flown, flown.items)
        except LinkError as exc:
            return LinkError(
                f"{why}; restoring mission {self.flown!r} failed too ({exc}): the "
                "vehicle may hold part of the branch: take control"
            )
        return LinkError(
            f"{why}; the vehicle had stored part of it: mission {self.flown!r} "
            "uploaded again and verified, it flies that"
        )


def start_mission(client: MissionClient, flying: Callable[[], bool] | None = None) -> None:
    """MAV_CMD_MISSION_START until the vehicle acknowledges it (LinkError when it refuses or
    never answers). ``flying``: whether the vehicle has been seen flying since; then its start
    was taken and its acknowledgement lost, and the command is not sent again (a copy reaching
    a vehicle whose flight is already over would start the mission once more)."""
    ts, tc = client._target()
    msg = client.mav.command_long_encode(
        ts, tc, mavlink.MAV_CMD_MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0
    )
    for _ in range(client.retries + 1):
        client.link.send(msg)
        ack = client._recv(client.timeout, {"COMMAND_ACK"}, None)
        if ack is not None and ack.command == mavlink.MAV_CMD_MISSION_START:
            if ack.result != mavlink.MAV_RESULT_ACCEPTED:
                raise LinkError(f"the vehicle refused to start the mission (result {ack.result})")
            return
        if flying is not None and flying():
            return
    raise LinkError("the vehicle did not answer MAV_CMD_MISSION_START")


def check_policy(policy: PolicyMissions, source: str = "") -> None:
    """One clear line (InputError) for a policy whose missions and switches do not fit
    together: unknown missions, items out of range, a switch point that is not a waypoint, a
    branch whose items before the failed point differ from its parent's."""
    names = set(policy.missions)
    if policy.primary not in names:
        raise InputError(
            f"the primary mission {policy.primary!r} is not among the missions",
            file=source,
            field="primary",
        )
    firmwares = {m.firmware for m in policy.missions.values()}
    if len(firmwares) > 1:
        raise InputError(
            f"the missions are for different firmwares: {sorted(firmwares)}",
            file=source,
            field="missions",
        )
    seen = set()
    for k, s in enumerate(policy.switches):
        field = f"switches[{k}]"
        for name in (s.mission, s.to_mission):
            if name not in names:
                raise InputError(
                    f"mission {name!r} is not among the missions", file=source, field=field
                )
        if (s.mission, s.point) in seen:
            raise InputError(
                f"two switches at point {s.point} of mission {s.mission!r}",
                file=source,
                field=field,
            )
        seen.add((s.mission, s.point))
        parent, branch = policy.missions[s.mission], policy.missions[s.to_mission]
        if dict(parent.point_seqs).get(s.point, s.item) != s.item:
            raise InputError(
                f"point {s.point} is item {dict(parent.point_seqs)[s.point]} of "
                f"mission {s.mission!r}, not {s.item}",
                file=source,
                field=field,
            )
        if not 0 <= s.item < len(parent.items) or parent.items[s.item].command != 16:
            raise InputError(
                f"item {s.item} of mission {s.mission!r} is not a waypoint",
                file=source,
                field=field,
            )
        if not s.item < s.resume_item < len(branch.items):
            raise InputError(
                f"resume item {s.resume_item} is not after item {s.item} in "
                f"mission {s.to_mission!r} ({len(branch.items)} items)",
                file=source,
                field=field,
            )
        same = mission_differences(
            list(parent.items[: s.item + 1]), list(branch.items[: s.item + 1])
        )
        if same:
            raise InputError(
                f"mission {s.to_mission!r} differs from {s.mission!r} before the "
                f"failed point: {same[0]}",
                file=source,
                field=field,
            )


def _resume_item(resume: int, current: int | None, old: Any, new: Any) -> int:
    """Where the vehicle goes on in the branch: the switch's resume item, unless the vehicle
    has gone past it while the upload ran (setting it would turn the aircraft back to it:
    ArduPlane and PX4 fly to the current item from wherever the aircraft is). Then: the item it
    flies already, when every item before that one is the same in both missions; else the
    branch's first item of its own (the first that differs from the old mission), flown
    from where the aircraft is."""
    if current is None or current <= resume:
        return resume
    shared = 0
    for a, b in zip(old, new):
        if a != b:
            break
        shared += 1
    if current <= shared and current < len(new):
        return current
    return max(resume, min(shared, len(new) - 1))


def writes_in_place(firmware: str | None) -> bool:
    """Whether ``firmware`` writes each uploaded item into the mission it flies (ArduPilot), so
    that a failed upload leaves it holding part of the new mission; False for an autopilot that
    receives into storage it is not flying (PX4). An autopilot without a record is taken to
    write in place: the ground station then checks what it holds."""
    ap = AUTOPILOTS.get(firmware or "")
    return ap is None or ap.protocol is None or ap.protocol.writes_in_place
