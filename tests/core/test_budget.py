"""The search budget: what a search cut short still proves, and the user's flags for it.

The mechanism behind the long-scenario report (a front of many-correction routes, each marked
optimal with gap 0, missing the routes with fewer corrections): best-first search by length
finds the short many-correction routes first, and a budget that ends it there leaves the longer
fewer-correction routes unexplored. Each found route's gap of 0 is true of that point, but
"optimal" must mean more: no route with no more corrections, nor one at least as likely to
arrive, left unexplored. These tests cut searches short at every budget and check both claims
against the exhaustive front.
"""

from __future__ import annotations

import io
import math

import pytest
from support.prefix_fronts import prefix_front
from support.scenarios import long_corridor_scenario, turning_scenario

from gcs_planner.cli import main
from gcs_planner.core.bnb import bnb_front
from gcs_planner.core.budget import Budget, Progress
from gcs_planner.core.planner import plan
from gcs_planner.errors import InfeasibleError
from gcs_planner.mission import plan_json
from gcs_planner.runtime.progress import SearchProgress
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Parameters

THREE = ("length", "corrections", "probability")
EPS = 1e-9


def claims_hold(front, proven, lower_bounds, exact, probability: bool) -> bool:
    """Check a cut-short front's claims against the exact front (Found-like items).

    Returns whether the cut-short front missed an exact route that an old-style flag (gap 0
    alone) would have hidden: a route with gap 0 beside a missing exact route with fewer
    corrections or a higher probability."""
    hidden = False
    for g, ok, lb in zip(front, proven, lower_bounds):
        best = min(
            (
                h.length
                for h in exact
                if h.corrections <= g.corrections
                and (not probability or h.probability >= g.probability - 1e-12)
            ),
            default=math.inf,
        )
        assert lb <= best + 1e-6, "a lower bound above the exact front"
        missing = [
            h
            for h in exact
            if (
                h.corrections <= g.corrections
                or (probability and h.probability > g.probability + 1e-12)
            )
            and not any(
                f.corrections == h.corrections
                and abs(f.length - h.length) < 1e-6
                and (not probability or abs(f.probability - h.probability) < 1e-9)
                for f in front
            )
        ]
        if ok:
            assert lb >= g.length - 1e-6
            assert not missing, f"route {g} marked optimal while the front misses {missing}"
        elif missing and lb >= g.length - 1e-6:
            hidden = True
    return hidden


@pytest.mark.parametrize("probability", [False, True])
def test_a_search_cut_short_never_marks_a_route_optimal_while_the_front_misses_one(
    probability: bool,
) -> None:
    hidden = cut = 0
    for seed in range(8):
        scenario = long_corridor_scenario(seed)
        full = bnb_front(scenario, probability=probability, max_labels=None)
        assert full.optimal and all(full.proven)
        for budget in sorted({1, 2, 3, 5, 8, full.labels // 4, full.labels // 2}):
            if not 0 < budget < full.labels:
                continue
            res = bnb_front(scenario, probability=probability, max_labels=budget)
            if res.optimal:
                continue
            cut += 1
            hidden += claims_hold(res.front, res.proven, res.lower_bounds, full.front, probability)
    assert cut >= 10
    # The mechanism occurs: routes with gap 0 beside missing routes (the old flag's error).
    assert hidden >= 1


@pytest.mark.parametrize("probability", [False, True])
def test_cut_short_claims_hold_against_enumeration_with_turns(probability: bool) -> None:
    checked = 0
    for seed in range(20):
        # at most 4 correction points (65 routes to fly, not 326), the same draws
        radius = [200.0, 1500.0][seed % 2]
        scenario = turning_scenario(seed, radius, max_points=4)
        # Enumerated with its routes flown by prefix, once for both objective sets.
        want = prefix_front(scenario, probability, ("turning_scenario", seed, radius, 4))
        exact = [_Point(w[0], w[1], -w[2] if probability else 1.0) for w in want]
        for budget in (1, 3, 8):
            res = bnb_front(scenario, probability=probability, max_labels=budget)
            claims_hold(res.front, res.proven, res.lower_bounds, exact, probability)
            checked += not res.optimal
    assert checked >= 8


class _Point:
    def __init__(self, length: float, corrections: int, probability: float) -> None:
        self.length, self.corrections, self.probability = length, corrections, probability


def test_plan_json_flags_follow_the_settled_rule() -> None:
    """The user-facing flag: plan() cut short, its JSON's "optimal" against the exact front."""
    checked = 0
    for seed in range(6):
        scenario = long_corridor_scenario(seed)
        try:
            full = plan(scenario, objectives=THREE, max_labels=None)
        except InfeasibleError:
            continue
        assert full.optimal and all(full.proven())
        cut = plan(scenario, objectives=THREE, max_labels=2)
        flags = [r["optimal"] for r in plan_json.plan_to_dict(cut)["front"]]
        assert flags == list(cut.proven())
        claims_hold(cut.routes, flags, cut.lower_bounds, full.routes, True)
        checked += 1
    assert checked >= 3


def test_three_objective_front_holds_the_two_objective_fewest_corrections_end() -> None:
    """Seeded by the two-objective front, even a search cut short at once keeps its fewest-
    corrections route (flown, with its probability) or one that dominates it."""
    for seed in range(6):
        scenario = long_corridor_scenario(seed, n=80)
        try:
            two = plan(scenario, objectives=("length", "corrections"))
        except InfeasibleError:
            continue
        fewest = two.routes[0]
        three = plan(scenario, objectives=THREE, max_labels=1)
        assert any(
            r.corrections <= fewest.corrections
            and r.length <= fewest.length + 1e-6
            and r.probability >= fewest.probability - 1e-12
            for r in three.routes
        )
        # The two-objective front bounds every three-objective route from below.
        for r, lb in zip(three.routes, three.lower_bounds):
            floor = min(q.length for q in two.routes if q.corrections <= r.corrections)
            assert lb >= floor - 1e-6 or not any(q.corrections <= r.corrections for q in two.routes)


def test_time_limit_zero_stops_before_the_first_label_and_names_the_flag() -> None:
    scenario = long_corridor_scenario(1)
    result = plan(scenario, objectives=THREE, max_labels=None, time_limit=0)
    assert not result.optimal
    assert "--time-limit" in result.statement
    assert result.stats["labels"] == 0


def test_time_limit_cuts_the_set_up_short_and_what_it_claims_still_holds() -> None:
    """With the limit already passed (0 s: deterministic) the bounds the search builds first are
    cut short or skipped, the statement says which, and the gaps it reports still hold."""
    checked = 0
    for seed in range(12):
        scenario = turning_scenario(seed, 200.0, max_points=4)
        want = prefix_front(scenario, True, ("turning_scenario", seed, 200.0, 4))
        if not want:
            continue
        exact = [_Point(w[0], w[1], -w[2]) for w in want]
        cut = plan(scenario, objectives=THREE, max_labels=None, time_limit=0)
        assert not cut.optimal and cut.stats["labels"] == 0
        assert "no bounds over the cone of arrival headings" in cut.stats["setup_cut"]
        assert "cut the set-up short" in cut.statement
        claims_hold(cut.routes, cut.proven(), cut.lower_bounds, exact, True)
        checked += 1
    assert checked >= 6


def test_infeasibility_not_proven_names_the_flag_to_raise() -> None:
    scenario = long_corridor_scenario(2).with_params(turn_radius=200.0)
    with pytest.raises(InfeasibleError, match="not proven.*--max-labels"):
        plan(scenario, objectives=("length", "corrections"), max_labels=0)
    with pytest.raises(InfeasibleError, match="not proven.*--time-limit"):
        plan(scenario, objectives=("length", "corrections"), max_labels=None, time_limit=0)


def test_progress_reports_bound_open_routes_and_routes_found() -> None:
    seen: list[Progress] = []
    scenario = long_corridor_scenario(3)
    budget = Budget(max_labels=None, progress=seen.append, every=0.0)
    res = bnb_front(scenario, probability=True, budget=budget)
    seen = [p for p in seen if not p.setup]  # the set-up's own reports: see the next test
    assert len(seen) == res.labels > 0
    if res.rounds == 1:
        assert [p.labels for p in seen] == list(range(1, res.labels + 1))
    assert all(0 < p.bound < math.inf and p.open_routes >= 0 for p in seen)
    assert seen[-1].routes_found >= 1
    out = io.StringIO()
    show = SearchProgress(out, force=True)  # --progress into a log: plain lines
    show(seen[-1])
    show.finish()
    line = out.getvalue()
    assert "labels" in line and "partial routes open" in line and "routes found" in line
    assert line.endswith("\n") and "\r" not in line  # no terminal: one plain line per report


def test_progress_shows_the_set_up_before_the_search() -> None:
    """On large maps the bounds take seconds before the first label: the console is told what
    is being built (every report is due here: ``every`` = 0)."""
    seen: list[Progress] = []
    scenario = turning_scenario(3, radius=200.0)
    budget = Budget(max_labels=None, progress=seen.append, every=0.0)
    res = bnb_front(scenario, probability=True, budget=budget)
    setup = [p.setup for p in seen if p.setup]
    assert setup[:2] == ["cost-to-go, layer 0", "cost-to-go, layer 1"]
    assert any(s.startswith("bounds over headings, layer") for s in setup)
    first_label = next(i for i, p in enumerate(seen) if p.labels)
    assert not any(p.setup.startswith("cost-to-go") for p in seen[first_label:])
    assert res.optimal and not res.cut  # no time limit: nothing cut
    out = io.StringIO()
    show = SearchProgress(out, force=True)
    show(seen[0])
    assert out.getvalue() == f"set-up: cost-to-go, layer 0, {seen[0].seconds:.1f} s\n"


def test_budget_flags_on_the_command_line(capsys) -> None:
    scenario = "missions/example/scenario.toml"
    rc = main(["plan", scenario, "--objectives", ",".join(THREE), "--time-limit", "0", "--json"])
    captured = capsys.readouterr()
    assert rc == 0 or "not proven" in captured.err
    if rc == 0:
        import json

        doc = json.loads(captured.out)
        assert doc["optimality"]["optimal"] is False
        assert "--time-limit" in doc["optimality"]["statement"]
    for bad in (["--time-limit", "-1"], ["--time-limit", "soon"], ["--max-labels", "-5"]):
        with pytest.raises(SystemExit) as exc:
            main(["plan", scenario, *bad])
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert bad[0] in err and "Traceback" not in err


def test_progress_flag_prints_to_stderr_only(capsys) -> None:
    rc = main(
        [
            "plan",
            "missions/example/scenario.toml",
            "--objectives",
            ",".join(THREE),
            "--progress",
            "--max-labels",
            "50",
            "--json",
        ]
    )
    assert rc == 0
    captured = capsys.readouterr()
    assert captured.out.lstrip().startswith("{")  # stdout stays one JSON object
    assert "Traceback" not in captured.err


def test_table_marks_routes_that_are_not_settled(capsys) -> None:
    args = ["plan", "missions/example/scenario.toml", "--objectives", ",".join(THREE)]
    assert main([*args, "--max-labels", "3"]) == 0
    cut = capsys.readouterr().out
    assert "? = not settled" in cut
    assert main([*args, "--max-labels", "0"]) == 0  # no limit: proven
    full = capsys.readouterr().out
    assert "optimality: exact" in full and "? = not settled" not in full


def test_long_corridor_three_objective_front_is_proven_and_holds_the_two_objective_front() -> None:
    """A 300 km corridor of 2,000 points with straight legs (routes of some 25 corrections whose
    lengths differ by metres): the three-objective front is proven within the default budget,
    and every route of the two-objective front is on it (a route dominating one would have to
    be as short with as few corrections), its fewest-corrections end among them."""
    scenario = random_scenario(
        2000, 1, params=Parameters(25, 15, 20, 25, 30, 0.001, turn_radius=0.0),
        box=(300_000, 20_000, 2_000),
    )  # fmt: skip
    two = plan(scenario, objectives=("length", "corrections"))
    three = plan(scenario, objectives=THREE)
    assert three.optimal and all(three.proven())
    assert len(three.routes) > len(two.routes) >= 2
    for r in two.routes:
        assert any(
            q.corrections == r.corrections
            and abs(q.length - r.length) <= 1e-6
            and q.probability >= r.probability - 1e-12
            for q in three.routes
        ), (r.length, r.corrections)
    assert min(q.corrections for q in three.routes) == two.routes[0].corrections
