"""Branch and bound over simple routes, for what the layered search cannot carry in a label:
the heading (turns: the flown length of a leg depends on the whole route before it) and the
distribution of error states (uncertain corrections).

Labels are whole partial routes (point, heading, flown length, corrections, error-state
distribution, path), explored best-first by f = L + G_j(e), G the admissible cost-to-go of
``cost_to_go``. A label is pruned when a route already found is at least as good on every
objective it can still reach: length <= f, corrections <= k, probability >= the mass still
alive. When the queue empties, the routes found are exactly the Pareto front under the model —
the proof is the exhausted search. If a label budget stops it earlier, every front point gets
the lower bound that the open labels still allow, and the gap is reported, never hidden.

With turns, partial routes of different headings are incomparable, and the search over whole
simple routes grows too fast where the front spans long routes (dataset 2, three objectives).
So each partial route the search pops is first *probed* (``_Prober``): the exact completions of
it in the relaxation that proved the floor (legs bounded over the cone of headings the route
can arrive with, where partial routes do compare by dominance) are searched, and if every one is
dominated by a route already found, so is every flown completion, and the partial route is
dropped. The states such a probe expanded are covered too and prune later probes (nogoods).

The parts: ``front`` (``bnb_front``: the floors, the guide, the search over simple routes),
``search`` (one best-first search, in Python or compiled), ``best_first`` (the Python search's
steps), ``ending`` (what a search says when it ends), ``probes``, ``open_routes`` (the partial
routes on a search's heap, and what the search asks a prober), ``context`` (what the rounds
share, and the ``Options`` they run with), ``incumbents`` (the routes found, ``Ceiling``),
``dominance`` (between partial routes at a point) and ``flown`` (routes flown again under the
leg model, independently of the search).
"""

from gcs_planner.core.bnb.context import Options
from gcs_planner.core.bnb.flown import flown_leg, flown_route, flown_route_legs
from gcs_planner.core.bnb.front import bnb_front
from gcs_planner.core.bnb.incumbents import BnbResult, Ceiling, Found
from gcs_planner.core.budget import DEFAULT_MAX_LABELS
from gcs_planner.core.proof import PROB_EPS

__all__ = [
    "DEFAULT_MAX_LABELS",
    "PROB_EPS",
    "BnbResult",
    "Ceiling",
    "Found",
    "Options",
    "bnb_front",
    "flown_leg",
    "flown_route",
    "flown_route_legs",
]
