"""What is known of a site prior's site, as one world and as the map messages a map server publishes.

The nominal world of a :class:`~drd_planner.domains.helicopter_site.OperatingSite` (:func:`site_world`):

- **terrain**: the site's DEM on the lattice's terrain grid (the prior's ``terrain_cell`` and
  ``world_margin``), heights in metres above the site's datum, with no registration error and with the
  pads the model cuts at the start and goal (the corridors model's own terrain of a world whose shift and
  bias are zero);
- **every known power line** (whether it stands or not is what the planner's prior is about; a map server
  publishes what is known): towers on every route point and evenly between them at most the middle of the
  ``span`` range apart, each a vertical cylinder (``tower_radius``) from 10 m under the ground to its top at
  the middle of the ``tower_height`` range above the DEM; between towers the middle of the ``conductors``
  range (rounded up) of conductors ``conductor_gap`` apart, the top one from top to top, each sagging by
  the middle of the ``sag`` range;
- **every known no-fly zone** (active or not), as its column (cylinder or prism over its ``z_range``), and
  the zones the model's ``nofly`` lists explicitly (random ones are not known and not published).

:func:`site_messages` encodes it as the planner node reads maps (:mod:`~drd_planner.planning.world_messages`:
wires as LINE_STRIPs through the capsule chain's knots, towers and zones as CYLINDER / CUBE markers, the
terrain as an organized PointCloud2), all in one frame (the planning frame; x along the site's heading).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Any

import numpy as np

from drd_msgs_py.factory import MessageFactory
from drd_planner.arrays import FloatArray
from drd_planner.domains.helicopter_corridors_model import CorridorsModel
from drd_planner.domains.helicopter_corridors_params import KnownLine
from drd_planner.domains.helicopter_site import SITE_MODEL, OperatingSite
from drd_planner.domains.helicopter_world_params import NoFlyZone
from drd_planner.domains.helicopter_worlds import HelicopterWorld
from drd_planner.exceptions import ProblemError
from drd_planner.geometry.pose import Pose
from drd_planner.geometry.shapes import Cylinder, Shape
from drd_planner.geometry.terrain import Heightfield
from drd_planner.geometry.wires import Wire
from drd_planner.planning.world_messages import helicopter_world_messages

__all__ = ["TOWER_FOOTING_M", "site_messages", "site_terrain", "site_world", "tower_positions"]

#: How far a tower cylinder reaches under the ground (metres), as in the corridors model.
TOWER_FOOTING_M = 10.0


def tower_positions(route: FloatArray, span: float) -> FloatArray:
    """(n, 2) tower positions along a (k >= 2, 2) route: every route point and evenly between, <= ``span`` apart.

    Metres, lattice frame.
    """
    out = [route[:1]]
    for a, b in itertools.pairwise(route):
        pieces = max(1, math.ceil(float(np.linalg.norm(b - a)) / span - 1e-9))
        out.append(a + (np.arange(1, pieces + 1)[:, None] / pieces) * (b - a))
    return np.concatenate(out)


def _middle(r: tuple[float, float]) -> float:
    return 0.5 * (float(r[0]) + float(r[1]))


def _line(site: OperatingSite, line: KnownLine) -> tuple[list[Wire], list[tuple[str, Shape, Pose]]]:
    """The nominal towers and conductors of one known line (see the module docstring)."""
    p = site.params
    bases = tower_positions(np.asarray(line.route, dtype=np.float64), _middle(line.span))
    ground = site.heights(bases[:, 0], bases[:, 1])
    if np.isnan(ground).any():
        raise ProblemError(f"{site.name}: known line {line.name!r} has towers outside the elevation grid")
    tops = ground + _middle(line.tower_height)
    solids: list[tuple[str, Shape, Pose]] = []
    for k, (base, z0, top) in enumerate(zip(bases, ground, tops, strict=True)):
        length = float(top - z0) + TOWER_FOOTING_M
        centre = (float(base[0]), float(base[1]), float(z0) - TOWER_FOOTING_M + length / 2.0)
        solids.append((f"tower_{line.name}_{k}", Cylinder(p.tower_radius, length), Pose(centre)))
    conductors = math.ceil(_middle(line.conductors))
    sag = _middle(line.sag)
    wires = [
        Wire(
            (float(bases[k, 0]), float(bases[k, 1]), float(tops[k]) - c * p.conductor_gap),
            (float(bases[k + 1, 0]), float(bases[k + 1, 1]), float(tops[k + 1]) - c * p.conductor_gap),
            sag,
            p.wire_diameter,
        )
        for k in range(bases.shape[0] - 1)
        for c in range(conductors)
    ]
    return wires, solids


def site_terrain(site: OperatingSite) -> Heightfield:
    """The site's terrain on the lattice's grid: DEM heights above the datum, pads at the start and goal (m).

    Raises:
        ProblemError: the lattice's terrain grid leaves the DEM (the text names the site and the extent).
    """
    exact = dataclasses.replace(site.params, shift_sigma=0.0, bias_sigma=0.0, datum=site.datum)
    # With no registration error the draw's terrain takes nothing from the generator.
    return CorridorsModel().draw(np.random.default_rng(0), exact, site.frame).terrain


def site_world(site: OperatingSite) -> HelicopterWorld:
    """The site's nominal world: its terrain, every known line and every known zone (module docstring).

    Raises:
        ProblemError: the lattice or a known line leaves the DEM.
    """
    wires: list[Wire] = []
    solids: list[tuple[str, Shape, Pose]] = []
    for line in site.params.lines:
        more_wires, more_solids = _line(site, line)
        wires.extend(more_wires)
        solids.extend(more_solids)
    listed: tuple[NoFlyZone, ...] = () if isinstance(site.params.nofly, int) else tuple(site.params.nofly)
    zones = tuple(zone.column() for zone in site.params.zones) + listed
    solids.extend((f"nofly_{i}", *zone.solid()) for i, zone in enumerate(zones))
    info: dict[str, Any] = {
        "site": site.name,
        "datum": site.datum,
        "lines": [line.name for line in site.params.lines],
        "zones": [zone.name for zone in site.params.zones],
    }
    return HelicopterWorld(SITE_MODEL, 0, site_terrain(site), tuple(wires), tuple(solids), zones, info)


def site_messages(
    site: OperatingSite,
    *,
    frame_id: str,
    stamp: tuple[int, int] = (0, 0),
    msgs: MessageFactory,
    world: HelicopterWorld | None = None,
) -> tuple[Any, Any]:
    """(MarkerArray of the known obstacles, DELETEALL first; organized PointCloud2 of the terrain).

    Args:
        site: the site.
        frame_id: the frame of both messages (the planning frame).
        stamp: (sec, nanosec) of the headers.
        msgs: the message factory (rclpy or rosbags classes).
        world: the site's nominal world when already built (:func:`site_world`).
    """
    nominal = site_world(site) if world is None else world
    return helicopter_world_messages(
        nominal, wire_segments=site.wire_segments, frame_id=frame_id, stamp=stamp, msgs=msgs
    )
