"""The probes of the search over simple routes (``_Prober``): whether a partial route can
still lead anywhere, asked of the relaxation that proved the floor."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from gcs_planner.core.bnb.context import _Context
from gcs_planner.core.bnb.dominance import _dominated_by, _kept, _key
from gcs_planner.core.bnb.incumbents import _Incumbents
from gcs_planner.core.bnb.open_routes import _Open
from gcs_planner.core.bnb.search import MAX_COMPILED_CRITICAL, _search
from gcs_planner.core.budget import Budget
from gcs_planner.core.failure_bounds import FailureBounds

if TYPE_CHECKING:
    from gcs_planner.core.probe_kernel import CompiledProbes


class _Prober:
    """Whether a partial route of the search over simple routes can still lead anywhere, asked
    of the relaxation that proved the floor: the exact relaxed completions of the partial route,
    searched with dominance, each compared with the routes found so far.

    Relaxing a completion only shortens its legs and raises its probability, and the partial
    route's own past is exact (its length, corrections and error states): so if every relaxed
    completion is dominated by a found route, every flown one is too, and the partial route is
    covered. The relaxation's search is small where the simple routes' search is not: partial
    routes at one point that came by one arc compare by dominance there (``pair_relaxed``)."""

    def __init__(self, ctx: _Context, critical: Sequence[int]) -> None:
        # The same bounds, made once: once the probes before (not the search) have spent
        # enough, so that a probe, compiled or not, has them throughout or not at all.
        self.root = ctx
        self.spent = 0  # labels of the probes so far
        self.ctx = ctx.probing(self.failures)
        self.max_labels = ctx.options.probe_labels
        # Walks that revisit none of these points: the floor's, under which it was exact.
        self.critical = frozenset(critical)
        # The probes compiled (``probe_kernel``): the same answers, made on first need (numba
        # is loaded only by searches that probe).
        self.compiled: CompiledProbes | None = None
        self._compile = ctx.options.compiled_probes and len(self.critical) <= MAX_COMPILED_CRITICAL
        # Partial routes of the relaxation proven covered, by ``_key``; the found routes only
        # grow, so they stay covered.
        self.nogoods: dict[tuple, list[tuple]] = {}
        # Prefixes of relaxed completions that escaped a probe, and of the routes the search
        # starts with: a partial route along one is likely to escape too (its own relaxed
        # completion is no longer than the route and at least as likely), so it is expanded
        # unprobed (skipping a probe is always sound).
        self.hopeful: set[tuple[int, ...]] = set()

    def failures(self, _spent: int = 0) -> FailureBounds | None:
        """The search's failure bounds for a probe, by the labels of the probes before it (a
        probe's own labels do not count: it has them throughout or not at all)."""
        return self.root.failures(self.spent)

    def hope(self, points: Sequence[int], after: int = 1) -> None:
        """Mark the prefixes of ``points`` longer than ``after`` points (not the whole route)
        hopeful."""
        points = tuple(points)
        self.hopeful.update(points[:n] for n in range(after + 1, len(points)))

    def __call__(self, entry: _Open, inc: _Incumbents, budget: Budget) -> tuple[bool, int]:
        """(covered, labels spent) for the heap ``entry`` of the search whose routes are
        ``inc``."""
        f, _, L, node, k, states, _heading, path, to_go, arc = entry
        if path in self.hopeful:
            return False, 0
        if self._compile and (
            # On a first run, Python probes until the search has compiled (``first_run``).
            not self.root.options.probes_after_search
            or "gcs_planner.core.search_kernel" in sys.modules
        ):
            if self.compiled is None:
                # Numba compiles the kernel on its first use after installing (about 6 s of
                # CPU on the 2-core test machine after the search's, 17 s without; see
                # docs/benchmarks.md, "The first plan after installing") and loads it from its
                # cache after that.
                budget.setup("the compiled probes (compiled once after installing)")
                from gcs_planner.core.probe_kernel import CompiledProbes

                self.compiled = CompiledProbes(self.ctx, self.critical)
            child = budget.probe(self.max_labels)
            limit = 0 if child.expired() else self.max_labels
            covered, labels, escape = self.compiled(
                inc, L, node, k, states, arc, path, to_go, limit
            )
            self.spent += labels
            if escape:
                self.hope(path + escape, after=len(path))
            return covered, labels
        key = _key(self.critical, node, path[:-1])
        state = _kept(L, k, states, sum(states.values()), arc)
        if _dominated_by(self.nogoods.get(key, ()), state, self.ctx.pair_floor):
            return True, 0
        # The pair relaxation's heading is the arc flown last.
        first = arc if self.ctx.pair_floor is not None else None
        origin = _Open(f, 0, L, node, k, states, first, path, to_go, arc)
        res = _search(
            self.ctx,
            self.critical,
            budget.probe(self.max_labels),
            (),
            origin=origin,
            incumbents=inc,
            nogoods=self.nogoods,
        )
        self.spent += res.labels
        for w in res.front:
            self.hope(w.points, after=len(path))
        return res.optimal, res.labels
