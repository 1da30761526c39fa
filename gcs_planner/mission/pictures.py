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
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

from gcs_planner.mission.builder import route_entry, route_legs, route_xyz  # noqa: E402
from gcs_planner.mission.geo_exports import trajectory_local  # noqa: E402

LIMIT = "#d62728"
MARGIN = "#2ca02c"
# A 3D view is drawn only up to this many points: beyond, the cloud hides the route.
THREE_D_MAX_POINTS = 1000
# Beyond this many points the points off the route are drawn as a faint background.
DENSE_POINTS = 2000
# A map view is stretched along its short side when it is flatter than this (height / width).
MIN_MAP_ASPECT = 0.18
MAX_STRETCH = 3.0
MIN_STRETCH = 1.5  # below this, the short side is widened with margin rather than stretched

COLOURS = {"V": "#1f77b4", "H": "#ff7f0e", "A": "#2ca02c", "B": "#d62728", "track": "#222222"}
UNRELIABLE = "#d62728"
KM = 1000.0
DPI = 110


def _png(fig: Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    plt.close(fig)
    return buf.getvalue()


# --- label placement ----------------------------------------------------------------------

# Directions tried around a point, preferred first: NE, E, SE, N, S, NW, W, SW.
AROUND = ((1, 1), (1, 0), (1, -1), (0, 1), (0, -1), (-1, 1), (-1, 0), (-1, -1))
# Above first (the margin labels of the error budget), then the sides, then below.
ABOVE = ((0, 1), (1, 1), (-1, 1), (1, 0), (-1, 0), (0, -1), (1, -1), (-1, -1))
# Gaps (points) between a label and its point's marker, nearest first.
GAPS = (2.0, 8.0, 16.0, 28.0, 44.0)
# A label further than this (points) from its point is tied to it by a thin leader line.
LEADER_FROM = 12.0
PAD = 1.5  # pixels kept free around each label


@dataclass
class Label:
    """A text to place near the point ``xy`` (data coordinates of its axes; for a 3D axes, the
    point's 3D coordinates). ``clearance``: the radius (points) of the point's own marker, which
    the label keeps clear of; lower ``priority`` is placed first."""

    text: str
    xy: tuple[float, ...]
    priority: int = 1
    size: float = 8.5
    weight: str = "normal"
    colour: str = "0.2"
    clearance: float = 4.0
    directions: tuple[tuple[int, int], ...] = AROUND
    gaps: tuple[float, ...] = GAPS


def _boxes_hit(box: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Which of ``boxes`` (n, 4: x0, y0, x1, y1) overlap ``box``."""
    if not len(boxes):
        return np.zeros(0, dtype=bool)
    return (
        (boxes[:, 0] < box[2])
        & (boxes[:, 2] > box[0])
        & (boxes[:, 1] < box[3])
        & (boxes[:, 3] > box[1])
    )


def _markers_hit(box: np.ndarray, markers: np.ndarray) -> np.ndarray:
    """Which of ``markers`` (n, 4: centre x, y, radii x, y; ellipses) overlap ``box``."""
    if not len(markers):
        return np.zeros(0, dtype=bool)
    c, r = markers[:, :2], markers[:, 2:]
    near = np.clip(c, box[:2], box[2:])
    return (((near - c) / r) ** 2).sum(axis=1) < 1.0


def _segments_hit(box: np.ndarray, segs: np.ndarray) -> bool:
    """Whether any segment of ``segs`` (n, 4: x0, y0, x1, y1) crosses ``box`` (Liang-Barsky)."""
    if not len(segs):
        return False
    xs, ys = segs[:, [0, 2]], segs[:, [1, 3]]
    near = (
        (xs.max(axis=1) >= box[0])
        & (xs.min(axis=1) <= box[2])
        & (ys.max(axis=1) >= box[1])
        & (ys.min(axis=1) <= box[3])
    )
    s = segs[near]
    if not len(s):
        return False
    dx, dy = s[:, 2] - s[:, 0], s[:, 3] - s[:, 1]
    p = np.stack([-dx, dx, -dy, dy], axis=1)
    q = np.stack([s[:, 0] - box[0], box[2] - s[:, 0], s[:, 1] - box[1], box[3] - s[:, 1]], 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = q / p
    enter = np.maximum(np.where(p < 0, t, -np.inf).max(axis=1), 0.0)
    leave = np.minimum(np.where(p > 0, t, np.inf).min(axis=1), 1.0)
    outside = ((p == 0) & (q < 0)).any(axis=1)
    return bool(np.any((enter <= leave) & ~outside))


class LabelPlacer:
    """Places labels on a figure whose layout is final, so that no two overprint.

    Made after everything else is drawn: it draws the figure (the layout engine places the
    axes), then fixes the layout, so that the pixel positions it computes are the saved ones.
    Each label, in order of priority, goes to the cheapest free spot among ``GAPS`` ×
    directions around its point inside its axes: never over a label already placed (nor an
    artist ``reserve``d), and preferably clear of the markers and lines it is told of.
    """

    def __init__(self, fig: Figure):
        self.fig = fig
        # Twice: the layout engine's first pass measures tick labels that the axes' final
        # limits (fixed aspect) change, and a cropped label would follow.
        fig.canvas.draw()
        fig.canvas.draw()
        fig.set_layout_engine("none")
        self.renderer = fig.canvas.get_renderer()
        self.taken = np.zeros((0, 4))
        self.px = fig.dpi / 72.0

    def reserve(self, artist) -> None:
        """Keep labels off ``artist`` (a text drawn elsewhere, a legend ...)."""
        bb = artist.get_window_extent(self.renderer)
        self._take(np.array([bb.x0, bb.y0, bb.x1, bb.y1]))

    def _take(self, box: np.ndarray) -> None:
        self.taken = np.vstack([self.taken, box + [-PAD, -PAD, PAD, PAD]])

    def _display(self, ax, pts: np.ndarray) -> np.ndarray:
        """Display coordinates of points (n, 2), or (n, 3) on a 3D axes."""
        pts = np.asarray(pts, dtype=float).reshape(len(pts), -1)
        if pts.shape[1] == 3:
            pts = np.column_stack(_project(ax, pts))
        return ax.transData.transform(pts)

    def place(
        self,
        ax,
        labels: list[Label],
        markers: list[tuple[np.ndarray, float | tuple[float, float]]] = (),
        lines: list[np.ndarray] = (),
    ) -> int:
        """Place ``labels`` on ``ax``; ``markers``: (points (n, 2|3) in data coordinates, radius
        in points, or (half width, half height) for a bar) the labels keep clear of; ``lines``:
        polylines (n, 2|3) they prefer not to cross. Returns how many labels found no free spot
        and were left out."""
        axbox = ax.get_window_extent(self.renderer)
        inside = np.array([axbox.x0 + 1, axbox.y0 + 1, axbox.x1 - 1, axbox.y1 - 1])
        blocks = [np.zeros((0, 4))]
        for pts, radius in markers:
            if len(pts):
                c = self._display(ax, pts)
                r = np.broadcast_to(np.asarray(radius, dtype=float) * self.px, c.shape)
                blocks.append(np.column_stack([c, r]))
        blocks = np.vstack(blocks)
        segs = []
        for line in lines:
            if len(line) > 1:
                d = self._display(ax, line)
                segs.append(np.column_stack([d[:-1], d[1:]]))
        segments = np.vstack(segs) if segs else np.zeros((0, 4))
        leaders: list[np.ndarray] = []
        dropped = 0
        order = sorted(range(len(labels)), key=lambda n: labels[n].priority)
        for n in order:
            lab = labels[n]
            anchor = self._display(ax, [lab.xy])[0]
            xy = lab.xy
            if len(xy) == 3:
                xy = tuple(float(c[0]) for c in _project(ax, np.array([xy])))
            probe = self.fig.text(0, 0, lab.text, fontsize=lab.size, fontweight=lab.weight)
            bb = probe.get_window_extent(self.renderer)
            probe.remove()
            w, h = bb.width, bb.height
            best = None
            for g, gap in enumerate(lab.gaps):
                reach = (lab.clearance + gap) * self.px
                for d, (dx, dy) in enumerate(lab.directions):
                    diag = 0.75 if dx and dy else 1.0
                    x0 = anchor[0] + (
                        reach * diag if dx > 0 else -reach * diag - w if dx else -w / 2
                    )
                    y0 = anchor[1] + (
                        reach * diag if dy > 0 else -reach * diag - h if dy else -h / 2
                    )
                    box = np.array([x0, y0, x0 + w, y0 + h])
                    if (box[:2] < inside[:2]).any() or (box[2:] > inside[2:]).any():
                        continue
                    if _boxes_hit(box, self.taken).any():
                        continue
                    cost = 1.5 * g + 0.1 * d
                    cost += 4.0 * np.count_nonzero(_markers_hit(box, blocks))
                    cost += 2.0 * _segments_hit(box, segments)
                    cost += 2.0 * any(_segments_hit(box, s) for s in leaders)
                    if gap > LEADER_FROM:  # its leader line, clear of the labels placed
                        leader = np.array([[*anchor, *(box[:2] + box[2:]) / 2]])
                        cost += 3.0 * any(_segments_hit(b, leader) for b in self.taken)
                    if best is None or cost < best[0]:
                        best = (cost, box, gap)
                if best is not None and best[0] < 1.5 * (g + 1):
                    break  # no spot further out can be cheaper
            if best is None:
                dropped += 1
                continue
            _, box, gap = best
            offset = (box[:2] - anchor) / self.px
            arrow = None
            if gap > LEADER_FROM:
                arrow = {
                    "arrowstyle": "-",
                    "lw": 0.6,
                    "color": "0.45",
                    "shrinkA": 0,
                    "shrinkB": lab.clearance,
                }
                leaders.append(np.array([[*anchor, *(box[:2] + box[2:]) / 2]]))
            ann = ax.annotate(
                lab.text,
                xy,
                xytext=tuple(offset),
                textcoords="offset points",
                ha="left",
                va="bottom",
                fontsize=lab.size,
                fontweight=lab.weight,
                color=lab.colour,
                arrowprops=arrow,
                annotation_clip=False,
                zorder=6,
            )
            ann.set_in_layout(False)
            self._take(box)
        return dropped


def _project(ax, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 2D coordinates of 3D points on a drawn 3D axes (what its transData takes)."""
    from mpl_toolkits.mplot3d import proj3d

    x, y, _ = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.M)
    return np.asarray(x, dtype=float), np.asarray(y, dtype=float)


def _left_out(ax, dropped: int, what: str = "label") -> None:
    """Say in the view's title how many labels found no room."""
    if dropped:
        plural = "" if dropped == 1 else "s"
        ax.set_title(f"{ax.get_title()} ({dropped} {what}{plural} left out: no room)")


def _marker_radius(size: float) -> float:
    """Radius (points) of a scatter marker of area ``size`` (points²)."""
    return float(np.sqrt(size)) / 2


# --- map views --------------------------------------------------------------------------


@dataclass
class MapView:
    """Limits of a plan view cropped to its data with a small margin, and the stretch of its
    short side (1: equal scales) that keeps it no flatter than ``MIN_MAP_ASPECT``: at most
    ``MAX_STRETCH``, beyond which the short side is widened with empty margin instead (a
    nearly straight route stretched more would look like a zigzag), and none below
    ``MIN_STRETCH`` (widened too: a stretch by 1.1 would only mislead)."""

    xlim: tuple[float, float]
    ylim: tuple[float, float]
    stretch: float  # > 1: north drawn this much larger than east; < 1: east larger

    @classmethod
    def of(cls, xs, ys, margin: float = 0.04) -> MapView:
        xs, ys = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
        dx, dy = float(np.ptp(xs)), float(np.ptp(ys))
        floor = 1e-3 * max(dx, dy, 1.0)
        dx, dy = max(dx, floor), max(dy, floor)
        stretch = float(np.clip(MIN_MAP_ASPECT * dx / dy, 1.0, MAX_STRETCH))
        if dy > dx / MIN_MAP_ASPECT:
            stretch = 1 / float(np.clip(MIN_MAP_ASPECT * dy / dx, 1.0, MAX_STRETCH))
        if 1 / MIN_STRETCH < stretch < MIN_STRETCH:  # a slight stretch: widen instead
            stretch = 1.0
        # Margins and widening in drawn units (north scaled by the stretch).
        w, h = dx, dy * stretch
        pad_x = pad_y = margin * max(w, h)
        pad_y = max(pad_y, (MIN_MAP_ASPECT * (w + 2 * pad_x) - h) / 2)
        pad_x = max(pad_x, (MIN_MAP_ASPECT * (h + 2 * pad_y) - w) / 2)
        cx, cy = (xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2
        half_x, half_y = dx / 2 + pad_x, (h / 2 + pad_y) / stretch
        return cls((cx - half_x, cx + half_x), (cy - half_y, cy + half_y), stretch)

    @property
    def aspect(self) -> float:
        """Height over width of the view as drawn."""
        return self.stretch * (self.ylim[1] - self.ylim[0]) / (self.xlim[1] - self.xlim[0])

    def apply(self, ax, title: str) -> None:
        ax.set_xlim(*self.xlim)
        ax.set_ylim(*self.ylim)
        ax.set_aspect(self.stretch, adjustable="box")
        if self.stretch > 1.001:
            title += f" (north stretched ×{self.stretch:.1f})"
        elif self.stretch < 0.999:
            title += f" (east stretched ×{1 / self.stretch:.1f})"
        ax.set_title(title)
        ax.set_xlabel("x east (km)")
        ax.set_ylabel("y north (km)")
        ax.grid(True, alpha=0.3)


def _points(plan: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n, 3) positions, kinds and unreliable flags of every point of the plan."""
    pts = plan.get("points") or []
    xyz = np.array([[p["x"], p["y"], p["z"]] for p in pts], dtype=float).reshape(-1, 3)
    kind = np.array([str(p.get("kind", "")) for p in pts])
    unreliable = np.array([bool(p.get("unreliable", False)) for p in pts], dtype=bool)
    return xyz, kind, unreliable


def _scatter(ax, pts: np.ndarray, dims: tuple[int, ...], **kw) -> None:
    """Scatter rows of ``pts`` (or one point) on the axes ``dims``; no depth shading in 3D,
    which would make far points look like a different colour."""
    pts = np.atleast_2d(pts)
    if len(dims) == 3:
        kw["depthshade"] = False
    ax.scatter(*(pts[:, d] for d in dims), **kw)


def _title(plan: dict, k: int, entry: dict) -> str:
    scen = plan.get("scenario") or {}
    name = scen.get("name", "scenario")
    parts = [f"{name}: route {k}", f"{entry.get('length', float('nan')) / KM:.2f} km flown"]
    parts.append(f"{entry.get('corrections', len(entry['route']) - 2)} corrections")
    if "probability" in (plan.get("objectives") or []):
        parts.append(f"P(success) {entry.get('probability', float('nan')):.3f}")
    radius = (plan.get("parameters") or {}).get("turn_radius")
    if radius is not None:
        parts.append(f"turn radius {radius:g} m")
    return ", ".join(parts)


def _flown_distance(track: np.ndarray) -> np.ndarray:
    """Distance flown (same unit as ``track``) at each vertex of the flown polyline."""
    steps = np.linalg.norm(np.diff(track, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def _route_stops(entry: dict) -> tuple[list[str], np.ndarray]:
    """Ids of the route's points and the distance flown (m) at each, A first."""
    ids = [str(pid) for pid in entry["route"]]
    along = [0.0] + [float(leg.get("cumulative", np.nan)) for leg in entry["legs"]]
    return ids, np.asarray(along, dtype=float)


# Marker areas (points²) of the route's points, A and B.
ROUTE_SIZE, A_SIZE, B_SIZE = 70.0, 300.0, 150.0
RING_SIZE = 220.0  # the ring round an unreliable point of the route


def _route_labels(pts: np.ndarray, ids: list[str], sizes=(ROUTE_SIZE, A_SIZE, B_SIZE)):
    """The route points' id labels: A and B first and in bold, then every other point, then
    the rest (so that, short of room, the labels left out are spread along the route)."""
    labels = []
    last = len(ids) - 1
    for n, pid in enumerate(ids):
        end = n in (0, last)
        size = sizes[1] if n == 0 else sizes[2] if n == last else sizes[0]
        labels.append(
            Label(
                pid,
                tuple(pts[n]),
                priority=0 if end else 1 + n % 2,
                size=12 if end else 8.5,
                weight="bold" if end else "normal",
                colour="black" if end else "0.2",
                clearance=_marker_radius(size),
            )
        )
    return labels


def _label_route(
    placer: LabelPlacer,
    ax,
    pts,
    ids,
    lines=(),
    sizes=(ROUTE_SIZE, A_SIZE, B_SIZE),
    ringed: np.ndarray | None = None,
):
    """Label the route's points with their ids, clear of their markers (and of the rings
    round the ``ringed`` ones, unreliable) and of ``lines``."""
    labels = _route_labels(pts, ids, sizes)
    markers = [(pts, _marker_radius(sizes[0])), (pts[:1], _marker_radius(sizes[1]))]
    markers.append((pts[-1:], _marker_radius(sizes[2])))
    if ringed is not None and ringed.any():
        markers.append((pts[ringed], _marker_radius(RING_SIZE)))
        for lab, ring in zip(labels, ringed, strict=True):
            if ring:
                lab.clearance = max(lab.clearance, _marker_radius(RING_SIZE))
    _left_out(ax, placer.place(ax, labels, markers, lines), "id")


def side_profile(plan: dict, route_index: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(distance flown in metres, altitude z in metres) along the route's flown polyline: the
    side view an operator reads climbs, descents and helices from."""
    track = trajectory_local(plan, route_index)
    return _flown_distance(track), track[:, 2]


def sawtooth(entry: dict, component: str, resets: str) -> tuple[np.ndarray, np.ndarray]:
    """(distance flown in metres, error in units) of one error component along a front entry,
    corrections succeeding: it grows along each leg to the arrival error the plan states and
    drops to 0 at each point of kind ``resets`` ("V" for the vertical error, "H" for the
    horizontal one)."""
    legs = entry["legs"]
    along = np.array([0.0] + [float(leg["cumulative"]) for leg in legs])
    arrival = np.array([0.0] + [float(leg[f"{component}_error"]) for leg in legs])
    kinds = np.array(["A"] + [str(leg.get("kind", "")) for leg in legs])
    after = np.where(kinds == resets, 0.0, arrival)
    after[0] = 0.0
    # (s_i, after_i) -> (s_i+1, arrival_i+1), then the drop to after_i+1
    return np.repeat(along, 2)[1:], np.column_stack([arrival, after]).ravel()[1:]


def _side_view(
    ax, track: np.ndarray, stops_along: np.ndarray, route: np.ndarray, ids, kinds, entry: dict
) -> list[Label]:
    """Altitude against distance flown, from the flown polyline: climbs, descents and helices
    appear as flown (a helix keeps the leg's constant path angle, so it is named beside it).
    Returns the view's labels beyond the route's ids (the helices), to place once drawn."""
    along = _flown_distance(track)
    ax.plot(along / KM, track[:, 2], color=COLOURS["track"], lw=1.4)
    labels = []
    for n, leg in enumerate(entry["legs"]):
        turns = int(leg.get("helix_turns", 0) or 0)
        if turns:
            labels.append(
                Label(
                    f"helix: {turns} turn{'s' if turns > 1 else ''}",
                    (
                        (stops_along[n] + stops_along[n + 1]) / 2 / KM,
                        (route[n, 2] + route[n + 1, 2]) / 2,
                    ),
                    priority=1,
                    size=9,
                    weight="bold",
                    colour="#9467bd",
                    clearance=1.0,
                    directions=((1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1)),
                )
            )
    for k in ("V", "H"):
        sel = kinds == k
        ax.scatter(
            stops_along[sel] / KM,
            route[sel, 2],
            s=SIDE_SIZE,
            c=COLOURS[k],
            marker="o" if k == "V" else "^",
            edgecolors="black",
            zorder=3,
        )
    ax.scatter(
        stops_along[0] / KM, route[0, 2], s=SIDE_A, c=COLOURS["A"], marker="*", ec="k", zorder=4
    )
    ax.scatter(
        stops_along[-1] / KM, route[-1, 2], s=SIDE_B, c=COLOURS["B"], marker="s", ec="k", zorder=4
    )
    ax.set_ylabel("altitude z (m)")
    ax.set_title("side view: altitude against distance flown")
    ax.margins(x=0.03, y=0.15)
    ax.grid(True, alpha=0.3)
    return labels


# Marker areas (points²) of the side view's route points, A and B.
SIDE_SIZE, SIDE_A, SIDE_B = 40.0, 200.0, 90.0


def _label_side_view(placer: LabelPlacer, ax, track_m, along, route_m, ids, extra: list[Label]):
    """The side view's labels: the route's ids and the helices, clear of the profile."""
    pts = np.column_stack([along / KM, route_m[:, 2]])
    profile = np.column_stack([_flown_distance(track_m) / KM, track_m[:, 2]])
    labels = _route_labels(pts, ids, (SIDE_SIZE, SIDE_A, SIDE_B)) + extra
    markers = [(pts, _marker_radius(SIDE_SIZE)), (pts[:1], _marker_radius(SIDE_A))]
    markers.append((pts[-1:], _marker_radius(SIDE_B)))
    _left_out(ax, placer.place(ax, labels, markers, [profile]))


FIG_W = 15.0  # inches, the route picture
CHROME = 1.8  # inches of a picture's title and legend
SIDE_H = 3.4  # inches, the side view below the maps


def _route_layout(aspect: float, with3d: bool):
    """Figure and axes of the route picture, sized so that the plan view (``aspect``: its
    height over width as drawn) fills its slot: with a 3D view, the 3D and plan views above the
    side view; without, the plan view above the side view when it is flat, beside it when not."""
    if with3d or aspect < 0.5:
        room = FIG_W - (5.5 if with3d else 0.0) - 1.0
        top = float(np.clip(room * aspect, 4.4 if with3d else 2.0, 5.4))
        plan_w = min(room, top / aspect) + 1.0
        fig = plt.figure(figsize=(FIG_W, top + SIDE_H + CHROME), layout="constrained", dpi=DPI)
        if with3d:
            # A spacer column: the layout engine does not see the 3D view's z label.
            grid = fig.add_gridspec(
                2,
                3,
                width_ratios=[FIG_W - plan_w - 0.4, 0.4, plan_w],
                height_ratios=[top, SIDE_H],
            )
            ax3 = fig.add_subplot(grid[0, 0], projection="3d")
            axy = fig.add_subplot(grid[0, 2])
        else:
            grid = fig.add_gridspec(2, 1, height_ratios=[top + 0.6, SIDE_H])
            ax3, axy = None, fig.add_subplot(grid[0, 0])
        axz = fig.add_subplot(grid[1, :])
        return fig, ax3, axy, axz
    height = 7.6
    plan_w = float(np.clip((height - CHROME - 0.6) / aspect, 4.0, 8.5)) + 1.0
    fig = plt.figure(figsize=(FIG_W, height), layout="constrained", dpi=DPI)
    grid = fig.add_gridspec(1, 2, width_ratios=[plan_w, FIG_W - plan_w])
    return fig, None, fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])


def route_figure(plan: dict, route_index: int | None = None) -> Figure:
    """The route over all correction points: plan view and side view (altitude against distance
    flown), and a 3D view for scenarios of at most ``THREE_D_MAX_POINTS`` points; the route's
    points labelled with their ids, no label over another."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route_m = route_xyz(plan, entry, legs)
    route = route_m / KM
    track_m = trajectory_local(plan, k)
    track = track_m / KM
    xyz, kind, unreliable = _points(plan)
    xyz = xyz / KM
    route_ids, along = _route_stops(entry)
    on_route = set(route_ids)
    ids = [str(p.get("id")) for p in plan.get("points") or []]
    visited = np.array([pid in on_route for pid in ids], dtype=bool)
    route_kinds = _route_kinds(plan, entry)
    with3d = len(xyz) <= THREE_D_MAX_POINTS
    dense = len(xyz) > DENSE_POINTS

    view = MapView.of(np.r_[xyz[:, 0], track[:, 0]], np.r_[xyz[:, 1], track[:, 1]])
    fig, ax3, axy, axz = _route_layout(view.aspect, with3d)

    faint = {"s": 2, "alpha": 0.2, "lw": 0} if dense else {"s": 9, "alpha": 0.35}
    layers = [  # (selection, scatter style), drawn in this order
        ((kind == "V") & ~visited, {"c": COLOURS["V"], "marker": "o", **faint}),
        ((kind == "H") & ~visited, {"c": COLOURS["H"], "marker": "^", **faint}),
        ((kind == "V") & visited, {"s": ROUTE_SIZE, "c": COLOURS["V"], "marker": "o", "ec": "k"}),
        ((kind == "H") & visited, {"s": ROUTE_SIZE, "c": COLOURS["H"], "marker": "^", "ec": "k"}),
        (unreliable & visited, {"s": RING_SIZE, "fc": "none", "ec": UNRELIABLE, "lw": 1.6}),
    ]
    if not dense:  # thousands of crosses would hide the route
        off = {"s": 14, "c": UNRELIABLE, "marker": "x", "lw": 0.6, "alpha": 0.6}
        layers.insert(2, (unreliable & ~visited, off))
    for ax, dims in ((ax3, (0, 1, 2)), (axy, (0, 1))):
        if ax is None:
            continue
        for sel, style in layers:
            if sel.any():
                _scatter(ax, xyz[sel], dims, **style)
        ax.plot(*(track[:, d] for d in dims), color=COLOURS["track"], lw=1.6, zorder=3)
        _scatter(ax, route[0], dims, s=A_SIZE, c=COLOURS["A"], marker="*", ec="k", zorder=5)
        _scatter(ax, route[-1], dims, s=B_SIZE, c=COLOURS["B"], marker="s", ec="k", zorder=5)
    helices = _side_view(axz, track_m, along, route_m, route_ids, route_kinds, entry)
    axz.set_xlabel("distance flown (km)")
    view.apply(axy, "plan view")
    if ax3 is not None:
        ax3.set_xlabel("x east (km)")
        ax3.set_ylabel("y north (km)")
        ax3.set_zlabel("z up (km)")
        ax3.set_title("3D view")
        ax3.view_init(elev=24, azim=-60)
        ax3.set_box_aspect((5, 4, 3))  # wider than deep: its slot is wide

    fig.legend(
        handles=_legend(dense), loc="outside lower center", ncol=4, fontsize=10, frameon=False
    )
    fig.suptitle(_title(plan, k, entry), fontsize=14)
    placer = LabelPlacer(fig)
    ringed = np.array([False] + [bool(leg.get("unreliable", False)) for leg in entry["legs"]])
    _label_route(placer, axy, route[:, :2], route_ids, [track[:, :2]], ringed=ringed)
    _label_side_view(placer, axz, track_m, along, route_m, route_ids, helices)
    if ax3 is not None:
        _label_route(placer, ax3, route, route_ids, [track], ringed=ringed)
    return fig


def route_png(plan: dict, route_index: int | None = None) -> bytes:
    """``route_figure`` as PNG bytes."""
    return _png(route_figure(plan, route_index))


def _route_kinds(plan: dict, entry: dict) -> np.ndarray:
    """Kind letter of each route point, A first."""
    kinds = ["A"] + [str(leg.get("kind", "")) for leg in entry["legs"]]
    kinds[-1] = "B"
    return np.array(kinds)


def _legend(dense: bool = False) -> list[Line2D]:
    def marker(label: str, **kw) -> Line2D:
        return Line2D([], [], ls="", label=label, **kw)

    other = {"ms": 2.5, "alpha": 0.5} if dense else {"ms": 4, "alpha": 0.5}
    return [
        Line2D([], [], color=COLOURS["track"], lw=1.6, label="flown trajectory (arcs + straights)"),
        marker(
            "V point (vertical correction) on route",
            marker="o",
            ms=8,
            mfc=COLOURS["V"],
            mec="black",
        ),
        marker(
            "H point (horizontal correction) on route",
            marker="^",
            ms=8,
            mfc=COLOURS["H"],
            mec="black",
        ),
        marker("other V points", marker="o", mfc=COLOURS["V"], mec="none", **other),
        marker("other H points", marker="^", mfc=COLOURS["H"], mec="none", **other),
        marker(
            "unreliable correction point on route"
            if dense
            else "unreliable correction point (x when off route)",
            marker="o",
            ms=13,
            mfc="none",
            mec=UNRELIABLE,
            mew=1.6,
        ),
        marker("A (start)", marker="*", ms=15, mfc=COLOURS["A"], mec="black"),
        marker("B (end)", marker="s", ms=10, mfc=COLOURS["B"], mec="black"),
    ]


BUDGET_W = 16.0  # inches, the error budget picture
BUDGET_ROW = 2.5  # inches, each of its side view and error plots when the plan view is above


def _budget_layout(aspect: float):
    """Figure and axes (plan, side, vertical, horizontal) of the error budget: the plan view
    (``aspect``: its height over width as drawn) left of the three others when it is tall
    enough, above them when it is flat."""
    if aspect >= 0.6:
        height = 10.0
        left = float(np.clip((height - CHROME - 0.6) / aspect, 4.0, 8.0)) + 1.0
        fig = plt.figure(figsize=(BUDGET_W, height), layout="constrained", dpi=DPI)
        grid = fig.add_gridspec(3, 2, width_ratios=[left, BUDGET_W - left])
        axy = fig.add_subplot(grid[:, 0])
        right = [grid[n, 1] for n in range(3)]
    else:
        top = float(np.clip((BUDGET_W - 1.0) * aspect, 1.5, 4.5)) + 0.6
        fig = plt.figure(
            figsize=(BUDGET_W, top + 3 * BUDGET_ROW + CHROME), layout="constrained", dpi=DPI
        )
        grid = fig.add_gridspec(4, 1, height_ratios=[top] + [BUDGET_ROW] * 3)
        axy = fig.add_subplot(grid[0, 0])
        right = [grid[n, 0] for n in range(1, 4)]
    axz = fig.add_subplot(right[0])
    axv = fig.add_subplot(right[1], sharex=axz)
    axh = fig.add_subplot(right[2], sharex=axz)
    return fig, axy, axz, axv, axh


# Marker areas (points²) of the error budget's plan view: route points, A and B.
BUDGET_SIZES = (50.0, 260.0, 120.0)


def error_budget_figure(plan: dict, route_index: int | None = None) -> Figure:
    """The error budget of a route: vertical and horizontal error against distance flown, with
    each point's limits and the margin left on arrival, beside the plan and side views."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route_m = route_xyz(plan, entry, legs)
    track_m = trajectory_local(plan, k)
    ids, along = _route_stops(entry)
    kinds = _route_kinds(plan, entry)
    params = plan.get("parameters") or {}
    residual = float(params.get("fail_residual", 0.0))
    unreliable = [False] + [bool(leg.get("unreliable", False)) for leg in entry["legs"]]

    route = route_m / KM
    track = track_m / KM
    view = MapView.of(np.r_[route[:, 0], track[:, 0]], np.r_[route[:, 1], track[:, 1]], 0.045)
    fig, axy, axz, axv, axh = _budget_layout(view.aspect)

    axy.plot(track[:, 0], track[:, 1], color=COLOURS["track"], lw=1.4)
    for letter in ("V", "H"):
        sel = kinds == letter
        axy.scatter(
            route[sel, 0],
            route[sel, 1],
            s=BUDGET_SIZES[0],
            c=COLOURS[letter],
            marker="o" if letter == "V" else "^",
            edgecolors="black",
            zorder=3,
        )
    ring = np.array(unreliable)
    if ring.any():
        axy.scatter(route[ring, 0], route[ring, 1], s=RING_SIZE, fc="none", ec=UNRELIABLE, lw=1.5)
    axy.scatter(*route[0, :2], s=BUDGET_SIZES[1], c=COLOURS["A"], marker="*", ec="k", zorder=4)
    axy.scatter(*route[-1, :2], s=BUDGET_SIZES[2], c=COLOURS["B"], marker="s", ec="k", zorder=4)
    view.apply(axy, "plan view")

    helices = _side_view(axz, track_m, along, route_m, ids, kinds, entry)
    margins = []
    for ax, component, resets in ((axv, "v", "V"), (axh, "h", "H")):
        margins.append(_budget(ax, entry, along, kinds, component, resets, unreliable, residual))
    axh.set_xlabel("distance flown (km)")
    plt.setp(axz.get_xticklabels(), visible=False)
    plt.setp(axv.get_xticklabels(), visible=False)

    handles = [
        Line2D([], [], color=COLOURS["V"], lw=1.6, label="error (corrections succeed)"),
        Line2D(
            [],
            [],
            ls="",
            marker="_",
            ms=16,
            mew=2.5,
            color=LIMIT,
            label="the point's limit on arrival",
        ),
        Line2D([], [], color=MARGIN, lw=3, alpha=0.5, label="margin left on arrival"),
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=7,
            mfc="none",
            mec=UNRELIABLE,
            label=f"error left if an unreliable correction fails (min(error, {residual:g}))",
        ),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=10, frameon=False)
    fig.suptitle("error budget — " + _title(plan, k, entry), fontsize=14)
    placer = LabelPlacer(fig)
    _label_route(placer, axy, route[:, :2], ids, [track[:, :2]], BUDGET_SIZES, ring)
    _label_side_view(placer, axz, track_m, along, route_m, ids, helices)
    for ax, (labels, markers, lines) in zip((axv, axh), margins, strict=True):
        _left_out(ax, placer.place(ax, labels, markers, lines), "margin")
    return fig


def error_budget_png(plan: dict, route_index: int | None = None) -> bytes:
    """``error_budget_figure`` as PNG bytes."""
    return _png(error_budget_figure(plan, route_index))


def _budget(ax, entry: dict, along, kinds, component: str, resets: str, unreliable, residual):
    """One component's sawtooth: growth along each leg, the drop at each correcting point, the
    limit (a bar) and the margin (a band from the error up to the limit) at every point.
    Returns the margins' labels, the markers and the lines they keep clear of."""
    legs = entry["legs"]
    arrival = np.array([0.0] + [float(leg[f"{component}_error"]) for leg in legs])
    limit = np.array([np.nan] + [float(leg[f"{component}_limit"]) for leg in legs])
    x = along / KM
    sx, sy = sawtooth(entry, component, resets)
    colour = COLOURS["V"] if component == "v" else COLOURS["H"]
    ax.plot(sx / KM, sy, color=colour, lw=1.6)
    ax.scatter(x[1:], arrival[1:], s=22, color=colour, zorder=3)
    ax.scatter(x[1:], limit[1:], marker="_", s=260, linewidths=2.5, color=LIMIT, zorder=4)
    ax.vlines(x[1:], arrival[1:], limit[1:], color=MARGIN, lw=3, alpha=0.5, zorder=2)
    tight = np.nanargmin(limit[1:] - arrival[1:]) + 1
    labels = []
    for n in range(1, len(x)):
        margin = limit[n] - arrival[n]
        labels.append(
            Label(
                f"{margin:.2f}" if margin < 1 else f"{margin:.1f}",
                (x[n], limit[n]),
                priority=0 if n == tight else 1,
                size=8,
                weight="bold" if n == tight else "normal",
                colour=LIMIT if n == tight else "0.25",
                clearance=2.0,
                directions=ABOVE,
            )
        )
    fails = [n for n in range(1, len(x)) if unreliable[n] and kinds[n] == resets]
    if fails:
        ax.scatter(
            x[fails],
            np.minimum(arrival[fails], residual),
            s=45,
            fc="none",
            ec=UNRELIABLE,
            lw=1.4,
            zorder=4,
        )
    # The corrections of this component, with the ids of the points that make them.
    for n in np.flatnonzero(kinds == resets):
        ax.axvline(x[n], color=colour, lw=0.6, alpha=0.25)
    name = "vertical" if component == "v" else "horizontal"
    ax.set_ylabel(f"{name} error (units)")
    top = np.nanmax(np.concatenate([limit[1:], arrival]))
    ax.set_ylim(0, top * 1.22)
    ax.set_title(
        f"{name} error: reset at {resets} points; limits and margins on arrival "
        f"(tightest {limit[tight] - arrival[tight]:.2f} at {entry['route'][tight]})",
        fontsize=11,
    )
    ax.grid(True, alpha=0.3)
    bars = np.column_stack([x[1:], limit[1:]])
    dots = np.column_stack([x[1:], arrival[1:]])
    markers = [(bars, (8.0, 2.0)), (dots, _marker_radius(22))]
    lines = [np.column_stack([sx / KM, sy])]
    lines += [np.array([[x[n], arrival[n]], [x[n], limit[n]]]) for n in range(1, len(x))]
    return labels, markers, lines


def front_figure(plan: dict) -> Figure:
    """The Pareto front: flown length against the number of corrections (integer ticks),
    coloured by the probability of arriving; readable with one route (said in words) and with
    fifty (labels only where they fit, routes below the plan's least probability drawn
    hollow)."""
    front = plan["front"]
    route_entry(plan)  # validates the plan and its chosen index
    chosen = int(plan.get("chosen", 0))
    corr = np.array([r.get("corrections", len(r["route"]) - 2) for r in front], dtype=float)
    length = np.array([r["length"] for r in front], dtype=float) / KM
    prob = np.array([r.get("probability", 1.0) for r in front], dtype=float)
    with_p = "probability" in (plan.get("objectives") or [])
    floor = float(plan.get("min_probability", 0.0) or 0.0)
    n = len(front)

    fig, ax = plt.subplots(figsize=(9, 6.5), layout="constrained", dpi=DPI)
    order = np.lexsort((length, corr))
    if not with_p and n > 1:  # with two objectives the front is a staircase worth a line
        ax.plot(corr[order], length[order], color="0.6", lw=1, zorder=1)
    size = 70 if n <= 20 else 40
    spread = with_p and prob.max() - prob.min() > 1e-9
    if spread:
        cmap = plt.get_cmap("viridis")
        norm = matplotlib.colors.Normalize(vmin=prob.min(), vmax=prob.max())
        colours = cmap(norm(prob))
        fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="P(arrive)")
    else:
        colours = np.tile(matplotlib.colors.to_rgba(COLOURS["V"]), (n, 1))
    safe = prob >= floor - 1e-12
    ax.scatter(
        corr[safe],
        length[safe],
        c=colours[safe],
        s=size,
        edgecolors="black",
        linewidths=0.6,
        zorder=2,
    )
    if (~safe).any():
        ax.scatter(
            corr[~safe],
            length[~safe],
            s=size,
            facecolors="none",
            edgecolors=colours[~safe],
            linewidths=1.6,
            zorder=2,
            label=f"P(arrive) below {floor:g}: not chosen by default",
        )
    # The chosen route is named in the legend, so that no label covers a point however many.
    text = f"chosen ({plan.get('choice', 'chosen')}): route {chosen}, "
    text += f"{corr[chosen]:.0f} corrections, {length[chosen]:.2f} km"
    if with_p:
        text += f", P(arrive) {prob[chosen]:.3f}"
    ax.scatter(
        corr[chosen],
        length[chosen],
        s=320,
        facecolors="none",
        edgecolors=COLOURS["B"],
        linewidths=2.2,
        zorder=3,
        label=text,
    )
    note = None
    if n == 1:
        note = ax.text(
            0.03,
            0.97,
            "The front has one route: no other feasible route is shorter,\n"
            "needs fewer corrections" + (" or is likelier to arrive." if with_p else "."),
            transform=ax.transAxes,
            va="top",
            fontsize=11,
            color="0.25",
        )
    if n == 1:  # a lone point: show a sensible window around it, not a zero-width axis
        ax.set_xlim(corr[0] - 1.5, corr[0] + 4.5)
        pad = max(abs(length[0]) * 0.03, 0.05)  # km; a 0 km route still gets a window
        ax.set_ylim(length[0] - pad, length[0] + pad)
    else:
        # A count axis: integer ticks, over at least three whole numbers (a narrower window
        # would leave MaxNLocator only fractional ticks).
        lo, hi = corr.min(), corr.max()
        pad = max(0.5, 0.08 * (hi - lo))
        lo, hi = lo - pad, hi + pad
        if hi - lo < 3:
            mid = (hi + lo) / 2
            lo, hi = mid - 1.5, mid + 1.5
        ax.set_xlim(lo, hi)
        ax.margins(y=0.1)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("number of corrections")
    ax.set_ylabel("flown length (km)")
    ax.grid(True, alpha=0.3)
    fig.legend(loc="outside lower center", ncol=1, fontsize=10, frameon=False)
    scen = (plan.get("scenario") or {}).get("name", "scenario")
    ax.set_title(
        f"{scen}: Pareto front ({n} route{'' if n == 1 else 's'}; objectives: "
        f"{', '.join(plan.get('objectives') or ['length', 'corrections'])})"
    )
    placer = LabelPlacer(fig)
    if note is not None:
        placer.reserve(note)
    if with_p and 1 < n <= 12:
        pts = np.column_stack([corr, length])
        labels = [
            Label(f"P {pr:.3f}", tuple(pt), size=9, colour="0.3", clearance=_marker_radius(size))
            for pt, pr in zip(pts, prob, strict=True)
        ]
        markers = [(pts, _marker_radius(size)), (pts[chosen : chosen + 1], _marker_radius(320))]
        _left_out(ax, placer.place(ax, labels, markers))
    return fig


def front_png(plan: dict) -> bytes:
    """``front_figure`` as PNG bytes."""
    return _png(front_figure(plan))
