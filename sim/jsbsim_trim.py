"""JSBSim's aircraft loaded and trimmed: the jsbsim package's aircraft and the project's own
(gcs_planner/aircraft/airframes, e.g. the ``aerosonde``), JSBSim's chatter silenced, and its
trim at an equivalent airspeed, altitude, flight-path angle or bank (sim/jsbsim_airframe.py
flies them; gcs_planner/aircraft/airframe_trim.py derives a plan's envelope from them)."""

from __future__ import annotations

import ctypes
import io
import math
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from gcs_planner.sim import atmosphere

from gcs_planner.aircraft.shipped_airframes import AIRFRAMES_DIR, is_shipped, shipped_airframes

FT = 0.3048
# JSBSim's trim modes (FGTrim::SetMode): longitudinal, full, turn.
_LONGITUDINAL, _FULL, _TURN = 0, 1, 5

_LIBC = ctypes.CDLL(None)


class AirframeLimit(Exception):
    """The airframe cannot be flown as asked (no trim at the start)."""


@contextmanager
def _quiet() -> Iterator[None]:
    """JSBSim writes its banner, trim reports and output-file errors to std::cout, which the
    jsbsim module may pass on to Python's sys.stdout or leave on the C stream: silence both,
    so a dry run's text (and its --json) stays the dry run's."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    py_out, py_err = sys.stdout, sys.stderr
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        sys.stdout = sys.stderr = io.StringIO()
        yield
    finally:
        sys.stdout, sys.stderr = py_out, py_err
        # std::cout is synchronised with C's stdout, which buffers when not a terminal: flush
        # it into /dev/null before the descriptors are put back.
        _LIBC.fflush(None)
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def available_aircraft() -> list[str]:
    """The aircraft JSBSim can fly here: the project's own (``shipped_airframes``) and those
    shipped with the jsbsim package (their folder names)."""
    import jsbsim

    root = os.path.join(jsbsim.get_default_root_dir(), "aircraft")
    theirs = (d for d in os.listdir(root) if os.path.isfile(os.path.join(root, d, f"{d}.xml")))
    return sorted({*theirs, *shipped_airframes()})


def _new_fdm(aircraft: str, rate_hz: float):  # noqa: ANN202 - jsbsim.FGFDMExec
    import jsbsim

    with _quiet():
        fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
        fdm.set_debug_level(0)
        if is_shipped(aircraft):
            # The project's own airframe: its folder holds the aircraft and its engines.
            fdm.set_aircraft_path(str(AIRFRAMES_DIR))
        if not fdm.load_model(aircraft):
            raise AirframeLimit(f"JSBSim cannot load the aircraft {aircraft!r}")
        fdm.disable_output()
    fdm.set_dt(1.0 / rate_hz)
    return fdm


def _psi_deg(course: float) -> float:
    """JSBSim's heading (degrees clockwise from north) of a local angle (rad CCW from east)."""
    return (90.0 - math.degrees(course)) % 360.0


@dataclass
class Trim:
    throttle: float
    theta: float  # rad
    pitch_trim: float


def trim(
    fdm,  # noqa: ANN001 - jsbsim.FGFDMExec
    altitude_msl: float,
    eas: float,
    *,
    gamma_deg: float = 0.0,
    bank_deg: float = 0.0,
    course: float = 0.0,
    wind: tuple[float, float] = (0.0, 0.0),
) -> Trim | None:
    """JSBSim's trim at ``eas`` (m/s, equivalent) and ``altitude_msl`` (m): full trim on a
    flight-path angle ``gamma_deg``, or a level turn at ``bank_deg``; None when it finds none
    (beyond the airframe: the throttle or the elevator at its stop, or the wing stalled).

    The project's own airframes are symmetric (the aerosonde: thrust on the centre line, no
    propeller torque applied, as Beard & McLain's k_T_P = 0): they are trimmed longitudinally,
    and a level turn as the level trim at the same lift coefficient, at ``eas``
    sqrt(cos(bank)) (lift n W at ``eas`` with n = 1/cos(bank)); the turn's extra drag is not
    checked there. JSBSim's turn trim fails on the aerosonde at every bank tried (2 to 60 deg,
    cause not found), which this sidesteps."""
    if is_shipped(fdm.get_model_name()):
        if bank_deg:
            eas *= math.sqrt(max(math.cos(math.radians(bank_deg)), 0.0))
            bank_deg = 0.0
        mode = _LONGITUDINAL
    else:
        mode = _TURN if bank_deg else _FULL
    fdm["atmosphere/wind-east-fps"] = wind[0] / FT
    fdm["atmosphere/wind-north-fps"] = wind[1] / FT
    fdm["ic/h-sl-ft"] = altitude_msl / FT
    fdm["ic/vt-fps"] = eas * atmosphere.eas2tas(altitude_msl) / FT
    fdm["ic/gamma-deg"] = gamma_deg
    fdm["ic/phi-deg"] = bank_deg
    fdm["ic/psi-true-deg"] = _psi_deg(course)
    fdm["ic/lat-geod-deg"] = 0.0
    fdm["ic/long-gc-deg"] = 0.0
    with _quiet():
        fdm.run_ic()
        fdm["propulsion/set-running"] = -1
        try:
            fdm.do_trim(mode)
        except Exception:  # jsbsim.TrimFailureError; its base class differs between versions
            return None
    thr = float(fdm["fcs/throttle-cmd-norm"])
    if not 0.0 <= thr <= 1.0:
        return None
    return Trim(thr, float(fdm["attitude/theta-rad"]), float(fdm["fcs/pitch-trim-cmd-norm"]))
