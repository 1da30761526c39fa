"""Labels on a drawn figure placed so that none overprints another: each goes to the cheapest
free spot around its point once the figure's layout is fixed (``LabelPlacer``); a label with no
free spot is left out and its view's title says how many were (``left_out``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure

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

    def reserve(self, artist: Artist) -> None:
        """Keep labels off ``artist`` (a text drawn elsewhere, a legend ...)."""
        bb = artist.get_window_extent(self.renderer)
        self._take(np.array([bb.x0, bb.y0, bb.x1, bb.y1]))

    def _take(self, box: np.ndarray) -> None:
        self.taken = np.vstack([self.taken, box + [-PAD, -PAD, PAD, PAD]])

    def _display(self, ax: Axes, pts: np.ndarray) -> np.ndarray:
        """Display coordinates of points (n, 2), or (n, 3) on a 3D axes."""
        pts = np.asarray(pts, dtype=float).reshape(len(pts), -1)
        if pts.shape[1] == 3:
            pts = np.column_stack(project(ax, pts))
        return ax.transData.transform(pts)

    def place(
        self,
        ax: Axes,
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
                xy = tuple(float(c[0]) for c in project(ax, np.array([xy])))
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


def project(ax: Axes, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 2D coordinates of 3D points on a drawn 3D axes (what its transData takes)."""
    from mpl_toolkits.mplot3d import proj3d

    x, y, _ = proj3d.proj_transform(pts[:, 0], pts[:, 1], pts[:, 2], ax.M)
    return np.asarray(x, dtype=float), np.asarray(y, dtype=float)


def left_out(ax: Axes, dropped: int, what: str = "label") -> None:
    """Say in the view's title how many labels found no room."""
    if dropped:
        plural = "" if dropped == 1 else "s"
        ax.set_title(f"{ax.get_title()} ({dropped} {what}{plural} left out: no room)")


def marker_radius(size: float) -> float:
    """Radius (points) of a scatter marker of area ``size`` (points²)."""
    return float(np.sqrt(size)) / 2
