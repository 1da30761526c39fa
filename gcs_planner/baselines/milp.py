"""The shortest feasible simple route with at most k corrections, as a 0-1 MILP (HiGHS).

Formulation (straight legs; distances and limits in metres flown, as ``Parameters.limits_m``):

- x_ij ∈ {0, 1} for every arc i → j that some route could use: j ≠ A, i ≠ B, and
  d_ij ≤ min(lim_v(j), lim_h(j)) (even right after both resets a longer leg arrives past a limit;
  this also implies d_ij ≤ ``Parameters.reach_m``).
- Flow: one arc leaves A, one enters B, and a correction point has in-flow = out-flow ≤ 1, so
  each point is used at most once.
- V_j, H_j ≥ 0: metres flown since the last vertical / horizontal reset on arrival at j (before
  its correction), bounded above by j's arrival limits. After j they carry on as V'_j = V_j
  (0 if j is a V point) and H'_j = H_j (0 if j is an H point); at A both are 0.
  On a used arc: V_j ≥ V'_i + d_ij and H_j ≥ H'_i + d_ij, written with big-M as
  V_j ≥ V'_i + d_ij − M_ij (1 − x_ij) where M_ij = ub(V'_i) + d_ij is the smallest M that
  leaves V_j ≥ 0 free when the arc is unused (ub from the scenario's limits, not a guess).
  V_j only has to be an upper estimate of the true error: the solver can always pick the true
  value, so "an estimate within the limit exists" ⇔ "the true error is within the limit".
- Σ_j in-flow(j) over correction points ≤ k, and Σ d_ij x_ij ≤ L̄, with L̄ = ``length_cap`` (a
  bound the error limits alone imply) or a caller's tighter bound; arcs with
  d(A, i) + d_ij + d(j, B) > L̄ are not generated at all.
- Subtours: the error variables alone exclude a cycle of correction points of a single kind
  (summing V_j ≥ V_i + d_ij round such a cycle gives 0 ≥ Σ d > 0), but not a cycle mixing V and
  H points, whose resets absorb the growth. With positive distances a cycle detached from the
  A–B path only adds length, so an optimum would not hold one, but a time-limited incumbent
  may, and coincident points give zero-length cycles. So Miller–Tucker–Zemlin order variables
  u_j (u_A = 0, u_j ≥ u_i + 1 − M_u (1 − x_ij)) exclude every cycle structurally: summed round
  a cycle not through A they give 0 ≥ |cycle|. A route has at most k + 1 legs, so u ≤ k + 1
  and M_u = k + 2.

Tolerances: HiGHS decides feasibility to 1e-7 (rows) and integrality to 1e-6, and the big-M rows
turn an "integral" x = 1 − 1e-6 into up to M·1e-6 m of slack. So the MILP's answer is never
trusted as is: the route is read off the rounded x, re-evaluated with ``evaluate_route`` (exact
float arithmetic, the same as every other part of the project), and if it is not feasible there
a no-good cut excluding that arc set is added and the MILP solved again. The optimality gap is
set to 0 relative and HiGHS's default 1e-6 absolute on the objective (metres): lengths are
optimal to within 1e-6 m.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import coo_array

from gcs_planner.baselines import Front
from gcs_planner.baselines.brute import distance_matrix
from gcs_planner.core.route import evaluate_route
from gcs_planner.scenario.model import Kind, Scenario

# Gap between the shortest lengths of two numbers of corrections below which the longer count is
# not a new point of the front: the MILP's lengths are only proven optimal to HiGHS's 1e-6 m.
LENGTH_TOL_M = 1e-6
# A no-good cut per re-solve; a route violating a limit by more than HiGHS's tolerances is rare,
# so a handful of cuts is plenty and more means something is wrong with the model.
MAX_CUTS = 50
# Slack on an upper bound on the length (metres), so that a route of exactly that length
# survives the rounding of the sums that test it.
UB_SLACK_M = 1e-3


@dataclass(frozen=True)
class MilpResult:
    """Outcome of one MILP solve.

    ``status`` is "optimal", "infeasible" (proven: no feasible route with ≤ k corrections),
    "time_limit" (``route`` then holds the best route found, if any, not proven optimal) or
    "error". ``seconds`` is the wall time of all solves including re-solves after cuts.
    """

    status: str
    length: float | None
    route: tuple[int, ...] | None
    corrections: int | None
    seconds: float
    optimal: bool
    cuts: int = 0
    arcs: int = 0


class MilpNotProvenError(RuntimeError):
    """A solve of ``milp_front`` ran out of time: the front so far is not proven exact."""

    def __init__(self, message: str, partial: Front) -> None:
        super().__init__(message)
        self.partial = partial


def _arrival_limits(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    lim_v = np.full(scenario.n, np.inf)
    lim_h = np.full(scenario.n, np.inf)
    for i, code in enumerate(scenario.kind):
        lim_v[i], lim_h[i] = scenario.params.limits_m(Kind(int(code)))
    return lim_v, lim_h


@dataclass(frozen=True)
class _Model:
    """The MILP without the cardinality bound and cuts, which vary per solve."""

    src: np.ndarray
    dst: np.ndarray
    dist: np.ndarray
    corrections: np.ndarray  # indices of correction points
    lim_v: np.ndarray
    lim_h: np.ndarray


def length_cap(scenario: Scenario, max_corrections: int) -> float:
    """Longest any feasible route with at most ``max_corrections`` corrections can be.

    Cut a route at its V points: each piece ends at a V point, where the vertical error (the
    piece's length) is at most α1/δ, or at B (θ/δ). So length ≤ n_V·α1/δ + θ/δ, and likewise
    ≤ n_H·β2/δ + θ/δ over the H points; n_V + n_H ≤ k. Nothing about the points is assumed.
    """
    params = scenario.params
    per_v = params.limits_m(Kind.V)[0]
    per_h = params.limits_m(Kind.H)[1]
    last = max(params.limits_m(Kind.B))
    k = max(0, int(max_corrections))
    return max(min(n_v * per_v, (k - n_v) * per_h) + last for n_v in range(k + 1))


def _arcs(scenario: Scenario, upper_bound: float | None) -> _Model:
    dist_all = distance_matrix(scenario)
    lim_v, lim_h = _arrival_limits(scenario)
    start, end = scenario.start, scenario.end
    n = scenario.n
    src, dst = np.nonzero(~np.eye(n, dtype=bool))
    d = dist_all[src, dst]
    keep = (
        (dst != start)
        & (src != end)
        & (d <= np.minimum(lim_v[dst], lim_h[dst]))
        & (d <= scenario.params.reach_m)
    )
    if upper_bound is not None:
        # An arc on a route no longer than the bound has d(A, i) + d_ij + d(j, B) ≤ bound by
        # the triangle inequality. The slack keeps a route of exactly that length despite
        # rounding in the three-term sum.
        via = dist_all[start, src] + d + dist_all[dst, end]
        keep &= via <= upper_bound + UB_SLACK_M
    is_corr = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    return _Model(src[keep], dst[keep], d[keep], np.flatnonzero(is_corr), lim_v, lim_h)


def _solve(
    scenario: Scenario,
    model: _Model,
    max_corrections: int,
    cuts: list[np.ndarray],
    time_limit: float,
    length_bound: float,
) -> tuple[str, np.ndarray | None]:
    """One HiGHS solve; returns (status, arc values or None)."""
    n = scenario.n
    m = len(model.src)
    start, end = scenario.start, scenario.end
    kind = scenario.kind
    src, dst, d = model.src, model.dst, model.dist
    k_cap = int(min(max_corrections, len(model.corrections)))
    # Column layout: x (m arcs) | V (n) | H (n) | u (n).
    ov, oh, ou = m, m + n, m + 2 * n
    n_var = m + 3 * n
    arc = np.arange(m)

    rows: list[np.ndarray] = []
    cols: list[np.ndarray] = []
    vals: list[np.ndarray] = []
    lo: list[np.ndarray] = []
    hi: list[np.ndarray] = []
    n_rows = 0

    def add(r: np.ndarray, c: np.ndarray, v: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> None:
        nonlocal n_rows
        rows.append(r + n_rows)
        cols.append(c)
        vals.append(np.asarray(v, dtype=float))
        lo.append(lb)
        hi.append(ub)
        n_rows += len(lb)

    # Flow at every point: out − in = 1 at A, −1 at B, 0 elsewhere.
    rhs = np.zeros(n)
    rhs[start], rhs[end] = 1.0, -1.0
    add(
        np.concatenate([src, dst]),
        np.concatenate([arc, arc]),
        np.concatenate([np.ones(m), -np.ones(m)]),
        rhs,
        rhs,
    )
    # Each point entered at most once (B exactly once, by the flow row).
    add(dst, arc, np.ones(m), np.zeros(n), np.ones(n))
    # Cardinality: arcs entering a correction point.
    into_corr = np.flatnonzero(np.isin(dst, model.corrections))
    add(
        np.zeros(len(into_corr), dtype=np.int64),
        into_corr,
        np.ones(len(into_corr)),
        np.array([-np.inf]),
        np.array([float(k_cap)]),
    )

    # Error propagation: E_j − E'_i − M_ij x_ij ≥ d_ij − M_ij, E'_i = E_i unless i resets E
    # (then E'_i = 0 and the term drops). ub(E'_i) is i's own arrival limit (0 at A).
    for offset, lim, reset in ((ov, model.lim_v, Kind.V), (oh, model.lim_h, Kind.H)):
        carries = (kind[src] != reset) & (src != start)
        ub_prev = np.where(carries, lim[src], 0.0)
        big_m = ub_prev + d
        r = np.concatenate([arc, arc, arc[carries]])
        c = np.concatenate([offset + dst, arc, offset + src[carries]])
        v = np.concatenate([np.ones(m), -big_m, -np.ones(int(carries.sum()))])
        add(r, c, v, d - big_m, np.full(m, np.inf))

    # MTZ order: u_j − u_i − M_u x_ij ≥ 1 − M_u.
    m_u = float(k_cap + 2)
    add(
        np.concatenate([arc, arc, arc]),
        np.concatenate([ou + dst, ou + src, arc]),
        np.concatenate([np.ones(m), -np.ones(m), -np.full(m, m_u)]),
        np.full(m, 1.0 - m_u),
        np.full(m, np.inf),
    )

    # Length bound: the arcs kept lie within it one by one, a route must as a whole.
    add(
        np.zeros(m, dtype=np.int64),
        arc,
        d,
        np.array([-np.inf]),
        np.array([length_bound + UB_SLACK_M]),
    )
    # No-good cuts: a rejected arc set may not be used in full again.
    for used in cuts:
        add(
            np.zeros(len(used), dtype=np.int64),
            used,
            np.ones(len(used)),
            np.array([-np.inf]),
            np.array([float(len(used) - 1)]),
        )

    a = coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(n_rows, n_var),
    ).tocsr()
    constraint = LinearConstraint(a, np.concatenate(lo), np.concatenate(hi))

    lb = np.zeros(n_var)
    ub = np.empty(n_var)
    ub[:m] = 1.0
    ub[ov : ov + n] = np.where(np.isfinite(model.lim_v), model.lim_v, 0.0)
    ub[oh : oh + n] = np.where(np.isfinite(model.lim_h), model.lim_h, 0.0)
    ub[ou : ou + n] = k_cap + 1
    # A: no error, order 0 (its limits are infinite; 0 is its only value anyway).
    ub[ov + start] = ub[oh + start] = ub[ou + start] = 0.0
    integrality = np.zeros(n_var)
    integrality[:m] = 1
    cost = np.zeros(n_var)
    cost[:m] = d

    res = milp(
        cost,
        integrality=integrality,
        bounds=Bounds(lb, ub),
        constraints=constraint,
        options={"time_limit": float(time_limit), "mip_rel_gap": 0.0, "presolve": True},
    )
    # scipy: 0 optimal, 1 iteration/time limit, 2 infeasible, 3 unbounded, 4 other.
    status = {0: "optimal", 1: "time_limit", 2: "infeasible"}.get(res.status, "error")
    return status, (None if res.x is None else np.asarray(res.x[:m]))


def _route_from_arcs(scenario: Scenario, model: _Model, x: np.ndarray) -> tuple[int, ...]:
    """Follow the used arcs from A to B (subtours are excluded by the model)."""
    used = np.flatnonzero(x > 0.5)
    succ = {int(model.src[a]): int(model.dst[a]) for a in used}
    route = [scenario.start]
    while route[-1] != scenario.end:
        nxt = succ.get(route[-1])
        if nxt is None or len(route) > scenario.n:
            raise RuntimeError("MILP solution is not a path from A to B")
        route.append(nxt)
    return tuple(route)


def milp_shortest(
    scenario: Scenario,
    max_corrections: int,
    time_limit: float = 60.0,
    upper_bound: float | None = None,
) -> MilpResult:
    """Shortest feasible simple route with at most ``max_corrections`` corrections.

    ``time_limit`` bounds the total HiGHS time in seconds (shared by re-solves after cuts).
    ``upper_bound``, if given, must be the length of some feasible route with at most
    ``max_corrections`` corrections (or any length not below the optimum): arcs that cannot
    lie on a route that short are dropped, which shrinks large scenarios to an ellipse around
    A–B, and the route length is constrained to it. A bound below the optimum makes the answer
    "infeasible". The same bound always applies with ``length_cap``, implied by the error
    limits alone. The returned route,
    if any, is feasible per ``evaluate_route``.
    """
    t0 = time.perf_counter()
    cap = length_cap(scenario, max_corrections)
    bound = cap if upper_bound is None else min(upper_bound, cap)
    model = _arcs(scenario, bound)
    arc_index = {
        (int(s), int(t)): a for a, (s, t) in enumerate(zip(model.src, model.dst, strict=True))
    }
    cuts: list[np.ndarray] = []
    while True:
        remaining = time_limit - (time.perf_counter() - t0)
        if remaining <= 0:
            return MilpResult(
                "time_limit",
                None,
                None,
                None,
                time.perf_counter() - t0,
                False,
                len(cuts),
                len(model.src),
            )
        status, x = _solve(scenario, model, max_corrections, cuts, remaining, bound)
        elapsed = time.perf_counter() - t0
        if x is None:
            return MilpResult(
                status, None, None, None, elapsed, status == "infeasible", len(cuts), len(model.src)
            )
        route = _route_from_arcs(scenario, model, x)
        evaluated = evaluate_route(scenario, route)
        if evaluated.feasible:
            return MilpResult(
                status,
                evaluated.length,
                route,
                evaluated.corrections,
                elapsed,
                status == "optimal",
                len(cuts),
                len(model.src),
            )
        if len(cuts) >= MAX_CUTS:
            return MilpResult("error", None, None, None, elapsed, False, len(cuts), len(model.src))
        cuts.append(
            np.array([arc_index[(a, b)] for a, b in zip(route[:-1], route[1:], strict=True)])
        )


def milp_front(
    scenario: Scenario, time_limit: float = 60.0, upper_bound: float | None = None
) -> Front:
    """The exact (length, corrections) front by solving for ≤ k corrections, k = 0, 1, ...

    First the problem without a cardinality bound gives the overall shortest length L*; then k
    grows until its shortest length reaches L* (no larger k can improve on it). A k whose
    shortest length is no shorter than k − 1's (to ``LENGTH_TOL_M``) adds no point: the front
    can have gaps. ``time_limit`` applies to each solve; a solve that runs out of time raises
    ``MilpNotProvenError`` carrying the front found so far. ``upper_bound`` (the length of any
    known feasible route) only prunes the first, unbounded-k solve; each later solve for ≤ k
    is pruned by the shortest length found for ≤ k − 1, which cannot be shorter than its own.
    """
    n_corr = int(np.sum((scenario.kind == Kind.V) | (scenario.kind == Kind.H)))
    overall = milp_shortest(scenario, n_corr, time_limit, upper_bound)
    if overall.status == "infeasible":
        return []
    if not overall.optimal or overall.length is None:
        raise MilpNotProvenError(f"unbounded-k solve ended with {overall.status}", [])
    front: Front = []
    for k in range(0, n_corr + 1):
        bound = front[-1][0] if front else None
        res = milp_shortest(scenario, k, time_limit, bound)
        if res.status == "infeasible":
            continue
        if not res.optimal or res.length is None or res.route is None:
            raise MilpNotProvenError(f"solve for k ≤ {k} ended with {res.status}", front)
        if not front or res.length < front[-1][0] - LENGTH_TOL_M:
            front.append((res.length, int(res.corrections), res.route))
        if res.length <= overall.length + LENGTH_TOL_M:
            break
    return front
