"""Pictures of a plan, PNG, headless (matplotlib's Agg backend).

* ``route_png``: the route over all correction points (V and H in two colours, unreliable points
  ringed, A and B marked, the flown trajectory with its turns): the plan view (XOY) and the side
  view (altitude against distance flown), with a 3D view as in the paper's Figure 8 only where it
  can be read (at most ``THREE_D_MAX_POINTS`` points; a cloud of thousands of points hides the
  route in 3D).
* ``front_png``: the Pareto front, length against corrections, the chosen route highlighted and
  the success probability as colour when the plan has it; it reads with one route and with fifty.
* ``error_budget_png``: what an operator checks before flying: the vertical and horizontal error
  against distance flown (the sawtooth of corrections), each point's limits and the margin left
  at it, beside the plan view and the side view (altitude against distance flown).

Route points carry their ids, as the scenario file names them. Labels are placed after the
figure's layout is fixed (``LabelPlacer``): each goes to the first free spot around its point, so
that no label overprints another; a label with no free spot is left out and the view's title says
how many were. Map views are cropped to what they show, with equal scales on both axes unless the
data is so elongated that one axis must be stretched (the title then says by how much).

The ``*_png`` functions return PNG bytes (writing them, atomically, is the caller's business);
the ``*_figure`` functions return the drawn figure, labels placed, for tests to measure.

Each picture is drawn in its own module (``route_picture``, ``front_picture``,
``error_budget_picture``) from the views they share (``map_view``, ``profile_view``), the label
placing (``picture_labels``) and what every picture shares (``picture_axes``); this module names
them all in one place.
"""

from __future__ import annotations

from gcs_planner.mission.error_budget_picture import (
    error_budget_figure,
    error_budget_png,
    sawtooth,
)
from gcs_planner.mission.front_picture import front_figure, front_png
from gcs_planner.mission.map_view import MapView
from gcs_planner.mission.picture_axes import COLOURS, DPI, KM, LIMIT, MARGIN, UNRELIABLE
from gcs_planner.mission.picture_labels import Label, LabelPlacer
from gcs_planner.mission.profile_view import side_profile
from gcs_planner.mission.route_picture import (
    DENSE_POINTS,
    THREE_D_MAX_POINTS,
    route_figure,
    route_png,
)

__all__ = [
    "COLOURS", "DENSE_POINTS", "DPI", "KM", "LIMIT", "MARGIN", "THREE_D_MAX_POINTS",
    "UNRELIABLE", "Label", "LabelPlacer", "MapView", "error_budget_figure", "error_budget_png",
    "front_figure", "front_png", "route_figure", "route_png", "sawtooth", "side_profile",
]  # fmt: skip
