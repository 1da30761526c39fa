"""Choosing one route from a Pareto front (docs/model.md, "Objectives"; the paper's Section 4),
and what the planner does when the user does not say: which objectives to search, and which route
of the front to choose.

An operator trusts a planner whose default route is likely to arrive. So the choice is made among
the front routes at least :data:`DEFAULT_MIN_PROBABILITY` likely to arrive; when none is, the most
reliable route is chosen and the plan says so (``threshold_met`` false), and the exporters refuse
to write it unless asked (:func:`check_exportable`). The command line and the library both call
this module, so they cannot disagree.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from gcs_planner.core.probability import PROB_EPS
from gcs_planner.errors import GcsPlannerError

if TYPE_CHECKING:
    from gcs_planner.core.route import Route
    from gcs_planner.scenario.model import Scenario

# name -> (objective column, +1 minimise / -1 maximise)
CHOICES = ("compromise", "shortest", "fewest", "most-reliable")


def satisfaction(values: np.ndarray, maximise: Sequence[bool]) -> np.ndarray:
    """Fuzzy satisfaction γ(k) of each front member (rows) over the objectives (columns).

    γ(c,k) is 1 at the objective's best value on the front, 0 at its worst, linear between, and
    1 when best = worst; γ(k) = Σc γ(c,k) / Σk Σc γ(c,k).
    """
    values = np.asarray(values, dtype=float)
    gamma = np.ones_like(values)
    for c, is_max in enumerate(maximise):
        col = values[:, c]
        lo, hi = col.min(), col.max()
        if hi > lo:
            gamma[:, c] = (col - lo) / (hi - lo) if is_max else (hi - col) / (hi - lo)
    per_route = gamma.sum(axis=1)
    total = per_route.sum()
    return per_route / total if total > 0 else np.full(len(values), 1.0 / len(values))


def choose(
    lengths: Sequence[float],
    corrections: Sequence[int],
    probabilities: Sequence[float] | None,
    how: str = "compromise",
    weights: Sequence[float] | None = None,
) -> int:
    """Index of the chosen route. Ties go to the shorter route, then fewer corrections."""
    if not len(lengths):
        raise ValueError("empty front")
    cols = [np.asarray(lengths, float), np.asarray(corrections, float)]
    maximise = [False, False]
    if probabilities is not None:
        cols.append(np.asarray(probabilities, float))
        maximise.append(True)
    values = np.column_stack(cols)
    tiebreak = np.lexsort((values[:, 1], values[:, 0]))  # shortest, then fewest
    rank = np.empty(len(tiebreak), dtype=int)
    rank[tiebreak] = np.arange(len(tiebreak))
    if how == "shortest":
        key = values[:, 0]
    elif how == "fewest":
        key = values[:, 1] * 1e12 + values[:, 0]
    elif how == "most-reliable":
        if probabilities is None:
            raise ValueError("most-reliable needs the probability objective")
        # Equal probabilities reached by products in different orders differ in the last bits.
        key = -np.round(values[:, 2], 12)
    elif how == "compromise":
        if weights is not None:
            gamma = _weighted(values, maximise, weights)
        else:
            gamma = satisfaction(values, maximise)
        key = -gamma
    else:
        raise ValueError(f"unknown choice {how!r}; one of {', '.join(CHOICES)}")
    return int(np.lexsort((rank, key))[0])


def _weighted(values: np.ndarray, maximise: Sequence[bool], weights: Sequence[float]) -> np.ndarray:
    if len(weights) != values.shape[1]:
        raise ValueError(f"{values.shape[1]} weights needed, one per objective")
    w = np.asarray(weights, float)
    if (w < 0).any() or w.sum() <= 0:
        raise ValueError("weights must be >= 0 and not all 0")
    gamma = np.ones_like(values)
    for c, is_max in enumerate(maximise):
        col = values[:, c]
        lo, hi = col.min(), col.max()
        if hi > lo:
            gamma[:, c] = (col - lo) / (hi - lo) if is_max else (hi - col) / (hi - lo)
    return gamma @ w


# Routes less likely than this to arrive are not chosen by default, nor exported unasked.
DEFAULT_MIN_PROBABILITY = 0.99


class RiskyRouteError(GcsPlannerError):
    """A route below the probability the user asked for was to be exported without consent."""

    exit_code = 3


class RiskyRouteWarning(UserWarning):
    """A route less likely to arrive than the safe default was exported, as asked."""


def default_objectives(
    scenario: Scenario,
    objectives: Sequence[str] | None = None,
    choice: str = "compromise",
) -> tuple[str, ...]:
    """The objectives to search: the given ones, else length and corrections, plus probability
    when the scenario has unreliable points (otherwise every route arrives with probability 1)
    or when the most reliable route is asked for (it needs the probability front)."""
    if objectives is None:
        chosen = ("length", "corrections")
        if bool(scenario.unreliable.any()):
            chosen += ("probability",)
    else:
        chosen = tuple(objectives)
    if choice == "most-reliable" and "probability" not in chosen:
        chosen += ("probability",)
    return chosen


def choose_index(
    routes: Sequence[Route],
    *,
    choice: str = "compromise",
    weights: Sequence[float] | None = None,
    min_probability: float = DEFAULT_MIN_PROBABILITY,
    use_probability: bool = True,
) -> tuple[int, bool]:
    """(index of the chosen route, whether it reaches ``min_probability``).

    The route is chosen by ``choice`` among those at least ``min_probability`` likely to arrive;
    when none is, the most reliable route (the shortest, then fewest corrections, of those) is
    the answer and the flag is False. ``use_probability`` says whether probability is one of
    the objectives the compromise weighs.
    """
    if not 0.0 <= min_probability <= 1.0:
        raise ValueError(f"min_probability must be within [0, 1], not {min_probability}")
    if not routes:
        raise ValueError("empty front")
    # The most reliable route is chosen on probability whatever the objectives searched.
    use_probability = use_probability or choice == "most-reliable"
    lengths = [r.length for r in routes]
    corrections = [r.corrections for r in routes]
    probabilities = [r.probability for r in routes]
    eligible = [i for i, p in enumerate(probabilities) if p >= min_probability - PROB_EPS]
    if not eligible:
        return choose(lengths, corrections, probabilities, "most-reliable"), False
    picked = eligible[
        choose(
            [lengths[i] for i in eligible],
            [corrections[i] for i in eligible],
            [probabilities[i] for i in eligible] if use_probability else None,
            choice,
            weights,
        )
    ]
    return picked, True


def risk_warning(probability: float, route_index: int) -> str:
    """The line that goes with every exported route below the default threshold."""
    return (
        f"route {route_index} arrives with probability {probability:.4f} "
        f"(lost with probability {1 - probability:.4f}); it is below the safe default "
        f"{DEFAULT_MIN_PROBABILITY:g}"
    )


def check_exportable(
    probability: float,
    route_index: int,
    min_probability: float,
    allow_risky: bool = False,
) -> str | None:
    """None when the route may be written silently; a warning to print when it may be written
    only with one; :class:`RiskyRouteError` when it is below ``min_probability`` and the user
    did not allow it."""
    if probability < min_probability - PROB_EPS and not allow_risky:
        raise RiskyRouteError(
            f"route {route_index} arrives with probability {probability:.4f} (lost with "
            f"probability {1 - probability:.4f}), below --min-probability {min_probability:g}; "
            "not exported: pass --allow-risky to export it anyway, or lower --min-probability"
        )
    if probability < DEFAULT_MIN_PROBABILITY - PROB_EPS:
        return risk_warning(probability, route_index)
    return None
