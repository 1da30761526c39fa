"""The mission's one-exchange work items: clear the mission, make an item current, and check
that the vehicle has the loiter-radius parameter an upload sets.

Each waits for the vehicle's answer with the session's timeout and resends up to its retries;
a refusal is a :class:`~gcs_planner.errors.LinkError` saying what the vehicle answered.
"""

from __future__ import annotations

import time
from enum import Enum

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink
from gcs_planner.link.params import read_parameter
from gcs_planner.link.protocol import describe_result
from gcs_planner.link.session import VehicleSession

_COMMAND_OK = (mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_IN_PROGRESS)
_SET_CURRENT_ANSWERS = {"MISSION_CURRENT", "COMMAND_ACK", "STATUSTEXT"}


class _Answer(Enum):
    """What a vehicle said to a request to make an item current, short of a refusal."""

    NOTHING = "nothing within the timeout"
    CURRENT = "its MISSION_CURRENT names the item"
    UNSUPPORTED = "MAV_CMD_DO_SET_MISSION_CURRENT is not supported"


def clear(session: VehicleSession, mission_type: int) -> None:
    """MISSION_CLEAR_ALL, confirmed by MISSION_ACK."""
    ts, tc = session._target()
    msg_out = session.mav.mission_clear_all_encode(ts, tc, mission_type)
    for _ in range(session.retries + 1):
        session.link.send(msg_out)
        msg = session._recv(session.timeout, {"MISSION_ACK"}, mission_type)
        if msg is None:
            session.retry_count += 1
            continue
        if msg.type == mavlink.MAV_MISSION_ACCEPTED:
            return
        raise LinkError(f"clear refused: {describe_result(msg.type)}")
    raise session._give_up("clear: MISSION_CLEAR_ALL")


def set_current(session: VehicleSession, seq: int) -> None:
    """Make ``seq`` the current item: MAV_CMD_DO_SET_MISSION_CURRENT, falling back to the
    older MISSION_SET_CURRENT when the vehicle does not support the command; success is the
    MISSION_CURRENT the vehicle broadcasts."""
    ts, tc = session._target()
    command = session.mav.command_long_encode(
        ts, tc, mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 0, seq, 0, 0, 0, 0, 0, 0
    )
    legacy = session.mav.mission_set_current_encode(ts, tc, seq)
    use_legacy = False
    for _ in range(session.retries + 1):
        session.link.send(legacy if use_legacy else command)
        answer = _current_answer(session, seq)
        if answer is _Answer.CURRENT:
            return
        if answer is _Answer.UNSUPPORTED:
            use_legacy = True
        session.retry_count += 1
    raise session._give_up(f"set current item {seq}")


def _current_answer(session: VehicleSession, seq: int) -> _Answer:
    """What the vehicle said within the timeout to a request to make ``seq`` current; a
    refusal is a :class:`LinkError`."""
    deadline = time.monotonic() + session.timeout
    while (remaining := deadline - time.monotonic()) > 0:
        msg = session._recv(remaining, _SET_CURRENT_ANSWERS, None)
        if msg is None:
            return _Answer.NOTHING
        kind = msg.get_type()
        if kind == "MISSION_CURRENT" and int(msg.seq) == seq:
            return _Answer.CURRENT
        if kind == "COMMAND_ACK" and msg.command == mavlink.MAV_CMD_DO_SET_MISSION_CURRENT:
            if msg.result == mavlink.MAV_RESULT_UNSUPPORTED:
                return _Answer.UNSUPPORTED
            if msg.result not in _COMMAND_OK:
                raise LinkError(f"the vehicle refused to make item {seq} current")
        # The vehicle's own words of a refusal (ArduPilot says why in a STATUSTEXT).
        if kind == "STATUSTEXT" and "current" in str(msg.text).lower():
            raise LinkError(f"the vehicle refused to make item {seq} current: {msg.text}")
    return _Answer.NOTHING


def check_loiter_parameter(session: VehicleSession) -> None:
    """Raise a :class:`LinkError` naming the parameter when the vehicle has no loiter-radius
    parameter under its autopilot's name (autopilots stay silent about unknown names)."""
    ap = session.autopilot()
    name = ap.loiter_radius_param
    try:
        read_parameter(session.link, session._target(), name, timeout=session.timeout, retries=1)
    except LinkError:
        raise LinkError(
            f"the vehicle did not answer a read of {name}, the {ap.firmware} loiter radius "
            "the plan's turning radius is set in; nothing was uploaded (use "
            "--keep-loiter-radius to upload without setting it)"
        ) from None
