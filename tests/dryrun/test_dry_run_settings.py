"""The scenario TOML's ``[dry_run]`` table (gcs_planner/dryrun/settings.py): the dry run's
seldom-changed flags kept with the scenario under their flags' names, a flag given on the
command line winning; a bad key or value is one line, exit 2, naming the file and the key."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from support.short_line import HEAD, POINTS, short_line

from gcs_planner.cli import build_parser, main
from gcs_planner.cli.dry_run import _fill_from_table
from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY
from gcs_planner.link.protocol import DEFAULT_TIMEOUT_S
from gcs_planner.scenario.readers import load_scenario


def scenario(tmp_path: Path, table: str) -> Path:
    return short_line(tmp_path, table)


def parsed(*argv: str):
    """The dry-run flags of ``argv`` with the [dry_run] table applied, as the command does."""
    argv = ("dry-run", *argv)
    args = build_parser(argv).parse_args(argv)
    _fill_from_table(args)
    return args


TABLE = """
[dry_run]
runs = 3
seed = 5
min_probability = 0.5
loss = 0.02
timeout = 2.5
acceptance_radius = 3
time_scale = 40
"""


def test_the_table_sets_the_flags_not_given(tmp_path):
    args = parsed(str(scenario(tmp_path, TABLE)))
    assert (args.runs, args.seed, args.loss, args.timeout) == ("3", "5", "0.02", "2.5")
    assert args.acceptance_radius == "3" and args.time_scale == "40"
    assert args.min_probability == 0.5


def test_a_flag_given_wins_over_the_table(tmp_path):
    path = str(scenario(tmp_path, TABLE))
    args = parsed(path, "--runs", "0", "--seed", "0", "--min-probability", "0.99",
                  "--timeout", "1", "--acceptance-radius", "1", "--time-scale", "20")  # fmt: skip
    assert (args.runs, args.seed, args.timeout, args.acceptance_radius) == ("0", "0", "1", "1")
    assert args.min_probability == 0.99 and args.time_scale == "20"
    assert args.loss == "0.02"  # not given: the table's


def test_without_a_table_the_flags_keep_their_defaults(tmp_path):
    args = parsed(str(scenario(tmp_path, "")))
    assert (args.runs, args.seed, args.loss) == ("0", "0", "0")
    assert args.timeout == str(DEFAULT_TIMEOUT_S) and args.acceptance_radius == "1"
    assert args.min_probability == DEFAULT_MIN_PROBABILITY
    assert type(args.min_probability) is float


def test_the_table_is_flown_and_loses_to_a_flag(tmp_path, capsys):
    path = str(scenario(tmp_path, "\n[dry_run]\nruns = 2\nseed = 7\nmin_probability = 0.5\n"))
    rc = main(["dry-run", path, "--json", "--quiet"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0, d
    assert d["runs"] == 2 and d["seed"] == 7 and d["min_probability"] == 0.5
    rc = main(["dry-run", path, "--runs", "0", "--json", "--quiet"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["runs"] == 0 and d["seed"] == 7 and d["demonstration"]


def test_a_scenario_with_the_table_reads_as_without_it(tmp_path):
    with_table = load_scenario(scenario(tmp_path, TABLE))
    without = load_scenario(scenario(tmp_path, ""))
    assert with_table.ids == without.ids and with_table.params == without.params


def exit_2(capsys, path: Path) -> str:
    rc = main(["dry-run", str(path), "--quiet"])
    out, err = capsys.readouterr()
    assert rc == 2 and out == "", err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert str(path) in err
    return err


def test_an_unknown_key_is_exit_2_naming_the_file_and_the_key(tmp_path, capsys):
    err = exit_2(capsys, scenario(tmp_path, "\n[dry_run]\nrunz = 3\n"))
    assert "dry_run.runz" in err and "allowed: runs" in err


@pytest.mark.parametrize(
    "line, key, wanted",
    [
        ("runs = -1", "runs", "a whole number >= 0"),
        ("runs = 2.5", "runs", "a whole number >= 0"),
        ("runs = true", "runs", "a whole number >= 0"),
        ('seed = "x"', "seed", "a whole number >= 0"),
        ("loss = 1.0", "loss", "a number in [0, 1)"),
        ("min_probability = 1.5", "min_probability", "a number in [0, 1]"),
        ("timeout = 0", "timeout", "a number >= 0.001"),
        ("timeout = inf", "timeout", "a number >= 0.001"),
        ("acceptance_radius = 256", "acceptance_radius", "a whole number in [1, 256)"),
        ("time_scale = 0", "time_scale", "a number in [0.01, 10000)"),
    ],
)
def test_a_bad_value_is_exit_2_naming_the_file_the_key_and_what_was_expected(
    tmp_path, capsys, line, key, wanted
):
    err = exit_2(capsys, scenario(tmp_path, f"\n[dry_run]\n{line}\n"))
    assert f"dry_run.{key}" in err and f"must be {wanted}" in err
    assert f"row {len(HEAD.splitlines()) + 3}" in err  # the key's line in the file


def test_a_dry_run_that_is_no_table_is_exit_2(tmp_path, capsys):
    path = tmp_path / "line.toml"
    (tmp_path / "line.csv").write_text(POINTS, encoding="utf-8")
    path.write_text('dry_run = 3\npoints = "line.csv"\n', encoding="utf-8")
    err = exit_2(capsys, path)
    assert "'dry_run'" in err and "must be a table" in err


def test_firmware_is_still_taken_as_the_autopilot(tmp_path, capsys):
    args = parsed(str(scenario(tmp_path, "")), "--firmware", "px4")
    assert args.autopilot == "px4"
    assert "--firmware is deprecated, use --autopilot" in capsys.readouterr().err
