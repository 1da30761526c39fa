"""The records the compiled search and probes take (numba types a NamedTuple as a record).

Each is made by the object it describes (the reach graph with the model's numbers, a cost-to-go
table, the pair and failure bounds, the found routes, the nogood store). Where a part is
absent (no pair relaxation, no failure bounds yet) an empty record of the same dtypes stands
for it, its ``present`` False: the kernel is then compiled once, not once per combination.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class ToGo(NamedTuple):
    """A cost-to-go table (``cost_to_go.CostToGo``): per point its rows ``indptr[j]:indptr[j+1]``,
    sorted by ``e_max``; ``table[i, m]`` the least length to B with at most m more corrections."""

    indptr: np.ndarray  # int64
    e_max: np.ndarray
    table: np.ndarray  # (rows, layers)


NO_TO_GO = ToGo(np.zeros(1, np.int64), np.empty(0), np.empty((0, 1)))


class Graph(NamedTuple):
    """The reach graph (CSR by tail) and what a step along it needs of the scenario."""

    indptr: np.ndarray  # int64
    target: np.ndarray
    length: np.ndarray  # heading-free leg lengths, per arc
    lim_v: np.ndarray  # per point: the largest vertical error it accepts
    lim_h: np.ndarray
    start: int
    end: int
    to_end_start: float  # the straight distance from A to B
    start_v: float  # the errors at A (``Scenario.initial_errors``), metres since the last reset
    start_h: float
    kind: np.ndarray  # int64, per point (scenario.Kind)
    unreliable: np.ndarray  # bool, per point
    p_success: float
    residual_m: float
    kmax: int
    crit_bit: np.ndarray  # int64, per point: its bit among the critical points (-1: none)


class Pairs(NamedTuple):
    """The pair relaxation (``pair_bounds.PairBounds``): legs lb(i, j, t) per arc flown last."""

    present: bool
    node_of_arc: np.ndarray  # int64
    pair_ptr: np.ndarray  # int64
    length: np.ndarray
    to_go: ToGo  # over the arcs


NO_PAIRS = Pairs(False, np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0), NO_TO_GO)


class Failures(NamedTuple):
    """The bounds per probability level (``failure_bounds.FailureBounds``)."""

    present: bool
    to_go: ToGo  # over the expanded graph (point, failures so far)
    n: int
    failures: int
    q_fail: float
    is_v: np.ndarray  # bool, per node


NO_FAILURES = Failures(False, NO_TO_GO, 0, 0, 0.0, np.zeros(1, bool))


class Incumbents(NamedTuple):
    """The found routes (``bnb._Incumbents``) and the ceiling per probability level."""

    has_ceiling: bool
    ceiling_rows: np.ndarray  # (levels + 1, kmax + 1)
    length: np.ndarray
    k: np.ndarray  # int64
    p: np.ndarray
    probs_sorted: np.ndarray
    order: np.ndarray  # int64: the routes by probability, ascending (stable)
    levels: np.ndarray


class Partial(NamedTuple):
    """The partial route a probe starts from."""

    L: float
    node: int
    k: int
    sv: np.ndarray  # its error states: vertical, horizontal, mass
    sh: np.ndarray
    sm: np.ndarray
    arc: int  # the arc flown last
    mask_before: int  # critical points visited before its point
    mask: int  # and with its point
    to_go: np.ndarray


class Nogoods(NamedTuple):
    """The partial routes proven covered (``probe_kernel.CompiledProbes``), entries linked back
    per (point, critical points visited) from a typed dict kept beside the record."""

    next: np.ndarray  # int64
    L: np.ndarray
    k: np.ndarray  # int64
    mass: np.ndarray
    arc: np.ndarray  # int64
    vmin: np.ndarray
    hmin: np.ndarray
    ss: np.ndarray  # int64: first state
    sn: np.ndarray  # int64: states
    sv: np.ndarray  # the states: vertical, horizontal, mass
    sh: np.ndarray
    sm: np.ndarray


def empty_nogoods(entries: int, states: int) -> Nogoods:
    """A nogood store with room for ``entries`` partial routes and ``states`` error states."""
    return Nogoods(
        np.full(entries, -1, np.int64),
        np.empty(entries),
        np.empty(entries, np.int64),
        np.empty(entries),
        np.empty(entries, np.int64),
        np.empty(entries),
        np.empty(entries),
        np.empty(entries, np.int64),
        np.empty(entries, np.int64),
        np.empty(states),
        np.empty(states),
        np.empty(states),
    )


class Legs(NamedTuple):
    """How the search flies its legs: ``mode`` one of ``search_kernel.LEGS_*``; the points and
    the airplane or cs3d model's numbers for the legs flown from the heading."""

    mode: int
    xyz: np.ndarray
    radius: float
    tan_climb: float
    tan_descent: float
    has_heading_a: bool
    heading_a: np.ndarray  # (3,)
    run_in: float  # airplane legs: least tangent into a point, m (0: none)
    run_out: float  # airplane legs: straight on from a point before turning, m
    # Airplane legs: the radius and the limits' tangents at each point's altitude; a leg takes
    # the largest radius and the smallest tangents of its two ends (airplane.LegEnvelope).
    radius_at: np.ndarray
    tan_climb_at: np.ndarray
    tan_descent_at: np.ndarray
    # The TAS each point's limits are taken at, and the design wind's (east, north) m/s where
    # each leg's angles follow its own track (zeros: from any direction; airplane_kernel).
    airspeed_at: np.ndarray
    wind: np.ndarray


class Seeds(NamedTuple):
    """The routes a search starts with (points as CSR)."""

    length: np.ndarray
    k: np.ndarray  # int64
    p: np.ndarray
    ptr: np.ndarray  # int64
    points: np.ndarray  # int64
