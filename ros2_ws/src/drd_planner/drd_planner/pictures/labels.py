"""Check numbers placed where they hide no obstacle: spots along each edge, then rings around it.

A plan picture writes each check's number next to its edge. :class:`LabelPlacer` puts every number
where its box (text plus its white background) overlaps no obstacle drawn on the panel: no wire, no
tower dot and no outline, and no filled footprint either, unless that footprint is a *background
surface* (it spans at least :data:`BACKGROUND_SHARE` of the panel's width and height, such as the arm's
table seen from above: a number may sit on it, never across its outline). It tries, best first:

1. the edge itself, at the arc-length fractions :data:`ANCHORS` of the edge on the screen;
2. rings of :data:`RING_DIRECTIONS` spots around those anchors, one label height further per ring (up
   to :data:`RINGS`), joined to their anchor by a thin leader line in the label's colour.

Within each ring, a spot clear of every obstacle that also keeps clear of the numbers already placed
and of the start and goal markers wins, then such a spot on a background surface; when no ring has one,
the nearest spot clear of obstacles (over another number); a number that finds no spot clear of
obstacles in any ring is left out (thinned, counted in ``hidden``). Everything is computed in display pixels of the
drawn figure (its layout fixed first), so what is tested is what the PNG shows. matplotlib is imported only here and in
the drawing modules.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from drd_planner.arrays import BoolArray, FloatArray
from drd_planner.pictures.geometry import PictureError

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.text import Text

__all__ = [
    "ANCHORS",
    "BACKGROUND_SHARE",
    "LABEL_BOX",
    "RINGS",
    "RING_DIRECTIONS",
    "DisplayObstacles",
    "LabelPlacer",
    "PendingLabel",
    "boxes_hit_segments",
    "boxes_overlap",
    "line_anchors",
]

#: Arc-length fractions along an edge (on the screen) tried as the label's spot, best first.
ANCHORS = (0.5, 0.38, 0.62, 0.26, 0.74, 0.14, 0.86)
#: Spots per ring around each anchor, and rings (each one label height further out).
RING_DIRECTIONS = 12
RINGS = 8
#: Free space kept between a label's box and an obstacle, in points.
CLEARANCE_PT = 1.5
#: A filled obstacle spanning at least this share of the panel's width and height is a background surface.
BACKGROUND_SHARE = 0.4
#: The text style of a check number and its box (matplotlib Text keywords).
LABEL_STYLE: dict[str, Any] = {
    "fontsize": 7,
    "fontweight": "bold",
    "ha": "center",
    "va": "center",
    "zorder": 10,
}
LABEL_BOX: dict[str, Any] = {"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.9}
_PAD = 0.15  # the box's pad, a fraction of the font size (LABEL_BOX's boxstyle)


@dataclass(frozen=True)
class PendingLabel:
    """A number waiting for its spot: its text, colour and the (K, 2) picture coordinates of its edge."""

    text: str
    colour: str
    line: FloatArray


def line_anchors(line: FloatArray, fractions: Sequence[float] = ANCHORS) -> FloatArray:
    """(A, 2) points at the given arc-length fractions along a (K, 2) polyline (one point: itself)."""
    if line.shape[0] < 2:
        return np.repeat(line[:1], len(fractions), axis=0)
    steps = np.linalg.norm(np.diff(line, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(steps)])
    if s[-1] <= 0.0:
        return np.repeat(line[:1], len(fractions), axis=0)
    at = np.asarray(fractions, dtype=np.float64) * s[-1]
    return np.stack([np.interp(at, s, line[:, 0]), np.interp(at, s, line[:, 1])], axis=1)


def boxes_hit_segments(boxes: FloatArray, segments: FloatArray, half_widths: FloatArray) -> BoolArray:
    """(C,) bool: which boxes touch a thick segment (separating axes, each box grown by the half width).

    Args:
        boxes: (C, 4) x0, y0, x1, y1 (pixels).
        segments: (M, 2, 2) end points (pixels); a zero-length segment is a dot.
        half_widths: (M,) half the drawn width of each segment (pixels).
    """
    if segments.shape[0] == 0 or boxes.shape[0] == 0:
        return np.zeros(boxes.shape[0], dtype=bool)
    w = half_widths[None, :]
    x0, y0 = boxes[:, 0:1] - w, boxes[:, 1:2] - w  # (C, M)
    x1, y1 = boxes[:, 2:3] + w, boxes[:, 3:4] + w
    a, b = segments[:, 0], segments[:, 1]  # (M, 2)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    apart = (hi[:, 0] < x0) | (lo[:, 0] > x1) | (hi[:, 1] < y0) | (lo[:, 1] > y1)
    normal = np.stack([a[:, 1] - b[:, 1], b[:, 0] - a[:, 0]], axis=1)  # (M, 2)
    sides = [
        (cx - a[:, 0]) * normal[:, 0] + (cy - a[:, 1]) * normal[:, 1]
        for cx, cy in ((x0, y0), (x0, y1), (x1, y0), (x1, y1))
    ]
    stacked = np.stack(sides)  # (4, C, M)
    apart |= np.all(stacked > 0.0, axis=0) | np.all(stacked < 0.0, axis=0)
    hit: BoolArray = np.any(~apart, axis=1)
    return hit


def boxes_overlap(boxes: FloatArray, others: FloatArray) -> BoolArray:
    """(C,) bool: which of (C, 4) boxes overlap any of (N, 4) boxes (x0, y0, x1, y1)."""
    if others.shape[0] == 0 or boxes.shape[0] == 0:
        return np.zeros(boxes.shape[0], dtype=bool)
    b, o = boxes[:, None, :], others[None, :, :]
    inter = (b[..., 0] < o[..., 2]) & (o[..., 0] < b[..., 2]) & (b[..., 1] < o[..., 3]) & (o[..., 1] < b[..., 3])
    hit: BoolArray = np.any(inter, axis=1)
    return hit


@dataclass(frozen=True)
class DisplayObstacles:
    """A panel's obstacles in display pixels: thick segments, and filled outlines.

    Attributes:
        segments: (M, 2, 2) wire pieces, outline sides and dots (zero length), pixels.
        half_widths: (M,) half their drawn width, pixels.
        fills: (P_i, 2) closed outlines of the filled obstacles, pixels.
        background: per fill, whether it is a background surface (see the module docstring).
    """

    segments: FloatArray
    half_widths: FloatArray
    fills: tuple[FloatArray, ...]
    background: tuple[bool, ...]

    @classmethod
    def from_artists(cls, ax: Axes, artists: Sequence[Artist]) -> DisplayObstacles:
        """The obstacles drawn on ``ax`` as LineCollections (wires), Patches (footprints), Line2Ds (dots).

        Raises:
            PictureError: another kind of artist.
        """
        pieces: list[FloatArray] = []
        widths: list[FloatArray] = []
        fills: list[FloatArray] = []
        for artist in artists:
            lines, half, fill = _artist_lines(ax, artist)
            fills += [] if fill is None else [fill]
            for line in lines:
                if line.shape[0] >= 2:
                    pieces.append(np.stack([line[:-1], line[1:]], axis=1))
                    widths.append(np.full(line.shape[0] - 1, half))
        bounds = ax.bbox
        background = tuple(
            bool(np.ptp(f[:, 0]) >= BACKGROUND_SHARE * bounds.width)
            and bool(np.ptp(f[:, 1]) >= BACKGROUND_SHARE * bounds.height)
            for f in fills
        )
        return cls(
            np.concatenate(pieces) if pieces else np.zeros((0, 2, 2)),
            np.concatenate(widths) if widths else np.zeros(0),
            tuple(fills),
            background,
        )

    def near(self, region: FloatArray) -> DisplayObstacles:
        """The obstacles that may touch the (4,) box x0, y0, x1, y1 (pixels): a cheaper set to test."""
        lo = np.minimum(self.segments[:, 0], self.segments[:, 1]) - self.half_widths[:, None]
        hi = np.maximum(self.segments[:, 0], self.segments[:, 1]) + self.half_widths[:, None]
        keep = np.all(lo <= region[2:], axis=1) & np.all(hi >= region[:2], axis=1)
        near = [
            k
            for k, f in enumerate(self.fills)
            if np.all(f.min(axis=0) <= region[2:]) and np.all(f.max(axis=0) >= region[:2])
        ]
        return DisplayObstacles(
            self.segments[keep],
            self.half_widths[keep],
            tuple(self.fills[k] for k in near),
            tuple(self.background[k] for k in near),
        )

    def hits(self, boxes: FloatArray) -> tuple[BoolArray, BoolArray]:
        """Which (C, 4) boxes touch an obstacle: (C,) counting background fills, and (C,) not counting them.

        A box touches a fill when a side of the fill crosses it (a segment) or its centre lies inside it.
        """
        from matplotlib.path import Path

        strict = boxes_hit_segments(boxes, self.segments, self.half_widths)
        centres = 0.5 * (boxes[:, :2] + boxes[:, 2:])
        lenient = strict.copy()
        for fill, is_background in zip(self.fills, self.background, strict=True):
            inside = Path(fill).contains_points(centres)
            strict |= inside
            if not is_background:
                lenient |= inside
        return strict, lenient


def _artist_lines(ax: Axes, artist: Artist) -> tuple[list[FloatArray], float, FloatArray | None]:
    """(polylines in pixels, half their drawn width in pixels, the filled outline or None) of an obstacle."""
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    scale = ax.figure.dpi / 72.0  # pixels per point
    if isinstance(artist, LineCollection):
        transform = artist.get_transform()
        lines = [transform.transform(np.asarray(s)) for s in artist.get_segments()]
        return lines, 0.5 * scale * float(np.max(artist.get_linewidth())), None
    if isinstance(artist, Patch):
        outline = np.asarray(artist.get_verts())
        return [outline], 0.5 * scale * artist.get_linewidth(), outline
    if isinstance(artist, Line2D):
        xy = artist.get_transform().transform(np.asarray(artist.get_xydata()))
        joined = artist.get_linestyle() not in ("None", "", " ")
        lines = [xy] if joined else [np.repeat(p[None, :], 2, axis=0) for p in xy]
        drawn = max(artist.get_linewidth() if joined else 0.0, artist.get_markersize())
        return lines, 0.5 * scale * drawn, None
    raise PictureError(
        f"cannot keep labels off a {type(artist).__name__}: obstacles are drawn as "
        "LineCollection, Patch or Line2D artists"
    )


class LabelPlacer:
    """Places the check numbers of one panel (see the module docstring).

    Args:
        ax: the panel, its layout already fixed (the figure drawn once).
        obstacles: the obstacle artists drawn on it (wires, footprints, tower dots).
        keep_clear: artists numbers should rather not cover (start and goal markers).

    Text sizes come from the figure's own renderer (a canvas must be attached).
    """

    def __init__(self, ax: Axes, obstacles: Sequence[Artist], keep_clear: Sequence[Artist]) -> None:
        self.ax = ax
        self.obstacles = DisplayObstacles.from_artists(ax, obstacles)
        boxes = [a.get_window_extent() for a in keep_clear]
        self.taken: list[FloatArray] = [np.array([b.x0, b.y0, b.x1, b.y1]) for b in boxes]
        inner = ax.bbox
        self.frame = (inner.x0 + 1.0, inner.y0 + 1.0, inner.x1 - 1.0, inner.y1 - 1.0)
        self.clearance = CLEARANCE_PT * ax.figure.dpi / 72.0

    def place(self, labels: Sequence[PendingLabel]) -> tuple[list[Text], dict[str, int]]:
        """Draw each label at its best spot; return the texts (in order) and ``moved`` / ``hidden`` counts."""
        texts: list[Text] = []
        counts = {"moved": 0, "hidden": 0}
        for label in labels:
            text = self.ax.text(0.0, 0.0, label.text, color=label.colour, bbox=LABEL_BOX, **LABEL_STYLE)
            text.set_in_layout(False)
            anchors = self.ax.transData.transform(line_anchors(label.line))
            spot = self._spot(anchors, self._size(text))
            if spot is None:
                text.set_visible(False)
                counts["hidden"] += 1
            else:
                centre, anchor, ring = spot
                inverse = self.ax.transData.inverted()
                x, y = (float(v) for v in inverse.transform(centre))
                text.set_position((x, y))
                if ring > 0:
                    (ax_, ay), (bx, by) = inverse.transform(np.stack([anchor, centre]))
                    leader = self.ax.plot(
                        [ax_, bx], [ay, by], color=label.colour, linewidth=0.7, alpha=0.9, zorder=9.5
                    )[0]
                    leader.set_in_layout(False)
                    counts["moved"] += 1
            texts.append(text)
        return texts, counts

    def _size(self, text: Text) -> FloatArray:
        """(2,) width and height (pixels) of a label's box: its text plus the box's pad on each side."""
        extent = text.get_window_extent()
        pad = 2.0 * _PAD * float(text.get_fontsize()) * self.ax.figure.dpi / 72.0
        return np.array([extent.width + pad, extent.height + pad])

    def _spot(self, anchors: FloatArray, size: FloatArray) -> tuple[FloatArray, FloatArray, int] | None:
        """(centre, anchor, ring) of the best free spot (pixels), or None when every spot hides an obstacle.

        Ring by ring outwards, a spot clear of every obstacle and of the labels already placed wins, then
        one that sits on a background surface; after the last ring, the nearest spot clear of obstacles
        that overlaps a label.
        """
        first_free: tuple[FloatArray, FloatArray, int] | None = None
        reach = 0.5 * size + _ring(np.zeros((1, 2)), size, RINGS)[0].max(axis=0) + self.clearance
        region = np.concatenate([anchors.min(axis=0) - reach, anchors.max(axis=0) + reach])
        obstacles = self.obstacles.near(region)
        for ring in range(RINGS + 1):
            centres, origins = _ring(anchors, size, ring)
            boxes = self._boxes(centres, size)
            inside = self._inside(boxes)
            apart = ~boxes_overlap(boxes, self._taken())
            for touches in obstacles.hits(boxes):
                free = inside & ~touches
                clear = free & apart
                if clear.any():
                    k = int(np.argmax(clear))
                    return self._take(centres[k], origins[k], ring, size)
                if first_free is None and free.any():
                    k = int(np.argmax(free))
                    first_free = (centres[k], origins[k], ring)
        return None if first_free is None else self._take(*first_free, size)

    def _take(
        self, centre: FloatArray, anchor: FloatArray, ring: int, size: FloatArray
    ) -> tuple[FloatArray, FloatArray, int]:
        """Mark a chosen spot as taken and return it."""
        self.taken.append(self._boxes(centre[None, :], size)[0])
        return centre, anchor, ring

    def _boxes(self, centres: FloatArray, size: FloatArray) -> FloatArray:
        """(C, 4) boxes of the given size about (C, 2) centres, grown by the clearance (pixels)."""
        half = 0.5 * size + self.clearance
        return np.concatenate([centres - half, centres + half], axis=1)

    def _inside(self, boxes: FloatArray) -> BoolArray:
        """(C,) bool: which boxes lie inside the panel (a number is never clipped)."""
        x0, y0, x1, y1 = self.frame
        inside: BoolArray = (boxes[:, 0] >= x0) & (boxes[:, 1] >= y0) & (boxes[:, 2] <= x1) & (boxes[:, 3] <= y1)
        return inside

    def _taken(self) -> FloatArray:
        return np.stack(self.taken) if self.taken else np.zeros((0, 4))


def _ring(anchors: FloatArray, size: FloatArray, ring: int) -> tuple[FloatArray, FloatArray]:
    """((C, 2) candidate centres, (C, 2) their anchors) of one ring around (A, 2) anchors (pixels).

    Ring 0 is the anchors themselves; ring k puts :data:`RING_DIRECTIONS` spots per anchor on an ellipse
    0.8 k label heights out (widened by half the label's width: the first ring clears the anchor).
    """
    if ring == 0:
        return anchors, anchors
    angles = np.pi / 2.0 + 2.0 * np.pi * np.arange(RING_DIRECTIONS) / RING_DIRECTIONS  # straight up first
    radius = np.array([0.5 * size[0] + 0.8 * ring * size[1], (0.8 * ring + 0.3) * size[1]])
    offsets = radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)  # (R, 2)
    centres = (anchors[:, None, :] + offsets[None, :, :]).reshape(-1, 2)
    origins = np.repeat(anchors, RING_DIRECTIONS, axis=0)
    return centres, origins
