"""The plan view of a map: its limits cropped to what it shows, with equal scales on both axes
unless the data is so elongated that its short side must be stretched (the title then says by
how much)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from matplotlib.axes import Axes
from numpy.typing import ArrayLike

# A map view is stretched along its short side when it is flatter than this (height / width).
MIN_MAP_ASPECT = 0.18
MAX_STRETCH = 3.0
MIN_STRETCH = 1.5  # below this, the short side is widened with margin rather than stretched


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
    def of(cls, xs: ArrayLike, ys: ArrayLike, margin: float = 0.04) -> MapView:
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

    def apply(self, ax: Axes, title: str) -> None:
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
