"""One real operating site seen from a helicopter lattice: the DEM in the lattice frame, the datum, the lattice.

The ``"corridors"`` world model draws its worlds on one real site
(:class:`~drd_planner.domains.helicopter_corridors_params.CorridorsParams`: an elevation grid, the lattice's
origin and heading on it, the height datum, the known lines and zones, the registration error). An
:class:`OperatingSite` holds what a map server publishes of that site and what a terrain map is compared
with: the elevation grid seen from the lattice frame
(:class:`~drd_planner.domains.helicopter_corridors_model.SiteGrid`), the datum (z = 0) and the lattice's
:class:`~drd_planner.domains.helicopter_world_frame.WorldFrame` (corridor, terrain grid, start and goal).

Frames and units: the lattice frame is the planning frame (x along the site's heading, y to its left,
z = 0 at the datum), metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter import HelicopterDomain
from drd_planner.domains.helicopter_corridors_model import CorridorsModel, SiteGrid
from drd_planner.domains.helicopter_corridors_params import CorridorsParams
from drd_planner.domains.helicopter_world_frame import WorldFrame
from drd_planner.exceptions import ProblemError

__all__ = ["SITE_MODEL", "OperatingSite", "operating_site"]

#: The world model whose worlds are those of one real site.
SITE_MODEL = "corridors"


@dataclass(frozen=True)
class OperatingSite:
    """One real site as a helicopter lattice sees it.

    Attributes:
        name: a label for messages (the prior's name, or the site file's).
        params: the site's parameters (DEM path and units, origin, heading, datum, known lines and zones,
            registration error).
        grid: the DEM seen from the lattice frame (heights in the DEM's own zero, metres).
        datum: the DEM height that is z = 0 of the planning frame (metres).
        frame: the lattice's corridor, terrain grid (cell, margin), start and goal, vehicle clearance.
        wire_segments: capsules per wire span in the domain's scenes (None: each wire's default).
    """

    name: str
    params: CorridorsParams
    grid: SiteGrid
    datum: float
    frame: WorldFrame
    wire_segments: int | None

    def heights(self, x: FloatArray, y: FloatArray) -> FloatArray:
        """DEM heights above the datum at lattice-frame points (any shape, metres); NaN outside the DEM."""
        return np.asarray(self.grid.heights(x, y) - self.datum, dtype=np.float64)

    @property
    def registration_bound(self) -> tuple[float, float]:
        """(horizontal, vertical) largest registration error of the site's worlds: 3 sigma each (metres).

        The horizontal bound is that of the shift's length (both axes at 3 sigma).
        """
        return 3.0 * math.sqrt(2.0) * self.params.shift_sigma, 3.0 * self.params.bias_sigma


def operating_site(
    domain: Any, *, name: str, params: CorridorsParams | None = None, model: CorridorsModel | None = None
) -> OperatingSite | None:
    """The site of a helicopter domain's ``corridors`` parameters (or of ``params``); None for other domains.

    Args:
        domain: the lattice's domain (a helicopter domain has a site; any other gives None).
        name: the label of the site in messages.
        params: the site's parameters (e.g. from a site file); None: the domain's ``corridors`` model's.
        model: the corridors model whose grid cache reads the DEM (None: a new one).

    Raises:
        ProblemError: the DEM is missing or unusable, or the lattice origin lies outside it (no datum).
    """
    if not isinstance(domain, HelicopterDomain):
        return None
    p = params if params is not None else domain.model_params(SITE_MODEL)
    if not isinstance(p, CorridorsParams):
        raise ProblemError(f"{name}: the site needs corridors parameters, got {type(p).__name__}")
    grid = (model or CorridorsModel()).site(p)
    datum = p.datum if p.datum is not None else float(grid.heights(np.zeros(1), np.zeros(1))[0])
    if not math.isfinite(datum):
        raise ProblemError(
            f"{name}: the site origin {p.site_origin} lies outside the elevation grid {p.resolved_path()}; "
            "no height datum"
        )
    return OperatingSite(name, p, grid, datum, domain.frame, domain.params.wire_segments)
