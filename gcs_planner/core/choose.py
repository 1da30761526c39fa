"""Choosing one route from a Pareto front (docs/model.md, "Objectives"; the paper's Section 4)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

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
