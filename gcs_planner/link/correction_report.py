"""The correction report: one STATUSTEXT per correction the vehicle meets, as the mock vehicle
sends it and as a companion computer on a real aircraft can send it (docs/flying-policies.md).

    <KIND> fix <POINT> <OUTCOME>[ <detail>]

KIND is ``V`` or ``H``; POINT the landmark's id as the scenario names it (no spaces); OUTCOME
``made`` (the correction took), ``FAILED`` (an unreliable point's fix did not take: the error
is clipped to the residual), ``MISSED`` (the aircraft passed outside the capture radius: no
fix at all) or ``LOST`` (an error was over the point's limit on arrival). What follows is for
people (the errors on arrival, the miss distance) and is not read. A STATUSTEXT carries at most
50 characters: the ids of a contest workbook (up to 3 digits) leave room for the detail.

The ground station acts on FAILED and MISSED alike (no correction took at that point) and reads
every other text as none of its business: an unknown or garbled text is never a report.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

OUTCOMES = ("made", "FAILED", "MISSED", "LOST")
_REPORT = re.compile(r"^(V|H) fix (\S{1,32}) (made|FAILED|MISSED|LOST)(?: .*)?$")
STATUSTEXT_CHARS = 50


@dataclass(frozen=True)
class CorrectionReport:
    """What the vehicle said of the correction at ``point``."""

    kind: str  # "V" or "H"
    point: str
    outcome: str  # one of OUTCOMES

    @property
    def took(self) -> bool:
        return self.outcome == "made"

    @property
    def no_fix(self) -> bool:
        """The fix did not take (failed or missed): a policy's switch may be due."""
        return self.outcome in ("FAILED", "MISSED")


def format_report(kind: str, point: str, outcome: str, detail: str = "") -> str:
    """The STATUSTEXT of one correction (cut to the 50 characters a STATUSTEXT carries; the
    detail goes first)."""
    if kind not in ("V", "H") or outcome not in OUTCOMES or not point or " " in point:
        raise ValueError(f"not a correction report: {kind!r} {point!r} {outcome!r}")
    text = f"{kind} fix {point} {outcome}"
    if detail and len(text) + 1 + len(detail) <= STATUSTEXT_CHARS:
        text += f" {detail}"
    return text


def parse_report(text: object) -> CorrectionReport | None:
    """The report a STATUSTEXT's text carries, or None for any other text (unknown, garbled,
    cut short, not text at all)."""
    if isinstance(text, bytes):
        try:
            text = text.decode("ascii")
        except UnicodeDecodeError:
            return None
    if not isinstance(text, str):
        return None
    m = _REPORT.match(text.rstrip("\x00").strip())
    if m is None:
        return None
    return CorrectionReport(m.group(1), m.group(2), m.group(3))
