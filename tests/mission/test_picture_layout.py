"""Pictures as a user reads them: no label over another, integer ticks on a count axis, map views
cropped to what they show, and no 3D view where thousands of points would hide the route.

Measured on the drawn figures (``*_figure``), after the labels are placed, with the renderer's
own text extents."""

from __future__ import annotations

import io
import itertools
from collections.abc import Iterator

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.text import Text
from support.missions import ORIGIN, make_plan

from gcs_planner.core.planner import plan as plan_scenario
from gcs_planner.mission import plan_json
from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.pictures import (
    DPI,
    THREE_D_MAX_POINTS,
    error_budget_figure,
    front_figure,
    route_figure,
)
from gcs_planner.mission.policy_build import MissionPath, PathSwitch
from gcs_planner.mission.policy_pictures import policy_front_figure, tree_figure
from gcs_planner.scenario.generate import DATASET1, random_scenario
from gcs_planner.scenario.model import Kind, Scenario
from gcs_planner.scenario.readers import load_scenario

DS2 = {"alpha1": 20, "alpha2": 10, "beta1": 15, "beta2": 20, "theta": 20, "delta": 0.001}


@pytest.fixture(scope="module")
def dataset2_plan(dataset_paths) -> dict:
    """Dataset 2 (327 points) planned as the users who reported overprinted labels did."""
    scenario = load_scenario(dataset_paths[2], {**DS2, "turn_radius": 0.0})
    return plan_json.plan_to_dict(plan_scenario(scenario))


@pytest.fixture(scope="module")
def dataset2_figures(dataset2_plan) -> Iterator[dict]:
    """Dataset 2's route and error budget figures, drawn once for the module (rendered once on
    their canvas, so that their layout is done): the tests below measure several properties of
    the same drawing (none of them draws on it; saving it moves nothing, which
    test_route_labels_are_drawn_at_the_saved_positions holds)."""
    figures = {draw: draw(dataset2_plan) for draw in (route_figure, error_budget_figure)}
    for fig in figures.values():
        fig.canvas.draw()
    yield figures
    for fig in figures.values():
        plt.close(fig)


@pytest.fixture(scope="module")
def dataset2_label_boxes(dataset2_figures) -> dict:
    """The label boxes of dataset 2's figures as rendered by ``dataset2_figures``."""
    return {draw: label_boxes(fig, render=False) for draw, fig in dataset2_figures.items()}


def crowded_scenario(n_route: int = 40, n_other: int = 200, seed: int = 3) -> Scenario:
    """A route of ``n_route`` points packed along a 20 km line (about 500 m apart, closer than
    their labels are wide at the picture's scale) in a 100 km box of other points, some
    unreliable: labels placed naively overprint each other here."""
    rng = np.random.default_rng(seed)
    line = np.column_stack(
        [
            np.linspace(40_000, 60_000, n_route),
            50_000 + rng.normal(0, 300, n_route),
            rng.uniform(1_000, 3_000, n_route),
        ]
    )
    other = rng.uniform([0, 0, 0], [100_000, 100_000, 5_000], size=(n_other, 3))
    xyz = np.vstack([[0, 50_000, 2_000], line, other, [100_000, 50_000, 2_000]])
    n = len(xyz)
    kinds = [Kind.A] + [Kind.V if i % 2 else Kind.H for i in range(n - 2)] + [Kind.B]
    unreliable = np.zeros(n, dtype=bool)
    unreliable[1 : n_route + 1 : 3] = True
    return Scenario(
        ids=tuple(str(1000 + i) for i in range(n)),
        xyz=xyz,
        kind=np.array(kinds, dtype=np.uint8),
        unreliable=unreliable,
        params=DATASET1.__class__(**{**DATASET1.to_dict(), "turn_radius": 0.0}),
        name="crowded",
        source="hand-made",
        origin=ORIGIN,
    )


def crowded_plan() -> dict:
    s = crowded_scenario()
    route = [0, *range(1, 41), s.n - 1]
    return make_plan(s, (route, route[::2] + [s.n - 1]))


def label_boxes(fig, render: bool = True) -> list:
    """Window extents of every text drawn on the figure's axes (ids, margins, names ...): the
    text's own box (an annotation's extent would also cover its leader line). ``render`` False:
    the figure was rendered already (a module's figure, unchanged since)."""
    if render:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    return [
        Text.get_window_extent(t, renderer)
        for ax in fig.axes
        for t in ax.texts
        if t.get_visible() and t.get_text().strip()
    ]


def assert_no_overprint(fig, boxes: list | None = None) -> int:
    """No two label boxes overlap (``boxes``: the figure's, measured already); their number."""
    boxes = label_boxes(fig) if boxes is None else boxes
    for a, b in itertools.combinations(boxes, 2):
        inter_w = min(a.x1, b.x1) - max(a.x0, b.x0)
        inter_h = min(a.y1, b.y1) - max(a.y0, b.y0)
        assert inter_w <= 0.5 or inter_h <= 0.5, f"labels overprint: {a} and {b}"
    return len(boxes)


def axes_titled(fig, start: str):
    (ax,) = [ax for ax in fig.axes if ax.get_title().startswith(start)]
    return ax


@pytest.fixture(autouse=True)
def close_figures():
    before = set(plt.get_fignums())
    yield
    for num in set(plt.get_fignums()) - before:
        plt.close(num)


# --- no label over another -----------------------------------------------------------------


@pytest.mark.parametrize("draw", [route_figure, error_budget_figure, front_figure])
def test_no_label_overprints_another_on_dataset2(
    dataset2_plan, dataset2_figures, dataset2_label_boxes, draw
):
    fig = dataset2_figures[draw] if draw in dataset2_figures else draw(dataset2_plan)
    n = assert_no_overprint(fig, dataset2_label_boxes.get(draw))
    route = dataset2_plan["front"][dataset2_plan["chosen"]]["route"]
    if draw is not front_figure:  # every id of the route is shown in these views
        assert n >= len(route)


@pytest.mark.parametrize("draw", [route_figure, error_budget_figure])
def test_no_label_overprints_another_on_a_crowded_route(draw):
    plan = crowded_plan()
    fig = draw(plan)
    n = assert_no_overprint(fig)
    # The labels that found no room are few and said in the titles, not drawn over others.
    titles = " ".join(ax.get_title() for ax in fig.axes)
    shown = sum(t.get_text() in plan["front"][0]["route"] for ax in fig.axes for t in ax.texts)
    assert shown >= 40 and n >= 40
    if "left out" in titles:
        assert "no room" in titles


def test_labels_stay_inside_their_axes(dataset2_figures):
    fig = dataset2_figures[route_figure]  # rendered by the fixture
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        frame = ax.get_window_extent(renderer)
        for t in ax.texts:
            box = Text.get_window_extent(t, renderer)
            assert frame.x0 <= box.x0 and box.x1 <= frame.x1
            assert frame.y0 <= box.y0 and box.y1 <= frame.y1


def test_route_labels_are_drawn_at_the_saved_positions(dataset2_figures, dataset2_label_boxes):
    """The layout is fixed before the labels are placed: saving moves nothing."""
    fig = dataset2_figures[route_figure]
    before = dataset2_label_boxes[route_figure]
    fig.savefig(io.BytesIO(), format="png", dpi=DPI)
    after = label_boxes(fig)
    assert np.allclose([b.bounds for b in before], [b.bounds for b in after])


# --- integer ticks on the count axis -------------------------------------------------------


@pytest.mark.parametrize("counts", [[5, 5, 5], [12, 13, 21], [7], [3, 4]])
def test_front_count_axis_has_integer_ticks(counts):
    plan = make_plan(routes=tuple([[0, 6]] * len(counts)), probability=True)
    for entry, c in zip(plan["front"], counts, strict=True):
        entry["corrections"] = c
    fig = front_figure(plan)
    fig.canvas.draw()
    ax = fig.axes[0]
    lo, hi = ax.get_xlim()
    ticks = [t for t in ax.get_xticks() if lo <= t <= hi]
    assert len(ticks) >= 2
    assert all(float(t).is_integer() for t in ticks)
    labels = [t.get_text().replace("\u2212", "-") for t in ax.get_xticklabels() if t.get_text()]
    assert labels and all(s.lstrip("-").isdigit() for s in labels)
    assert lo <= min(counts) and max(counts) <= hi


# --- map views cropped to their data -------------------------------------------------------


def assert_cropped(ax, xs, ys, margin: float = 0.1):
    """The axes' limits hold the data and exceed it by at most ``margin`` of its larger span
    (and by no more than the widening that keeps a flat map readable)."""
    span = max(np.ptp(xs), np.ptp(ys))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= xs.min() and xs.max() <= x1 and y0 <= ys.min() and ys.max() <= y1
    assert xs.min() - x0 <= margin * span and x1 - xs.max() <= margin * span
    assert ys.min() - y0 <= margin * span and y1 - ys.max() <= margin * span


def test_route_plan_view_is_cropped_to_the_points_with_equal_scales(
    dataset2_plan, dataset2_figures
):
    fig = dataset2_figures[route_figure]
    ax = axes_titled(fig, "plan view")
    xyz = np.array([[p["x"], p["y"]] for p in dataset2_plan["points"]]) / 1000
    track = trajectory_local(dataset2_plan) / 1000
    assert_cropped(ax, np.r_[xyz[:, 0], track[:, 0]], np.r_[xyz[:, 1], track[:, 1]], 0.06)
    assert ax.get_aspect() == 1.0
    # Drawn square (as rendered by the fixture): equal scales on a square scenario.
    box = ax.get_window_extent()
    assert box.width == pytest.approx(box.height, rel=0.02)


def test_error_budget_plan_view_is_cropped_to_the_route(dataset2_plan, dataset2_figures):
    fig = dataset2_figures[error_budget_figure]
    ax = axes_titled(fig, "plan view")
    track = trajectory_local(dataset2_plan) / 1000
    assert_cropped(ax, track[:, 0], track[:, 1], 0.06)
    assert ax.get_aspect() == 1.0
    # Not the whole scenario: the route of dataset 2 stays within y 20..80 km.
    assert ax.get_ylim()[0] > 10 and ax.get_ylim()[1] < 90


def test_flat_map_is_stretched_and_says_so():
    """A 300 × 2 km route drawn at equal scales would be a line: north is stretched (at most
    MAX_STRETCH), the title says by how much, and the limits still hold the route."""
    s = random_scenario(60, 1, box=(300_000.0, 2_000.0, 500.0))
    s = s.with_params(turn_radius=0.0)
    order = [0, *sorted(range(1, s.n - 1), key=lambda i: s.xyz[i, 0])[::6], s.n - 1]
    plan = make_plan(s, (order,))
    fig = error_budget_figure(plan)
    ax = axes_titled(fig, "plan view")
    assert "north stretched" in ax.get_title()
    assert 1.5 <= ax.get_aspect() <= 3.0
    track = trajectory_local(plan) / 1000
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= track[:, 0].min() and track[:, 0].max() <= x1
    assert y0 <= track[:, 1].min() and track[:, 1].max() <= y1
    assert (x1 - x0) <= 1.1 * np.ptp(track[:, 0])
    assert_no_overprint(fig)


# --- no 3D view where it cannot be read ----------------------------------------------------


def test_3d_view_only_for_small_scenarios(dataset2_figures):
    assert any(ax.name == "3d" for ax in route_figure(make_plan()).axes)
    assert any(ax.name == "3d" for ax in dataset2_figures[route_figure].axes)

    # One point over the limit (its correction points, A and B): the smallest cloud without
    # a 3D view, which a limit off by one would still draw in 3D.
    s = random_scenario(THREE_D_MAX_POINTS - 1, 1, params=DATASET1).with_params(turn_radius=0.0)
    assert s.n == THREE_D_MAX_POINTS + 1
    route = [0, *sorted(range(1, s.n - 1), key=lambda i: s.xyz[i, 0])[:: s.n // 10], s.n - 1]
    plan = make_plan(s, (route,))
    fig = route_figure(plan)
    assert all(ax.name != "3d" for ax in fig.axes)
    # Its place is taken by the 2D views: a plan view and a side view, both labelled.
    axes_titled(fig, "plan view")
    axes_titled(fig, "side view")
    assert_no_overprint(fig)
    shown = {t.get_text() for ax in fig.axes for t in ax.texts}
    assert {plan["front"][0]["route"][0], plan["front"][0]["route"][-1]} <= shown


# --- the policy pictures -------------------------------------------------------------------


def test_policy_tree_labels_do_not_overprint_and_the_map_is_cropped():
    """Six failed fixes a few hundred metres apart, each switching to a branch: their long
    labels and the ids of the points all find room, none over another."""
    s = crowded_scenario()
    primary = [0, *range(1, 41), s.n - 1]
    plan = make_plan(s, (primary,))
    missions = [(MissionPath("primary", tuple(primary)), plan)]
    switches = []
    for k, failed in enumerate((4, 7, 10, 13, 16, 19)):
        detour = 41 + k  # a point off the line, then back to the route's end
        points = tuple(primary[: failed + 1] + [detour] + primary[failed + 2 :])
        name = f"branch-{failed}"
        missions.append((MissionPath(name, points, "primary", failed), make_plan(s, (points,))))
        switches.append(PathSwitch("primary", failed, name))
    fig = tree_figure(plan, missions, switches, "crowded: policy")
    n = assert_no_overprint(fig)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert sum("fails" in t for t in texts) == len(switches)  # every switch is said
    assert n >= 30
    ax = fig.axes[0]
    xy = s.xyz[:, :2] / 1000
    assert_cropped(ax, xy[:, 0], xy[:, 1], 0.06)
    assert ax.get_aspect() == 1.0


def test_policy_front_names_do_not_overprint():
    rows = [(k, 100_000 + 50 * k, 0.5 + 0.001 * k, 120_000 + 50 * k, 0.6) for k in range(8)]
    fig = policy_front_figure(rows, 3, "policy front")
    assert assert_no_overprint(fig) >= 6
