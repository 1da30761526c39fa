"""The vehicle setup as the parameter files ground stations load.

* ``.param``: Mission Planner's and MAVProxy's format, one ``NAME,VALUE`` a line; a line
  starting with ``#`` is a comment (pymavlink's ``MAVParmDict.load``, which MAVProxy's
  ``param load`` calls, drops everything after a ``#`` and splits on commas and blanks; Mission
  Planner's parameter list loads the same files). Each value is preceded by a comment line
  giving what the plan needs and why.
* ``.params``: QGroundControl's format (``ParameterManager``'s save and load): tab-separated
  ``vehicle-id component-id name value type`` with the MAV_PARAM_TYPE of the value; ``#`` lines
  are comments, so the same reasons stand there.

Both name the autopilot in a header comment (``# autopilot: ardupilot``). :func:`read` reads
either back (the suffix decides), as ``upload --params FILE`` does, with the file, row and field
of anything it cannot use.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from gcs_planner.aircraft.autopilot import PARAM_TYPE_REAL32, autopilot_for
from gcs_planner.errors import InputError
from gcs_planner.mission.vehicle_setup import ParameterNeed

# The file names ``plan --out`` and ``export`` write the setup under, beside the mission.
PARAM_FILE = "vehicle.param"
QGC_PARAMS_FILE = "vehicle.params"
SETUP_FILES = (PARAM_FILE, QGC_PARAMS_FILE)
_MAX_NAME = 16  # MAVLink's param_id


@dataclass(frozen=True)
class SetupFile:
    """A setup read from a file: the autopilot its header names ("" when none), and the
    parameters in file order."""

    autopilot: str
    values: dict[str, float]


def _header(firmware: str, source: str) -> list[str]:
    ap = autopilot_for(firmware)
    return [
        f"# Vehicle setup for {ap.title}: the parameters the mission relies on (gcs-planner).",
        f"# autopilot: {ap.firmware}",
        f"# plan: {source}" if source else "# plan: (unnamed)",
        "# Load it with the mission: gcs-planner upload --params FILE MISSION, or your ground",
        "# station's parameter list. Each value follows a line that says what the plan needs.",
    ]


def _why(need: ParameterNeed) -> str:
    text = f"# {need.name}: {need.wanted()}: {need.why}"
    if need.impossible:
        text += f" -- CANNOT BE MET: {need.impossible}"
    return text


def _value(x: float) -> str:
    return f"{x:.6g}"


def render_param(needs: Sequence[ParameterNeed], firmware: str, source: str = "") -> str:
    """The setup as a Mission Planner / MAVProxy ``.param`` file."""
    lines = _header(firmware, source)
    for need in needs:
        lines += [_why(need), f"{need.name},{_value(need.set_to)}"]
    return "\n".join(lines) + "\n"


def render_qgc_params(needs: Sequence[ParameterNeed], firmware: str, source: str = "") -> str:
    """The setup as a QGroundControl ``.params`` file (vehicle 1, component 1)."""
    ap = autopilot_for(firmware)
    lines = _header(firmware, source) + ["#", "# Vehicle-Id\tComponent-Id\tName\tValue\tType"]
    for need in needs:
        spec = ap.spec(need.name)
        ptype = spec.ptype if spec is not None else PARAM_TYPE_REAL32
        value = spec.stored(need.set_to) if spec is not None else need.set_to
        text = str(int(value)) if ptype != PARAM_TYPE_REAL32 else _value(value)
        lines += [_why(need), f"1\t1\t{need.name}\t{text}\t{ptype}"]
    return "\n".join(lines) + "\n"


def render_setup(
    needs: Sequence[ParameterNeed], firmware: str, source: str = ""
) -> list[tuple[str, str]]:
    """(file name, content) of both setup files."""
    return [
        (PARAM_FILE, render_param(needs, firmware, source)),
        (QGC_PARAMS_FILE, render_qgc_params(needs, firmware, source)),
    ]


def read(path: str | Path) -> SetupFile:
    """A ``.param`` or ``.params`` file's parameters; InputError naming the file, row and field
    of what cannot be read."""
    path = Path(path)
    name = str(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError("no such file", file=name) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", file=name) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError("not a text file (UTF-8)", file=name) from None
    qgc = path.suffix.lower() == ".params"
    if path.suffix.lower() not in (".param", ".params"):
        raise InputError(
            "a vehicle setup is a .param (Mission Planner, MAVProxy) or .params "
            "(QGroundControl) file",
            file=name,
        )
    autopilot = ""
    values: dict[str, float] = {}
    for row, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("#"):
            key, _, rest = stripped[1:].strip().partition(":")
            if key.strip() == "autopilot" and not autopilot:
                autopilot = rest.strip()
            continue
        if not stripped:
            continue
        if qgc:
            fields = [f.strip() for f in line.split("\t")]
            if len(fields) != 5:
                raise InputError(
                    f"expected 5 tab-separated fields (vehicle, component, name, value, type), "
                    f"got {len(fields)}",
                    file=name,
                    row=row,
                )
            pname, ptext = fields[2], fields[3]
        else:
            fields = stripped.split("#", 1)[0].replace(",", " ").split()
            if len(fields) != 2:
                raise InputError("expected NAME,VALUE", file=name, row=row)
            pname, ptext = fields
        if not pname or len(pname) > _MAX_NAME or not pname.isascii():
            raise InputError(
                f"a parameter name is 1-{_MAX_NAME} ASCII characters, got {pname!r}",
                file=name,
                row=row,
                field="name",
            )
        try:
            value = float(ptext)
        except ValueError:
            raise InputError(f"not a number: {ptext!r}", file=name, row=row, field=pname) from None
        if not math.isfinite(value):
            raise InputError(f"not a finite number: {ptext!r}", file=name, row=row, field=pname)
        if pname in values:
            raise InputError("given twice", file=name, row=row, field=pname)
        values[pname] = value
    if not values:
        raise InputError("names no parameter", file=name)
    return SetupFile(autopilot, values)


def find_beside(mission: str | Path) -> Path | None:
    """The setup ``plan --out`` or ``export`` wrote beside ``mission`` (its .param), if any."""
    folder = Path(mission).parent
    for file in SETUP_FILES:
        if (folder / file).is_file():
            return folder / file
    return None
