"""Cells: one scenario with one set of values, planned (and replayed) as one task.

A cell is small plain data — a file name or a generator's seed, and a few numbers — so that the
scheduler ships descriptions, not arrays: each worker loads or generates its scenario itself.
Its ``key`` is a digest of everything that decides its result, which is how ``--resume`` knows a
cell it has already finished, whatever order the cells are listed in.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

from gcs_planner.core.budget import DEFAULT_MAX_LABELS, DEFAULT_TIME_LIMIT
from gcs_planner.sweep.spec import (
    ENVIRONMENT_KEYS,
    SEARCH_KEYS,
    FileSource,
    GeneratedSource,
    SweepSpec,
)

# Swept keys that are not the scenario's or the vehicle's: applied by the task, not the reader.
NOT_OVERRIDES = ("objectives", *SEARCH_KEYS, *ENVIRONMENT_KEYS)


@dataclass(frozen=True)
class Cell:
    index: int  # position in the spec's expansion (scenarios outer, value sets inner)
    source: FileSource | GeneratedSource
    values: tuple[tuple[str, object], ...]  # swept keys and their values, in the spec's order
    objectives: tuple[str, ...] | None = None  # None: as `gcs-planner plan` (see task)
    choice: str = "compromise"
    max_labels: int | None = DEFAULT_MAX_LABELS
    time_limit: float | None = DEFAULT_TIME_LIMIT
    dry_run_runs: int = 0
    dry_run_seed: int = 0

    @property
    def key(self) -> str:
        identity = {
            "source": self.source.describe(),
            "values": {k: list(v) if isinstance(v, tuple) else v for k, v in self.values},
            "objectives": list(self.objectives) if self.objectives else None,
            "choice": self.choice,
            "max_labels": self.max_labels,
            "time_limit": self.time_limit,
            "dry_run": [self.dry_run_runs, self.dry_run_seed],
        }
        text = json.dumps(identity, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    @property
    def overrides(self) -> dict[str, object]:
        """The values as scenario overrides (the scenario's and the vehicle's parameters)."""
        return {k: v for k, v in self.values if k not in NOT_OVERRIDES}

    @property
    def environment(self) -> dict[str, float]:
        """The swept environment values (metres per error unit, capture radius)."""
        return {k: float(v) for k, v in self.values if k in ENVIRONMENT_KEYS}  # type: ignore[arg-type]

    @property
    def planned_objectives(self) -> tuple[str, ...] | None:
        swept = dict(self.values).get("objectives")
        return swept if swept is not None else self.objectives  # type: ignore[return-value]


def expand(spec: SweepSpec) -> list[Cell]:
    """Every cell of ``spec``: each scenario with each value set (a swept search setting wins
    over [plan]'s)."""
    cells = []
    for source in spec.scenarios:
        for values in spec.value_sets:
            cells.append(
                Cell(
                    index=len(cells),
                    source=source,
                    values=tuple(values.items()),
                    objectives=spec.objectives,
                    choice=values.get("choice", spec.choice),
                    max_labels=values.get("max_labels", spec.max_labels),
                    time_limit=values.get("time_limit", spec.time_limit),
                    dry_run_runs=spec.dry_run_runs,
                    dry_run_seed=spec.dry_run_seed,
                )
            )
    return cells
