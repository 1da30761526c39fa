"""Success probability of a route under uncertain corrections (docs/model.md, "Uncertain
corrections").

At an unreliable point the correction succeeds with probability p; on failure the component it
corrects becomes min(component, r). Outcomes are independent, so the errors after each point form
a Markov chain over (v, h). :func:`success_probability` runs that chain exactly, merging identical
states; :func:`monte_carlo_success` replays it at random; :func:`brute_force_success` enumerates
every outcome vector and is only an independent reference for tests.

Errors are kept in metres flown since the last effective reset (error / delta), exactly as
:func:`gcs_planner.core.route.evaluate_route` keeps them, and a constraint holds iff
``flown <= limit_m``. With every correction succeeding, the three functions therefore take the
same feasibility decisions as ``evaluate_route``, bit for bit.

Why merging identical float keys is exact, and why equal states do produce equal keys:

- The transition of a state depends on the state alone (the outcome draws are independent of
  the past), so adding the masses of two identical states before propagating them gives the same
  distribution as propagating them apart and adding afterwards (Chapman-Kolmogorov). Merging can
  only lose exactness if two keys that should be one stay apart, and even that would cost states,
  never probability.
- Each component's value is produced by one fixed recipe: a *base* set at its last effective
  reset, 0.0 after a success or the single float ``residual_m = r / delta`` after a failure that
  clipped, then the legs flown since, added one by one in route order. A failure that does not
  clip (component already <= residual_m) leaves the float untouched. So two histories that share
  the last effective reset (point and base) of a component compute it by the very same float
  operations and get the very same bits; ``0.0 + leg == leg`` makes the base-0 recipe identical to
  ``evaluate_route``'s. Histories whose last resets differ give different real numbers (legs are
  positive), except for degenerate coincidences that rounding may or may not merge; either way
  the probability is unchanged.

Bound on the number of states (asserted in the tests). Let S_v be the set of vertical values
reachable after a point, ignoring the constraints. A reliable V point maps S_v to {0.0}; an
unreliable one maps it to {0.0} union {min(x, residual_m) : x in S_v + leg}, the image of a
function of S_v plus one element, so |S_v| grows by at most one; H points and legs apply a
function to S_v, which cannot grow it. Hence |S_v| <= k_v + 1, with k_v the unreliable V points
since the last reliable V point, and likewise |S_h| <= k_h + 1. Without constraints the joint
states are a subset of S_v x S_h; dropping violating mass only removes states. So after any point
the chain holds at most (k_v + 1) * (k_h + 1) states. (When the legs between same-kind unreliable
points exceed residual_m, as on the contest data, the clip merges everything and |S_v| <= 2.)
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.route import Leg, straight_legs
from gcs_planner.dryrun.confidence import wilson_interval
from gcs_planner.scenario.model import Kind, Parameters, Scenario

State = tuple[float, float]

# Probabilities reached along different routes are products taken in different orders: equal
# values may differ in the last bits, and must still compare equal. The one tolerance every
# comparison of probabilities uses (the search, its proofs, its compiled probes, the choice).
PROB_EPS = 1e-12

BRUTE_FORCE_MAX_UNRELIABLE = 20


@dataclass(frozen=True)
class SuccessProbability:
    """Exact success probability of one route."""

    probability: float  # P(arrive at B within theta with every constraint met)
    # Per route point (A first, 1.0): P(arriving there within its limits, all earlier met).
    per_stop: tuple[float, ...]
    states: int  # largest number of distinct merged states held after any point


@dataclass(frozen=True)
class MonteCarloResult:
    """A seeded replay: successes out of runs and a Wilson score interval for the rate."""

    runs: int
    successes: int
    rate: float
    ci_low: float
    ci_high: float
    confidence: float


def outcomes(v: float, h: float, kind: Kind, residual_m: float) -> tuple[State, State]:
    """The errors (v, h) after a correction at a point of ``kind`` that succeeds and that fails
    (the corrected component reset to 0, or clipped to the residual); B and A correct nothing."""
    if kind == Kind.V:
        return (0.0, h), (min(v, residual_m), h)
    if kind == Kind.H:
        return (v, 0.0), (v, min(h, residual_m))
    return (v, h), (v, h)


def propagate(
    states: dict[State, float],
    leg: float,
    kind: Kind,
    unreliable: bool,
    params: Parameters,
) -> tuple[dict[State, float], float]:
    """One step of the chain: fly ``leg`` metres to a point of ``kind`` and correct there.

    ``states`` maps (v, h), in metres flown since the last effective reset, to probability mass,
    after the previous point's correction. Mass arriving beyond the point's limits is dropped;
    the rest is corrected (a success resets the component to 0, a failure at an unreliable point
    clips it to r / delta; B corrects nothing). Returns the new states and the mass that arrived
    within limits.
    """
    v_lim, h_lim = params.limits_m(kind)
    fails = bool(unreliable) and kind in (Kind.V, Kind.H)
    p = params.p_success if fails else 1.0
    q = 1.0 - p
    residual_m = params.residual_m
    out: dict[State, float] = {}
    arrived = 0.0
    for (v0, h0), mass in states.items():
        v = v0 + leg
        h = h0 + leg
        if not (v <= v_lim and h <= h_lim):
            continue
        arrived += mass
        succeeded, failed = outcomes(v, h, kind, residual_m)
        # Zero-mass branches (p = 0 or 1) are skipped so they cannot inflate the state count.
        if p > 0.0:
            out[succeeded] = out.get(succeeded, 0.0) + mass * p
        if q > 0.0:
            out[failed] = out.get(failed, 0.0) + mass * q
    return out, arrived


def _leg_lengths(
    scenario: Scenario, points: Sequence[int], leg_lengths: Sequence[float | Leg] | None
) -> list[float]:
    if leg_lengths is None:
        leg_lengths = straight_legs(scenario, points)
    if len(leg_lengths) != len(points) - 1:
        raise ValueError("one leg length per consecutive pair of points")
    return [float(leg.length if isinstance(leg, Leg) else leg) for leg in leg_lengths]


def _check_route(scenario: Scenario, points: Sequence[int]) -> list[int]:
    points = [int(i) for i in points]
    if len(points) < 2:
        raise ValueError("a route has at least A and B")
    if scenario.kind[points[0]] != Kind.A or scenario.kind[points[-1]] != Kind.B:
        raise ValueError("a route starts at A and ends at B")
    return points


def success_probability(
    scenario: Scenario,
    points: Sequence[int],
    leg_lengths: Sequence[float | Leg] | None = None,
) -> SuccessProbability:
    """Exact probability that the route ``points`` (indices, A to B) meets every constraint.

    ``leg_lengths`` are the flown lengths of the legs (floats or :class:`Leg`); straight legs by
    default.
    """
    points = _check_route(scenario, points)
    legs = _leg_lengths(scenario, points, leg_lengths)
    params = scenario.params
    states: dict[State, float] = {scenario.initial_errors: 1.0}
    per_stop = [1.0]
    largest = 1
    for j, leg in zip(points[1:], legs, strict=True):
        states, arrived = propagate(
            states, leg, Kind(int(scenario.kind[j])), bool(scenario.unreliable[j]), params
        )
        # Sums of p*m and (1-p)*m can exceed the true mass by an ulp; a probability above 1
        # would only be rounding, so it is capped.
        per_stop.append(min(1.0, arrived))
        largest = max(largest, len(states))
    return SuccessProbability(per_stop[-1], tuple(per_stop), largest)


def monte_carlo_success(
    scenario: Scenario,
    points: Sequence[int],
    leg_lengths: Sequence[float | Leg] | None = None,
    runs: int = 10000,
    seed: int = 0,
    confidence: float = 0.99,
) -> MonteCarloResult:
    """Replay the route ``runs`` times, drawing each unreliable correction's outcome.

    All runs advance together as numpy arrays, one route point at a time. The interval is the
    Wilson score interval at ``confidence``.
    """
    if runs < 1:
        raise ValueError("runs must be >= 1")
    if not 0.0 < confidence < 1.0:
        raise ValueError("confidence must lie in (0, 1)")
    points = _check_route(scenario, points)
    legs = _leg_lengths(scenario, points, leg_lengths)
    params = scenario.params
    residual_m = params.residual_m
    rng = np.random.default_rng(seed)
    v = np.full(runs, scenario.initial_errors[0])
    h = np.full(runs, scenario.initial_errors[1])
    ok = np.ones(runs, dtype=bool)
    for j, leg in zip(points[1:], legs, strict=True):
        kind = Kind(int(scenario.kind[j]))
        v += leg
        h += leg
        v_lim, h_lim = params.limits_m(kind)
        ok &= (v <= v_lim) & (h <= h_lim)
        if kind not in (Kind.V, Kind.H):
            continue
        if scenario.unreliable[j]:
            succeeded = rng.random(runs) < params.p_success
        else:
            succeeded = np.ones(runs, dtype=bool)
        if kind == Kind.V:
            v = np.where(succeeded, 0.0, np.minimum(v, residual_m))
        else:
            h = np.where(succeeded, 0.0, np.minimum(h, residual_m))
    successes = int(np.count_nonzero(ok))
    low, high = wilson_interval(successes, runs, confidence)
    return MonteCarloResult(runs, successes, successes / runs, low, high, confidence)


def brute_force_success(
    scenario: Scenario,
    points: Sequence[int],
    leg_lengths: Sequence[float | Leg] | None = None,
) -> float:
    """Reference for tests: sum over all 2^k outcome vectors of the k unreliable points.

    Each outcome vector is flown deterministically; no states are merged. Refuses k > 20.
    """
    points = _check_route(scenario, points)
    legs = _leg_lengths(scenario, points, leg_lengths)
    params = scenario.params
    residual_m = params.residual_m
    kinds = [Kind(int(scenario.kind[j])) for j in points]
    risky = [
        i for i, j in enumerate(points) if scenario.unreliable[j] and kinds[i] in (Kind.V, Kind.H)
    ]
    if len(risky) > BRUTE_FORCE_MAX_UNRELIABLE:
        raise ValueError(
            f"{len(risky)} unreliable points: brute force stops at {BRUTE_FORCE_MAX_UNRELIABLE}"
        )
    p = params.p_success
    total = 0.0
    for outcome in itertools.product((True, False), repeat=len(risky)):
        failed_at = {i for i, ok in zip(risky, outcome, strict=True) if not ok}
        weight = 1.0
        for ok in outcome:
            weight *= p if ok else 1.0 - p
        v, h = scenario.initial_errors
        feasible = True
        for i, leg in enumerate(legs, start=1):
            v += leg
            h += leg
            v_lim, h_lim = params.limits_m(kinds[i])
            if not (v <= v_lim and h <= h_lim):
                feasible = False
                break
            if kinds[i] == Kind.V:
                v = min(v, residual_m) if i in failed_at else 0.0
            elif kinds[i] == Kind.H:
                h = min(h, residual_m) if i in failed_at else 0.0
        if feasible:
            total += weight
    return total
