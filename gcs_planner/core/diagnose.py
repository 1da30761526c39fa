"""Why a scenario has no feasible route: the limit, point or leg that rules every route out.

Every search calls :func:`why_infeasible` once its front is empty and its search exhaustive, so
that the user reads the same kind of reason whatever the leg model and objectives. The
diagnosis works on the reach graph, whose arcs are the leg model's heading-free lower bounds
(a leg too steep for R = 0 is no arc), in three steps from the coarsest relaxation down:

1. The direct leg A -> B and the corrections allowed: with no correction possible (none in the
   scenario, or ``max_corrections`` 0) the direct leg is the only route, and its length or
   slope is the reason.
2. Reachability over walks with heading-free legs and certain corrections: per point, the least
   error it can be reached with (a smaller carried error is never less feasible, so that one
   number decides what can follow). If B is out of reach, the reason is the first wall the
   walks hit: no correction point within reach of A; no point of one kind within its limits
   from anything reachable; the limit on corrections; or theta around B.
3. If walks reach B but the model does not (turns, or every route lost with certainty), the
   flown legs are the reason: no second leg (after the free first one) can be flown within the
   limits, or else the first limit the heading-free relaxation's shortest route breaks when it
   is flown with turns.

Numbers are given in the user's terms: metres, error units (metres times delta), degrees.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from gcs_planner.core.bnb.flown import flown_route
from gcs_planner.core.reach import ReachGraph, build_reach_graph
from gcs_planner.core.straight_search import search_front
from gcs_planner.geometry.legs import LegModel, scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

# Candidates per reachable point when looking for the nearest-to-feasible arrival at a kind of
# point (nearest by chord; enough to name one, which is all the message needs).
_NEAREST = 8


def why_infeasible(
    scenario: Scenario,
    graph: ReachGraph | None = None,
    max_corrections: int | None = None,
    *,
    probability: bool = False,
    simple_infeasible: bool = False,
) -> str:
    """One sentence: why no feasible route exists (the caller knows none does). ``graph``: the
    scenario's reach graph when the caller has it. ``probability``: routes were also required
    to arrive with a positive probability. ``simple_infeasible``: the caller's search was the
    heading-free one over simple routes (``search.straight_front``), so that is known empty."""
    graph = build_reach_graph(scenario) if graph is None else graph
    model = scenario_leg_model(scenario)
    p = scenario.params
    start = graph.start
    inner = scenario.n - 2
    kmax = inner if max_corrections is None else max(0, min(max_corrections, inner))
    direct = _direct_leg(scenario, model)
    if kmax == 0:
        if inner == 0:
            return f"the scenario has no correction points, and {direct}"
        return f"--max-corrections {max_corrections} forbids corrections, and {direct}"
    carried, fewest = _reach(graph, scenario.kind == Kind.V, kmax)
    if fewest < 0:
        if kmax < inner:
            _, unlimited = _reach(graph, scenario.kind == Kind.V, inner)
            if unlimited >= 0:
                return (
                    f"--max-corrections {kmax} is too few: every route needs at least "
                    f"{unlimited} corrections"
                )
        if not np.isfinite(carried[np.arange(scenario.n) != start]).any():
            detail = (
                f"{direct}; and the closest any feasible chain of corrections gets to B is A "
                f"itself: {_nothing_from_a(scenario, model)}"
            )
        else:
            detail = _unreached_kind(scenario, graph, model, carried) or _around_b(
                scenario, graph, carried
            )
        binding = _binding(scenario, kmax)
        return f"{binding}; as it is, {detail}" if binding else f"no route from A to B: {detail}"
    # Walks with heading-free legs reach B. Routes are simple: do any of them?
    relaxed = () if simple_infeasible else search_front(scenario, graph, max_corrections).front
    if not relaxed:
        walk = search_front(scenario, graph, max_corrections, max_rounds=1).front[0].points
        twice = sorted({scenario.ids[q] for q in walk if walk.count(q) > 1})
        return (
            "every chain of corrections that reaches B within the limits visits a point twice "
            f"(e.g. {','.join(scenario.ids[q] for q in walk)}: point {', '.join(twice)}), and a "
            "route visits each point once"
        )
    # Simple routes with heading-free legs exist: the flown legs rule them out.
    if model.carries_heading:
        return _turns(scenario, graph, model, relaxed)
    if probability:
        return (
            "routes exist when every correction succeeds, but each of them fails with "
            f"certainty (p_success={p.p_success:g})"
        )
    return "no route is feasible"  # (unreachable: the search and this diagnosis disagree)


# Above this many points the limits are not tried one by one (``_binding``): each try builds a
# reach graph, seconds on the largest maps.
_BINDING_MAX_POINTS = 5_000
_LIMITS = ("alpha1", "alpha2", "beta1", "beta2", "theta")
# What each limit bounds: (error, at, the kind of point).
_MEANING = {
    "alpha1": ("vertical error", "a V point", Kind.V),
    "alpha2": ("horizontal error", "a V point", Kind.V),
    "beta1": ("vertical error", "an H point", Kind.H),
    "beta2": ("horizontal error", "an H point", Kind.H),
    "theta": ("vertical and the horizontal error each", "B", Kind.B),
}


def _binding(scenario: Scenario, kmax: int) -> str:
    """Which single limit rules every route out: the error limits each raised alone to the
    largest of them, and with R = 0 the climb and descent limits lifted, each tried over walks
    with heading-free legs. '' when none alone does (or the map is too large to try)."""
    if scenario.n > _BINDING_MAX_POINTS:
        return ""
    p = scenario.params
    values = {name: float(getattr(p, name)) for name in _LIMITS}
    top = max(values.values())
    kind_v = scenario.kind == Kind.V
    tries = [(name, {name: top}) for name, value in values.items() if value < top]
    if p.turn_radius <= 0 and (p.max_climb_angle < 90 or p.max_descent_angle < 90):
        tries.append(("climb", {"max_climb_angle": 90.0, "max_descent_angle": 90.0}))
    enough = []
    for name, change in tries:
        relaxed = scenario.with_params(**change)
        if _reach(build_reach_graph(relaxed), kind_v, kmax)[1] >= 0:
            enough.append(name)
    if not enough:
        return ""
    if enough == ["climb"]:
        return (
            f"the climb and descent limits ({p.max_climb_angle:g} and {p.max_descent_angle:g} "
            "deg) rule every route out: with turning radius 0 a leg steeper than them cannot be "
            "flown, and without them routes would exist"
        )
    named = [f"{n}={values[n]:g}" for n in enough if n != "climb"]
    if len(named) == 1:
        name = enough[0] if enough[0] != "climb" else enough[1]
        error, where, kind = _MEANING[name]
        metres = p.limits_m(kind)[0 if error.startswith("vertical") else 1]
        return (
            f"{named[0]} rules every route out: the {error} on arrival at {where} must be "
            f"within {values[name]:g} (at most {metres:,.0f} m flown since the last "
            f"correction), and raised to {top:g}, the largest of the limits, it would allow "
            "routes"
        )
    return (
        f"each of {', '.join(named)} rules every route out (raising any one of them to "
        f"{top:g}, the largest of the limits, would allow routes)"
    )


def _units(scenario: Scenario, metres: float) -> str:
    return f"{metres * scenario.params.delta:.4g}"


def _direct_leg(scenario: Scenario, model: LegModel) -> str:
    """What the direct leg A -> B needs, against theta (or the climb limit)."""
    p = scenario.params
    a, b = scenario.xyz[scenario.start], scenario.xyz[scenario.end]
    bound = float(model.lower_bounds(a, b[None, :])[0])
    chord = float(np.linalg.norm(b - a))
    if not math.isfinite(bound):
        return _too_steep("the direct leg A->B", scenario, a, b)
    return (
        f"B is {bound:,.0f} m from A: its direct leg accumulates {_units(scenario, bound)} units "
        f"of error against theta={p.theta:g}"
        + ("" if bound <= chord * (1 + 1e-9) else f" (its chord is {chord:,.0f} m; the climb "
           "limit makes it longer)")
    )  # fmt: skip


def _too_steep(what: str, scenario: Scenario, a: np.ndarray, b: np.ndarray) -> str:
    p = scenario.params
    w = b - a
    angle = math.degrees(math.atan2(abs(w[2]), math.hypot(w[0], w[1])))
    climbs = w[2] > 0
    limit = p.max_climb_angle if climbs else p.max_descent_angle
    return (
        f"{what} {'climbs' if climbs else 'descends'} at {angle:.1f} deg, steeper than the "
        f"{'climb' if climbs else 'descent'} limit of {limit:g} deg (with turning radius 0 "
        "there is no helix to fly it on)"
    )


def _state(kind_v: np.ndarray, carried: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(vertical, horizontal) metres carried right after each point's correction: a V point
    carries only the horizontal error, an H point (and A, with 0) only the vertical."""
    return np.where(kind_v, 0.0, carried), np.where(kind_v, carried, 0.0)


def _reach(graph: ReachGraph, kind_v: np.ndarray, kmax: int) -> tuple[np.ndarray, int]:
    """Per point, the least error any walk with at most ``kmax`` corrections reaches it with
    (inf: none does), and the fewest corrections of a walk that reaches B within theta (-1:
    none). Layer by layer from the points whose error fell in the layer before: the others
    were expanded with that error already."""
    n, start, end = graph.n, graph.start, graph.end
    lim_b = graph.lim_v[end]
    carried = np.full(n, np.inf)
    carried[start] = 0.0
    frontier = np.array([start], dtype=np.int64)
    deg = graph.degree()
    for k in range(kmax + 1):
        v, h = _state(kind_v[frontier], carried[frontier])
        if (np.maximum(v, h) + graph.into_end[frontier] <= lim_b).any():
            return carried, k
        if k == kmax or not len(frontier):
            break
        counts = deg[frontier]
        src = np.repeat(frontier, counts)
        first = np.repeat(graph.indptr[frontier], counts)
        offset = np.arange(len(src)) - np.repeat(np.cumsum(counts) - counts, counts)
        arc = first + offset
        j = graph.target[arc].astype(np.int64)
        d = graph.length[arc]
        v, h = _state(kind_v[src], carried[src])
        ok = (j != end) & (v + d <= graph.lim_v[j]) & (h + d <= graph.lim_h[j])
        e = np.where(kind_v[j], h + d, v + d)
        best = np.full(n, np.inf)
        np.minimum.at(best, j[ok], e[ok])
        frontier = np.flatnonzero(best < carried)
        carried = np.minimum(carried, best)
    return carried, -1


def _nothing_from_a(scenario: Scenario, model: LegModel) -> str:
    """No correction point is reachable from A: the nearest of each kind, against its limits."""
    p = scenario.params
    a = scenario.xyz[scenario.start]
    bound = model.lower_bounds(a, scenario.xyz)
    parts = []
    for kind, name, limits in (
        (Kind.V, "V", (("alpha1", p.alpha1), ("alpha2", p.alpha2))),
        (Kind.H, "H", (("beta1", p.beta1), ("beta2", p.beta2))),
    ):
        pts = np.flatnonzero(scenario.kind == kind)
        if not len(pts):
            continue
        j = int(pts[np.argmin(bound[pts])])
        d = float(bound[j])
        tight = min(limits, key=lambda t: t[1])
        if not math.isfinite(d):
            parts.append(
                _too_steep(
                    f"every {name} point is too steep to reach: A->{scenario.ids[j]}",
                    scenario,
                    a,
                    scenario.xyz[j],
                )
            )
            continue
        parts.append(
            f"the nearest {name} point, {scenario.ids[j]}, is {d:,.0f} m away "
            f"({_units(scenario, d)} units against {tight[0]}={tight[1]:g})"
        )  # fmt: skip
    return "no correction point can be reached from A: " + "; ".join(parts)


def _unreached_kind(
    scenario: Scenario, graph: ReachGraph, model: LegModel, carried: np.ndarray
) -> str | None:
    """If no point of a kind (V or H) is reachable while the scenario has some: that kind's
    limits, and the arrival closest to them from any reachable point. None otherwise."""
    p = scenario.params
    kind_v = scenario.kind == Kind.V
    reached = np.flatnonzero(np.isfinite(carried) & (np.arange(scenario.n) != graph.end))
    for kind, name, (l1, l2) in (
        (Kind.V, "V", (("alpha1", p.alpha1), ("alpha2", p.alpha2))),
        (Kind.H, "H", (("beta1", p.beta1), ("beta2", p.beta2))),
    ):
        pts = np.flatnonzero(scenario.kind == kind)
        if not len(pts) or np.isfinite(carried[pts]).any():
            continue
        # The arrival at a point of this kind that comes nearest to its limits.
        tree = cKDTree(scenario.xyz[pts])
        _, near = tree.query(scenario.xyz[reached], k=min(_NEAREST, len(pts)))
        near = np.asarray(near).reshape(len(reached), -1)
        best = (math.inf, 0, 0, 0.0, 0.0, 0.0)
        v0, h0 = _state(kind_v[reached], carried[reached])
        for row, i in enumerate(reached):
            js = pts[near[row]]
            d = model.lower_bounds(scenario.xyz[i], scenario.xyz[js])
            v, h = v0[row] + d, h0[row] + d
            ratio = np.maximum(v / graph.lim_v[js], h / graph.lim_h[js])
            m = int(np.argmin(ratio))
            if ratio[m] < best[0]:
                best = (float(ratio[m]), int(i), int(js[m]), float(d[m]), float(v[m]), float(h[m]))
        _, i, j, d, v, h = best
        over = []
        if v > graph.lim_v[j]:
            over.append(f"v = {_units(scenario, v)} against {l1[0]}={l1[1]:g}")
        if h > graph.lim_h[j]:
            over.append(f"h = {_units(scenario, h)} against {l2[0]}={l2[1]:g}")
        src = "A" if i == scenario.start else f"point {scenario.ids[i]}"
        leg = f"{d:,.0f} m from {src}" if math.isfinite(d) else f"too steep to fly to from {src}"
        return (
            f"no chain from A reaches a {name} point within {l1[0]}={l1[1]:g} and "
            f"{l2[0]}={l2[1]:g} ({p.limits_m(kind)[0]:,.0f} m and {p.limits_m(kind)[1]:,.0f} m "
            f"flown since the last correction of each error): the nearest to them, "
            f"{name} point {scenario.ids[j]}, is {leg}, arriving with " + " and ".join(over)
        )
    return None


def _around_b(scenario: Scenario, graph: ReachGraph, carried: np.ndarray) -> str:
    """B is out of reach although correction points of each kind are: theta, and how close to
    B the reachable points come."""
    p = scenario.params
    lim_b = graph.lim_v[graph.end]
    reached = np.flatnonzero(np.isfinite(carried) & (np.arange(scenario.n) != graph.end))
    closest = int(reached[np.argmin(graph.to_end[reached])])
    d = float(graph.to_end[closest])
    where = "A itself" if closest == graph.start else f"point {scenario.ids[closest]}"
    return (
        f"the closest any feasible chain of corrections gets to B is {where}, {d:,.0f} m "
        f"from B, but B must be reached within theta={p.theta:g} "
        f"(at most {lim_b:,.0f} m flown since the last correction of each error, "
        f"delta={p.delta:g})"
    )


def _turns(scenario: Scenario, graph: ReachGraph, model: LegModel, relaxed: Sequence) -> str:
    """Heading-free routes (``relaxed``, the front of ``straight_search.search_front``) reach B
    but no route flown with turns does: the legs that cannot be flown, from the first ones out
    of A."""
    R = scenario.params.turn_radius
    xyz, kind_v = scenario.xyz, scenario.kind == Kind.V
    start, end = graph.start, graph.end
    radius = f"with turning radius {R:g} m ({model.name} legs)"
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
    lo, hi = graph.indptr[start], graph.indptr[start + 1]
    first = graph.target[lo:hi].astype(np.int64)
    flown, headings = model.lengths(xyz[start], heading_a, xyz[first])
    ok = (flown <= graph.lim_v[first]) & (flown <= graph.lim_h[first]) & (first != end)
    if not ok.any():
        i = int(np.argmin(flown / np.minimum(graph.lim_v[first], graph.lim_h[first])))
        return (
            f"{radius} and the heading given at A, no first leg can be flown within the limits: "
            f"{_flown_text(scenario, graph, start, int(first[i]), float(flown[i]))}"
        )
    # Second legs, from the heading each feasible first leg arrives with.
    best: tuple[float, int, int, float] | None = None
    sources = 0
    for idx in np.flatnonzero(ok):
        i = int(first[idx])
        e = float(flown[idx])  # the error i carries (both grew by the first leg)
        v0, h0 = (0.0, e) if kind_v[i] else (e, 0.0)
        a, b = graph.indptr[i], graph.indptr[i + 1]
        nxt = graph.target[a:b].astype(np.int64)
        nxt = nxt[nxt != start]
        if not len(nxt):
            continue
        sources += 1
        second, _ = model.lengths(xyz[i], None if headings is None else headings[idx], xyz[nxt])
        ratio = np.maximum((v0 + second) / graph.lim_v[nxt], (h0 + second) / graph.lim_h[nxt])
        m = int(np.argmin(ratio))
        if ratio[m] <= 1.0:
            break  # a second leg can be flown: the routes fail later
        if best is None or ratio[m] < best[0]:
            best = (float(ratio[m]), i, int(nxt[m]), float(second[m]))
    else:
        if best is None:
            return f"{radius} no route can be flown: no point follows any first leg from A"
        _, i, j, d = best
        if not math.isfinite(d):
            return (
                f"{radius} no second leg can be flown: after each of the {sources} first legs "
                "from A every next point lies inside the turning circle (e.g. "
                f"{_flown_text(scenario, graph, i, j, d)})"
            )
        return (
            f"{radius} no second leg can be flown within the limits: after each of the "
            f"{sources} first legs from A the aircraft must turn towards the next point, and "
            f"the nearest to feasible, {_flown_text(scenario, graph, i, j, d)}"
        )
    # The heading-free relaxation's routes, flown with turns: the first limit one breaks.
    for fp in relaxed:
        route = flown_route(scenario, fp.points)
        stop = route.first_violation()
        if stop is None:
            continue
        k = route.points.index(stop.index)
        prev = route.points[k - 1]
        over = []
        if not math.isfinite(stop.leg.length):
            over.append("its target lies inside the turning circle")
        else:
            if stop.v_flown > stop.v_limit_m:
                over.append(f"v = {stop.v_arrival:.4g} against {stop.v_limit:.4g}")
            if stop.h_flown > stop.h_limit_m:
                over.append(f"h = {stop.h_arrival:.4g} against {stop.h_limit:.4g}")
        ids = ",".join(scenario.ids[q] for q in fp.points)
        return (
            f"{radius} no route can be flown within the limits, though heading-free legs "
            f"would allow routes (the shortest with {fp.corrections} corrections: {ids}, "
            f"{fp.length:,.0f} m); flown with turns, its leg {scenario.ids[prev]}->{stop.id} "
            f"is {stop.leg.length:,.0f} m and arrives with " + " and ".join(over)
        )
    return f"{radius} no route can be flown within the limits"


def _flown_text(scenario: Scenario, graph: ReachGraph, i: int, j: int, flown: float) -> str:
    chord = float(np.linalg.norm(scenario.xyz[j] - scenario.xyz[i]))
    limit = float(min(graph.lim_v[j], graph.lim_h[j]))
    src = "A" if i == graph.start else scenario.ids[i]
    dst = "B" if j == graph.end else scenario.ids[j]
    if not math.isfinite(flown):
        return f"{src}->{dst}, chord {chord:,.0f} m"
    return (
        f"{src}->{dst} (chord {chord:,.0f} m), is flown as {flown:,.0f} m against at most "
        f"{limit:,.0f} m"
    )
