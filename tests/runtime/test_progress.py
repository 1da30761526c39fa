"""The one progress display (gcs_planner.runtime.progress): silent off a terminal and with --quiet,
and
on a terminal every redraw leaves exactly the last line on screen (no tail of a longer line
before it: the old sweep printer showed "ETA 21ss")."""

from __future__ import annotations

import io
import math
import re

import pytest
from support.terminal import FakeTerminal, screen

from gcs_planner.cli import main
from gcs_planner.core.budget import Progress as Report
from gcs_planner.link.progress import Progress as TransferProgress
from gcs_planner.runtime.progress import Counter, SearchProgress, StatusLine


def report(labels: int, seconds: float, bound: float = 1234.0) -> Report:
    return Report(labels, 10 * labels, 3, bound, seconds, "search")


def test_nothing_is_written_when_the_stream_is_not_a_terminal() -> None:
    out = io.StringIO()
    show = SearchProgress(out)
    assert not show.enabled
    show(report(1, 0.1))
    show.finish()
    bar = Counter("cells", 100, stream=out)
    bar.update(50, failed=1)
    bar.close()
    transfer = TransferProgress("upload", 100, stream=out)
    transfer.update(100)
    transfer.close()
    assert out.getvalue() == ""


def test_quiet_silences_even_a_terminal() -> None:
    out = FakeTerminal()
    show = SearchProgress(out, quiet=True)
    show(report(1, 0.1))
    show.finish()
    Counter("cells", 100, stream=out, quiet=True).update(5)
    t = TransferProgress("download", 100, stream=out, enabled=False)
    t.update(100)
    t.close()
    assert out.getvalue() == ""


def test_a_shorter_status_line_leaves_no_stray_characters() -> None:
    out = FakeTerminal()
    line = StatusLine(out)
    line.show("cells 9/10 done, ETA 1m21s")
    line.show("cells 10/10 done, ETA 21s")
    line.close()
    assert screen(out.getvalue()) == ["cells 10/10 done, ETA 21s"]


def test_the_search_line_keeps_labels_open_routes_and_the_bound() -> None:
    out = FakeTerminal()
    show = SearchProgress(out)
    show(report(123_456, 12.3, bound=98_765.0))
    show(report(7, 1.0, bound=math.inf))  # shorter: its tail must be gone
    show.finish()
    assert screen(out.getvalue()) == [
        "search: 1.0 s, 7 labels, 70 partial routes open, 3 routes found, front complete "
        "below none open"
    ]


def test_a_counter_shows_the_count_and_the_time_left_and_ends_its_line() -> None:
    out = FakeTerminal()
    bar = Counter("cells", 40, unit="cell", stream=out)
    for done in range(41):
        bar.update(done, failed=done // 10)
    bar.close()
    rows = screen(out.getvalue())
    assert len(rows) == 1 and out.getvalue().endswith("\n")
    assert "40/40" in rows[0] and "failed=4" in rows[0] and "cell/s" in rows[0]
    # tqdm's [elapsed<remaining] is the transfer's ETA.
    assert re.search(r"\[\d\d:\d\d<\d\d:\d\d", rows[0])


def test_transfers_under_the_minimum_draw_nothing() -> None:
    out = FakeTerminal()
    t = TransferProgress("upload", 5, stream=out)
    t.update(5)
    t.close()
    assert out.getvalue() == ""


def test_forced_progress_off_a_terminal_is_plain_lines() -> None:
    out = io.StringIO()
    show = SearchProgress(out, force=True)
    show(report(1, 0.1))
    show(report(2, 0.2))  # within 10 s of the first: kept for the end
    show.finish()
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue() and len(lines) == 2
    assert lines[-1].startswith("search: 0.2 s, 2 labels")


@pytest.mark.parametrize("command", ["plan", "dry-run", "upload", "download", "sweep"])
def test_every_command_that_shows_progress_takes_quiet(command: str, capsys) -> None:
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert "--quiet" in capsys.readouterr().out


def test_plan_quiet_writes_no_progress(capsys) -> None:
    args = [
        "plan",
        "missions/example/scenario.toml",
        "--objectives",
        "length,corrections,probability",
    ]
    assert main([*args, "--progress", "--quiet", "--json"]) == 0
    err = capsys.readouterr().err
    assert "labels," not in err and "set-up:" not in err
