"""The sweep spec (a TOML file): which scenarios, which parameter values, which plan options and
whether each cell's chosen route is dry-run.

Everything is checked here, before a single task is submitted, so that a typo costs one line on
the terminal and not a thousand failed cells. Errors name the spec file, its line and the field
(``grid.delta``, ``scenarios[2].seeds``).

    name = "radius study"                     # optional

    [plan]                                    # optional: how every cell plans
    objectives = ["length", "corrections"]    # default: as `gcs-planner plan`
    choice = "compromise"
    time_limit = 60                           # seconds per cell (default 60)
    max_labels = 200000                       # labels per search (default: no limit)

    [[scenarios]]                             # a scenario file (.toml, .csv, .xlsx) ...
    file = "example/scenario.toml"            # relative to the spec

    [[scenarios]]                             # ... or the project's generator
    generate = "random"
    corrections = [60, 120]                   # correction points; a number or a list
    seeds = { first = 1, count = 20 }         # or a list of seeds
    box = [60000, 24000, 2000]                # optional, metres
    parameters = "dataset1"                   # base parameters: dataset1 or dataset2
    unreliable_fraction = [0.24, 0.33]        # optional; a number or a list

    [grid]                                    # every combination of these values
    turn_radius = [200, 250]
    delta = [0.001, 0.0011]

    [[cases]]                                 # and/or a list of value sets, crossed with [grid]
    leg_model = "cs3d"

    [dry_run]                                 # optional: replay each chosen route
    runs = 200
    seed = 0

    [cluster]                                 # optional: workers as batch jobs (dask-jobqueue)
    system = "slurm"                          # slurm, pbs or sge
    jobs = 4                                  # jobs submitted (default 1)
    cores = 8                                 # per job
    memory = "16GB"                           # per job
    walltime = "02:00:00"                     # optional, per job
    queue = "normal"                          # optional: partition (SLURM) or queue
    processes = 8                             # optional: worker processes per job (default:
                                              # cores, one thread each)
    account = "proj42"                        # optional (SLURM, PBS)
    host = "10.0.0.5"                         # optional: the address the jobs reach the
                                              # scheduler at (default: dask-jobqueue's choice)
    log_directory = "logs"                    # optional: the jobs' output, relative to the spec
    job_directives = ["--exclusive"]          # optional: more lines for the job script's header
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from gcs_planner.aircraft.profile import LEG_MODELS, MAX_BANK_DEG
from gcs_planner.core.budget import DEFAULT_MAX_LABELS, DEFAULT_TIME_LIMIT
from gcs_planner.core.choose import CHOICES
from gcs_planner.core.planner import OBJECTIVES
from gcs_planner.errors import InputError
from gcs_planner.scenario.generate import DATASET1, DATASET2
from gcs_planner.scenario.model import Parameters
from gcs_planner.scenario.readers import PARAMETER_KEYS
from gcs_planner.scenario.toml_reader import load_toml

if sys.version_info >= (3, 11):
    pass
else:  # pragma: no cover - exercised only on Python 3.10
    pass

TOP_KEYS = ("name", "plan", "scenarios", "grid", "cases", "dry_run", "cluster")
PLAN_KEYS = ("objectives", "choice", "max_labels", "time_limit")
FILE_KEYS = ("file",)
GENERATOR_KEYS = (
    "generate",
    "corrections",
    "seeds",
    "box",
    "parameters",
    "unreliable_fraction",
)
DRY_RUN_KEYS = ("runs", "seed")
CLUSTER_KEYS = (
    "system",
    "jobs",
    "cores",
    "memory",
    "walltime",
    "queue",
    "processes",
    "account",
    "host",
    "log_directory",
    "job_directives",
)
# The batch systems dask-jobqueue starts workers on that the sweep offers.
BATCH_SYSTEMS = ("slurm", "pbs", "sge")
# What a cell may vary: every scenario and vehicle parameter, the leg model, the environment
# the planner reads (metres per error unit, the landmarks' capture radius), the objectives and
# the search's settings.
VEHICLE_KEYS = ("cruise_airspeed", "max_bank_angle", "leg_model")
ENVIRONMENT_KEYS = ("error_unit", "capture_radius")
SEARCH_KEYS = ("choice", "max_labels", "time_limit")
SWEEP_KEYS = (*PARAMETER_KEYS, *VEHICLE_KEYS, *ENVIRONMENT_KEYS, "objectives", *SEARCH_KEYS)
GENERATORS = ("random",)
BASE_PARAMETERS: dict[str, Parameters] = {"dataset1": DATASET1, "dataset2": DATASET2}
SCENARIO_SUFFIXES = (".toml", ".csv", ".xlsx")
# The contest's 100 km box (generate.random_scenario's default).
DEFAULT_BOX = (100_000.0, 100_000.0, 10_000.0)


@dataclass(frozen=True)
class FileSource:
    """A scenario file, read by the worker that plans it."""

    path: str  # absolute, so a worker started elsewhere reads the same file

    def describe(self) -> dict:
        return {"file": self.path}


@dataclass(frozen=True)
class GeneratedSource:
    """A scenario the worker generates itself from a seed (generate.random_scenario)."""

    corrections: int
    seed: int
    box: tuple[float, float, float]
    parameters: str
    unreliable_fraction: float

    def describe(self) -> dict:
        return {
            "generate": "random",
            "corrections": self.corrections,
            "seed": self.seed,
            "box": list(self.box),
            "parameters": self.parameters,
            "unreliable_fraction": self.unreliable_fraction,
        }


ScenarioSource = FileSource | GeneratedSource


@dataclass(frozen=True)
class ClusterSpec:
    """The spec's [cluster]: worker jobs on a batch system, started through dask-jobqueue."""

    system: str  # slurm, pbs or sge
    jobs: int
    cores: int  # per job
    memory: str  # per job, as the batch system takes it ("16GB")
    processes: int  # worker processes per job
    walltime: str | None = None
    queue: str | None = None
    account: str | None = None
    host: str | None = None
    log_directory: str | None = None
    job_directives: tuple[str, ...] = ()


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep spec: the cells are scenarios × value sets (see :mod:`.cells`)."""

    path: str
    name: str
    scenarios: tuple[ScenarioSource, ...]
    # Each a mapping of SWEEP_KEYS to one value; the cells take every one of them per scenario.
    value_sets: tuple[dict, ...]
    # The keys that vary from one value set to another, in the spec's order (the summary's axes).
    swept: tuple[str, ...]
    objectives: tuple[str, ...] | None = None
    choice: str = "compromise"
    max_labels: int | None = DEFAULT_MAX_LABELS
    time_limit: float | None = DEFAULT_TIME_LIMIT
    dry_run_runs: int = 0
    dry_run_seed: int = 0
    cluster: ClusterSpec | None = None


class _Where:
    """Finds the line of a key in the spec's text (tomllib gives none), best effort."""

    def __init__(self, file: str, text: str) -> None:
        self.file = file
        self.lines = text.splitlines()

    def line(self, table: str, key: str | None = None, index: int | None = None) -> int | None:
        """Line of ``key`` in ``[table]`` (the ``index``-th ``[[table]]``); of the header when
        ``key`` is None; of a top-level key when ``table`` is ""."""
        current, seen, header_line = "", -1, None
        key_re = None
        if key:
            key_re = re.compile(rf"""^\s*(?:{re.escape(key)}|"{re.escape(key)}")\s*=""")
        for number, text in enumerate(self.lines, start=1):
            header = re.match(r"^\s*\[\[?\s*([^\[\]]+?)\s*\]\]?", text)
            if header:
                current = header.group(1)
                if current == table:
                    seen += 1
                    if index is None or seen == index:
                        header_line = number
                        if key is None:
                            return number
                continue
            in_table = current == table and (index is None or seen == index)
            if key_re and in_table and key_re.match(text):
                return number
        return header_line

    def error(
        self, message: str, table: str, key: str | None = None, index: int | None = None
    ) -> InputError:
        name = table if index is None else f"{table}[{index + 1}]"
        name = f"{name}.{key}" if key and name else (key or name)
        return InputError(message, file=self.file, row=self.line(table, key, index), field=name)


def read_spec(path: str | Path) -> SweepSpec:
    """Read and check a sweep spec; raises InputError naming the file, line and field."""
    path = Path(path)
    file = str(path)
    if path.is_dir():
        raise InputError("is a directory, not a sweep spec", file=file)
    if path.suffix.lower() != ".toml":
        raise InputError(f"a sweep spec is a .toml file (got {path.suffix!r})", file=file)
    doc, text = load_toml(path)
    where = _Where(file, text)
    _unknown(doc, TOP_KEYS, where, "")

    name = doc.get("name", path.stem)
    if not isinstance(name, str):
        raise where.error("must be a string", "", "name")

    objectives, choice, max_labels, time_limit = _plan(doc, where)
    scenarios = _scenarios(doc, where, path.parent)
    value_sets, swept = _value_sets(doc, where)
    runs, seed = _dry_run(doc, where)
    cluster = _cluster(doc, where, path.parent)
    return SweepSpec(
        path=str(path.resolve()),
        name=name,
        scenarios=scenarios,
        value_sets=value_sets,
        swept=swept,
        objectives=objectives,
        choice=choice,
        max_labels=max_labels,
        time_limit=time_limit,
        dry_run_runs=runs,
        dry_run_seed=seed,
        cluster=cluster,
    )


# --- sections -------------------------------------------------------------------------------


def _unknown(table: dict, allowed: tuple[str, ...], where: _Where, name: str, index=None) -> None:
    unknown = [k for k in table if k not in allowed]
    if unknown:
        raise where.error(
            f"unknown key {unknown[0]!r} (allowed: {', '.join(allowed)})", name, unknown[0], index
        )


def _table(doc: dict, key: str, where: _Where) -> dict:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise where.error("must be a table", "", key)
    return value


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _plan(doc: dict, where: _Where) -> tuple[tuple[str, ...] | None, str, int | None, float | None]:
    table = _table(doc, "plan", where)
    _unknown(table, PLAN_KEYS, where, "plan")
    objectives = None
    if "objectives" in table:
        objectives = _objectives(table["objectives"], where, "plan", "objectives")
    choice = table.get("choice", "compromise")
    if choice not in CHOICES:
        raise where.error(
            f"unknown choice {choice!r}: one of {', '.join(CHOICES)}", "plan", "choice"
        )
    max_labels = table.get("max_labels", DEFAULT_MAX_LABELS)
    if max_labels is not None and (not _is_int(max_labels) or max_labels < 1):
        raise where.error(f"must be a whole number >= 1 (got {max_labels!r})", "plan", "max_labels")
    time_limit = table.get("time_limit", DEFAULT_TIME_LIMIT)
    if time_limit is not None and (not _is_number(time_limit) or time_limit <= 0):
        raise where.error(f"must be seconds > 0 (got {time_limit!r})", "plan", "time_limit")
    return objectives, choice, max_labels, time_limit


def _objectives(value: object, where: _Where, table: str, key: str, index=None) -> tuple[str, ...]:
    if isinstance(value, str):
        value = [o.strip() for o in value.split(",") if o.strip()]
    if not isinstance(value, list) or not value or not all(isinstance(o, str) for o in value):
        raise where.error(
            f'must be a list of objectives such as ["length", "corrections"] (got {value!r})',
            table,
            key,
            index,
        )
    unknown = [o for o in value if o not in OBJECTIVES]
    if unknown:
        raise where.error(
            f"unknown objective {unknown[0]!r}: choose from {', '.join(OBJECTIVES)}",
            table,
            key,
            index,
        )
    twice = [o for o in OBJECTIVES if value.count(o) > 1]
    if twice:
        raise where.error(f"objective {twice[0]!r} given more than once", table, key, index)
    return tuple(value)


def _scenarios(doc: dict, where: _Where, base: Path) -> tuple[ScenarioSource, ...]:
    entries = doc.get("scenarios")
    if entries is None:
        raise InputError(
            "no [[scenarios]]: give at least one scenario file or generator",
            file=where.file,
            field="scenarios",
        )
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise where.error("must be an array of tables ([[scenarios]])", "", "scenarios")
    if not entries:
        raise where.error("is empty: give at least one scenario", "", "scenarios")
    out: list[ScenarioSource] = []
    for i, entry in enumerate(entries):
        if "file" in entry:
            _unknown(entry, FILE_KEYS, where, "scenarios", i)
            out.append(_file_source(entry["file"], where, base, i))
        elif "generate" in entry:
            _unknown(entry, GENERATOR_KEYS, where, "scenarios", i)
            out.extend(_generated(entry, where, i))
        else:
            raise where.error(
                'needs either file = "..." or generate = "random"', "scenarios", None, i
            )
    return tuple(out)


def _file_source(value: object, where: _Where, base: Path, i: int) -> FileSource:
    if not isinstance(value, str) or not value.strip():
        raise where.error("must be a file name (string)", "scenarios", "file", i)
    path = (base / value).resolve()
    if path.suffix.lower() not in SCENARIO_SUFFIXES:
        raise where.error(
            f"scenario file must be .toml, .csv or .xlsx (got {value!r})", "scenarios", "file", i
        )
    if not path.is_file():
        what = "is a directory" if path.is_dir() else "does not exist"
        raise where.error(f"scenario file {str(path)!r} {what}", "scenarios", "file", i)
    return FileSource(str(path))


def _as_list(value: object) -> list:
    return value if isinstance(value, list) else [value]


def _generated(entry: dict, where: _Where, i: int) -> list[GeneratedSource]:
    def fail(message: str, key: str) -> InputError:
        return where.error(message, "scenarios", key, i)

    if entry["generate"] not in GENERATORS:
        raise fail(f"unknown generator {entry['generate']!r}: one of {GENERATORS}", "generate")
    for required in ("corrections", "seeds"):
        if required not in entry:
            raise fail("missing key (the generator needs corrections and seeds)", required)
    sizes = _as_list(entry["corrections"])
    if not sizes or not all(_is_int(n) and n >= 1 for n in sizes):
        raise fail(f"must be a whole number >= 1 or a list of them (got {sizes!r})", "corrections")
    seeds = entry["seeds"]
    if isinstance(seeds, dict):
        if set(seeds) != {"first", "count"}:
            raise fail("a seed range is { first = N, count = M }", "seeds")
        first, count = seeds["first"], seeds["count"]
        if not (_is_int(first) and first >= 0 and _is_int(count) and count >= 1):
            raise fail("first must be a whole number >= 0 and count >= 1", "seeds")
        seeds = list(range(first, first + count))
    seeds = _as_list(seeds)
    if not seeds or not all(_is_int(s) and s >= 0 for s in seeds):
        raise fail(f"must be whole numbers >= 0 (got {seeds!r})", "seeds")
    box = entry.get("box", list(DEFAULT_BOX))
    if not (isinstance(box, list) and len(box) == 3 and all(_is_number(b) and b > 0 for b in box)):
        raise fail(f"must be three lengths > 0 in metres [x, y, z] (got {box!r})", "box")
    base = entry.get("parameters", "dataset1")
    if base not in BASE_PARAMETERS:
        known = ", ".join(BASE_PARAMETERS)
        raise fail(f"unknown parameters {base!r}: one of {known}", "parameters")
    fractions = _as_list(entry.get("unreliable_fraction", 0.24))
    if not fractions or not all(_is_number(f) and 0 <= f <= 1 for f in fractions):
        raise fail(f"must lie in [0, 1] (got {fractions!r})", "unreliable_fraction")
    return [
        GeneratedSource(n, s, tuple(float(b) for b in box), base, float(f))  # type: ignore[arg-type]
        for n in sizes
        for f in fractions
        for s in seeds
    ]


def _value_sets(doc: dict, where: _Where) -> tuple[tuple[dict, ...], tuple[str, ...]]:
    grid = _table(doc, "grid", where)
    _unknown(grid, SWEEP_KEYS, where, "grid")
    axes: list[tuple[str, list]] = []
    for key, values in grid.items():
        values = _as_list(values) if key != "objectives" else _objective_values(values)
        if not values:
            raise where.error("is empty: give at least one value", "grid", key)
        axes.append((key, [_value(key, v, where, "grid") for v in values]))

    cases = doc.get("cases", [{}])
    if not isinstance(cases, list) or not all(isinstance(c, dict) for c in cases):
        raise where.error("must be an array of tables ([[cases]])", "", "cases")
    checked_cases = []
    for i, case in enumerate(cases or [{}]):
        _unknown(case, SWEEP_KEYS, where, "cases", i)
        checked = {k: _value(k, v, where, "cases", i) for k, v in case.items()}
        overlap = [k for k in checked if k in grid]
        if overlap:
            raise where.error("given in both [grid] and [[cases]]", "cases", overlap[0], i)
        checked_cases.append(checked)

    value_sets: list[dict] = []
    for case in checked_cases:
        combos: list[dict] = [dict(case)]
        for key, values in axes:
            combos = [{**c, key: v} for c in combos for v in values]
        value_sets.extend(combos)
    for i, values in enumerate(value_sets):
        if "turn_radius" in values and "max_bank_angle" in values:
            table, index = ("grid", None) if "max_bank_angle" in grid else ("cases", i)
            raise where.error(
                "give either turn_radius or max_bank_angle (with cruise_airspeed), not both",
                table,
                "max_bank_angle",
                index if table == "cases" and index < len(checked_cases) else None,
            )
    keys: list[str] = []
    for values in value_sets:
        keys.extend(k for k in values if k not in keys)
    swept = tuple(k for k in keys if len({_hashable(v.get(k)) for v in value_sets}) > 1)
    return tuple(value_sets), swept


def _objective_values(values: object) -> list:
    """[grid] objectives: a list of objective lists (or of comma strings), or one such list."""
    if isinstance(values, list) and values and all(isinstance(v, str) for v in values):
        if all("," not in v for v in values):
            return [values]  # one set, written flat
    return _as_list(values)


def _hashable(value: object) -> object:
    return tuple(value) if isinstance(value, (list, tuple)) else value


def _value(key: str, value: object, where: _Where, table: str, index=None) -> object:
    """One value of a swept key, checked as the scenario readers would check it."""
    if key == "objectives":
        return _objectives(value, where, table, key, index)
    if key == "choice":
        if value not in CHOICES:
            raise where.error(
                f"unknown choice {value!r}: one of {', '.join(CHOICES)}", table, key, index
            )
        return value
    if key == "max_labels":
        if not _is_int(value) or value < 1:  # type: ignore[operator]
            raise where.error(f"must be a whole number >= 1 (got {value!r})", table, key, index)
        return value
    if key == "leg_model":
        if value not in LEG_MODELS:
            raise where.error(
                f"unknown leg model {value!r}: one of {', '.join(LEG_MODELS)}", table, key, index
            )
        return value
    if not _is_number(value):
        raise where.error(f"must be a finite number (got {value!r})", table, key, index)
    number = float(value)  # type: ignore[arg-type]
    if key in PARAMETER_KEYS:
        problems = Parameters(**{**DATASET1.to_dict(), key: number}).validate()
        if problems:
            raise where.error(problems[0], table, key, index)
    elif key in (*ENVIRONMENT_KEYS, "time_limit") and not number > 0:
        raise where.error(f"must be > 0 (got {value!r})", table, key, index)
    elif key == "cruise_airspeed" and not 0 < number <= 300:
        raise where.error(f"must lie in (0, 300] m/s (got {value!r})", table, key, index)
    elif key == "max_bank_angle" and not 0 < number <= MAX_BANK_DEG:
        raise where.error(
            f"must lie in (0, {MAX_BANK_DEG:g}] degrees (got {value!r})", table, key, index
        )
    return number


def _dry_run(doc: dict, where: _Where) -> tuple[int, int]:
    if "dry_run" not in doc:
        return 0, 0
    table = _table(doc, "dry_run", where)
    _unknown(table, DRY_RUN_KEYS, where, "dry_run")
    runs = table.get("runs", 100)
    if not _is_int(runs) or runs < 1:
        raise where.error(f"must be a whole number >= 1 (got {runs!r})", "dry_run", "runs")
    seed = table.get("seed", 0)
    if not _is_int(seed) or seed < 0:
        raise where.error(f"must be a whole number >= 0 (got {seed!r})", "dry_run", "seed")
    return runs, seed


_MEMORY = re.compile(r"^\s*\d+(\.\d+)?\s*([kKMGTP]i?)?B\s*$")
_WALLTIME = re.compile(r"^\d+(:[0-5]\d){0,2}$|^\d+-\d+(:[0-5]\d){0,2}$")


def _cluster(doc: dict, where: _Where, base: Path) -> ClusterSpec | None:
    if "cluster" not in doc:
        return None
    table = _table(doc, "cluster", where)
    _unknown(table, CLUSTER_KEYS, where, "cluster")

    def fail(message: str, key: str | None) -> InputError:
        return where.error(message, "cluster", key)

    for required in ("system", "cores", "memory"):
        if required not in table:
            raise fail("missing key (a [cluster] needs system, cores and memory)", required)
    system = table["system"]
    if system not in BATCH_SYSTEMS:
        raise fail(f"unknown batch system {system!r}: one of {', '.join(BATCH_SYSTEMS)}", "system")
    counts = {}
    for key, default in (("jobs", 1), ("cores", None), ("processes", table.get("cores"))):
        value = table.get(key, default)
        if not _is_int(value) or value < 1:
            raise fail(f"must be a whole number >= 1 (got {value!r})", key)
        counts[key] = value
    if counts["cores"] % counts["processes"]:
        raise fail(
            f"must divide cores ({counts['cores']}): each worker process gets the same threads",
            "processes",
        )
    memory = table["memory"]
    if not isinstance(memory, str) or not _MEMORY.match(memory):
        raise fail(f'must be an amount such as "16GB" (got {memory!r})', "memory")
    walltime = table.get("walltime")
    if walltime is not None and (not isinstance(walltime, str) or not _WALLTIME.match(walltime)):
        raise fail(f'must be a time such as "02:00:00" (got {walltime!r})', "walltime")
    texts = {}
    for key in ("queue", "account", "host", "log_directory"):
        value = table.get(key)
        if value is not None and (not isinstance(value, str) or not value.strip()):
            raise fail(f"must be a non-empty string (got {value!r})", key)
        texts[key] = value
    if texts["account"] is not None and system == "sge":
        raise fail("SGE jobs take no account (give the queue, or a job directive)", "account")
    if texts["log_directory"] is not None:
        texts["log_directory"] = str((base / texts["log_directory"]).resolve())
    directives = table.get("job_directives", [])
    if not isinstance(directives, list) or not all(isinstance(d, str) for d in directives):
        raise fail(f"must be a list of strings (got {directives!r})", "job_directives")
    return ClusterSpec(
        system=system,
        jobs=counts["jobs"],
        cores=counts["cores"],
        memory=memory.strip(),
        processes=counts["processes"],
        walltime=walltime,
        queue=texts["queue"],
        account=texts["account"],
        host=texts["host"],
        log_directory=texts["log_directory"],
        job_directives=tuple(directives),
    )
