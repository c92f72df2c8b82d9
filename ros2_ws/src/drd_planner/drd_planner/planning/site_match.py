"""Whether a terrain map can be a site prior's site: extent, height offset and shape against the prior's DEM.

A corridors prior (:mod:`~drd_planner.planning.prior_site`; its site an
:class:`~drd_planner.domains.helicopter_site.OperatingSite`) was trained on worlds whose terrain is the
site's DEM shifted horizontally by at most the registration bound ``3 sqrt(2) shift_sigma`` and vertically
by at most ``3 bias_sigma``. A terrain map of that site, in the planning frame (x along the site's heading,
z = 0 at its datum, metres), therefore

- covers the lattice's corridor (x and y ranges of the lattice, half a terrain cell of slack);
- lies at the DEM's height: the median of (terrain - DEM) over the corridor's cells is within the vertical
  bound plus :data:`HEIGHT_TOLERANCE_M` (a map above sea level, or of another site's datum, is not);
- has the DEM's shape: once that median is taken off, at most :data:`OUTLIER_FRACTION` of the cells differ
  from the DEM by more than what the horizontal bound explains on the local slope (``slope * bound``) plus
  the tolerance (a map of another place, mirrored, or shifted by hundreds of metres is not). The fraction
  leaves room for the pads the model cuts at the start and goal and for a building or two.

:func:`site_mismatch` returns why a terrain is not the site (one sentence with the numbers), or None.
Measured on the shipped ``heli_lines`` site: worlds of the model (registration errors up to 34 m
vertically) give medians within 35 m and at most 0.6 % outlying cells; a world of another model, the
site mirrored or rolled by 300 m give 77-87 % outlying cells, the site raised by 400 m a median of 410 m.
"""

from __future__ import annotations

import numpy as np

from drd_planner.domains.helicopter_site import OperatingSite
from drd_planner.geometry.terrain import Heightfield

__all__ = ["HEIGHT_TOLERANCE_M", "OUTLIER_FRACTION", "SLOPE_STEP_M", "site_mismatch"]

#: Metres allowed on top of the registration error's bounds (DEM interpolation, map noise).
HEIGHT_TOLERANCE_M = 15.0
#: Largest fraction of the corridor's cells whose height may differ from the DEM beyond the bound.
OUTLIER_FRACTION = 0.2
#: Half the step of the central differences that give the DEM's slope (metres).
SLOPE_STEP_M = 10.0


def _cells(terrain: Heightfield) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) x and y of the terrain's grid points, metres."""
    rows, cols = terrain.heights.shape
    xs = float(terrain.origin[0]) + float(terrain.cell_size) * np.arange(cols)
    ys = float(terrain.origin[1]) + float(terrain.cell_size) * np.arange(rows)
    gx, gy = np.meshgrid(xs, ys)
    return gx, gy


def _slope(site: OperatingSite, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The DEM's slope (rise per metre, >= 0) at points ``x``, ``y`` (same shape), by central differences."""
    h = SLOPE_STEP_M
    dx = (site.heights(x + h, y) - site.heights(x - h, y)) / (2.0 * h)
    dy = (site.heights(x, y + h) - site.heights(x, y - h)) / (2.0 * h)
    return np.asarray(np.nan_to_num(np.hypot(dx, dy), nan=0.0), dtype=np.float64)


def _extent_problem(site: OperatingSite, terrain: Heightfield) -> str | None:
    """Why the terrain's grid does not cover the lattice's corridor, or None."""
    x0, x1, y0, y1 = terrain.extent
    (lx0, lx1), (ly0, ly1) = site.frame.x_range, site.frame.y_range
    slack = 0.5 * float(terrain.cell_size)
    if x0 - slack <= lx0 and x1 + slack >= lx1 and y0 - slack <= ly0 and y1 + slack >= ly1:
        return None
    return (
        f"its grid spans x [{x0:.0f}, {x1:.0f}] m, y [{y0:.0f}, {y1:.0f}] m and does not cover the lattice "
        f"x [{lx0:.0f}, {lx1:.0f}] m, y [{ly0:.0f}, {ly1:.0f}] m (planning frame: x along the site's heading, "
        "origin at the lattice's)"
    )


def site_mismatch(site: OperatingSite, terrain: Heightfield, *, tolerance: float = HEIGHT_TOLERANCE_M) -> str | None:
    """Why ``terrain`` cannot be ``site``'s terrain (one sentence, starting "terrain is not ..."), or None.

    Args:
        site: the prior's site (DEM, datum, lattice corridor, registration error).
        terrain: the terrain map, heights in metres above the planning frame's z = 0.
        tolerance: metres allowed beyond the registration error's bounds.
    """
    label = f"terrain is not the site of prior {site.name!r}"
    extent = _extent_problem(site, terrain)
    if extent is not None:
        return f"{label}: {extent}"
    gx, gy = _cells(terrain)
    (lx0, lx1), (ly0, ly1) = site.frame.x_range, site.frame.y_range
    inside = (gx >= lx0) & (gx <= lx1) & (gy >= ly0) & (gy <= ly1)
    diff = terrain.heights - site.heights(gx, gy)
    known = inside & np.isfinite(diff)
    if not known.any():
        return (
            f"{label}: no height of its grid over the lattice can be compared with the site's DEM (every one "
            "is unknown, or the DEM has no data there)"
        )
    d = diff[known]
    offset = float(np.median(d))
    shift, bias = site.registration_bound
    allowed = bias + tolerance
    if abs(offset) > allowed:
        return (
            f"{label}: median height differs by {offset:+.0f} m from its DEM (allowed {allowed:.0f} m: "
            f"registration error {bias:.0f} m plus {tolerance:.0f} m); heights must be metres above the site's "
            f"datum ({site.datum:.1f} m of the DEM), not above sea level or another datum"
        )
    bound = _slope(site, gx[known], gy[known]) * shift + tolerance
    outlying = float(np.mean(np.abs(d - offset) > bound))
    if outlying > OUTLIER_FRACTION:
        return (
            f"{label}: its shape differs from the DEM: {100 * outlying:.0f} % of the cells over the lattice "
            f"differ by more than the registration error explains (allowed {100 * OUTLIER_FRACTION:.0f} %; "
            f"horizontal error up to {shift:.0f} m, {tolerance:.0f} m tolerance): another place, or a frame "
            "turned, mirrored or offset from the lattice's"
        )
    return None
