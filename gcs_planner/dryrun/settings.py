"""The scenario's ``[dry_run]`` table: the dry run's seldom-changed settings kept with the
scenario they are for, under the names of their flags (``--min-probability``:
``min_probability``). A flag given on the command line wins over the table.

::

    [dry_run]
    runs = 200              # --runs
    seed = 7                # --seed
    min_probability = 0.95  # --min-probability
    loss = 0.05             # --loss: the radio link's message loss, both ways
    timeout = 1.5           # --timeout: the ground station's wait per message, seconds
    acceptance_radius = 1   # --acceptance-radius, whole metres
    time_scale = 20         # --time-scale (--policy)

Every key and value is checked as its flag's is; a bad one is an InputError naming the file,
the line where found, the key (``dry_run.runs``) and what was expected.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from gcs_planner.errors import InputError
from gcs_planner.scenario.toml_reader import key_line, load_toml

TABLE = "dry_run"


@dataclass(frozen=True)
class KeyRange:
    """What a key takes: a whole number or any finite number, at least ``low`` and below
    ``high`` (up to it with ``high_closed``; no bound when None)."""

    whole: bool
    low: float
    high: float | None = None
    high_closed: bool = False

    def refusal(self, value: object) -> str | None:
        """Why ``value`` is not one of this key's (None when it is)."""
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if self.whole:
            number = number and isinstance(value, int)
        in_range = number and math.isfinite(value) and value >= self.low  # type: ignore[arg-type]
        if in_range and self.high is not None:
            in_range = value <= self.high if self.high_closed else value < self.high  # type: ignore[operator]
        if in_range:
            return None
        return f"must be {self.wanted} (got {value!r})"

    @property
    def wanted(self) -> str:
        kind = "a whole number" if self.whole else "a number"
        if self.high is None:
            return f"{kind} >= {self.low:g}"
        end = "]" if self.high_closed else ")"
        return f"{kind} in [{self.low:g}, {self.high:g}{end}"


# Each key, as its flag checks it (cli/dry_run.py, cli/dry_run_policy.py, cli/common.py).
KEYS: dict[str, KeyRange] = {
    "runs": KeyRange(whole=True, low=0),
    "seed": KeyRange(whole=True, low=0),
    "min_probability": KeyRange(whole=False, low=0.0, high=1.0, high_closed=True),
    "loss": KeyRange(whole=False, low=0.0, high=1.0),
    "timeout": KeyRange(whole=False, low=1e-3),
    "acceptance_radius": KeyRange(whole=True, low=1, high=256),
    "time_scale": KeyRange(whole=False, low=0.01, high=10_000.0),
}


def read_dry_run_table(scenario: str | Path | None) -> dict[str, int | float]:
    """The checked ``[dry_run]`` table of the scenario file ``scenario``: {} when it is not a
    TOML file or has no such table. InputError naming the file and the key otherwise."""
    if scenario is None or Path(scenario).suffix.lower() != ".toml":
        return {}
    path = Path(scenario)
    file = str(path)
    doc, text = load_toml(path)
    if TABLE not in doc:
        return {}
    table = doc[TABLE]
    if not isinstance(table, dict):
        line = key_line(text, "", TABLE)
        raise InputError("must be a table", file=file, row=line, field=TABLE)
    unknown = [key for key in table if key not in KEYS]
    if unknown:
        raise InputError(
            f"unknown key(s) {', '.join(repr(f'{TABLE}.{k}') for k in unknown)} "
            f"(allowed: {', '.join(KEYS)})",
            file=file,
            row=key_line(text, TABLE, unknown[0]),
            field=f"{TABLE}.{unknown[0]}",
        )
    for key, value in table.items():
        why = KEYS[key].refusal(value)
        if why is not None:
            line = key_line(text, TABLE, key)
            raise InputError(why, file=file, row=line, field=f"{TABLE}.{key}")
    return dict(table)
