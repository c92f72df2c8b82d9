"""All exceptions raised by drd_planner.

Every error a user can trigger with bad input derives from :class:`DrdError`, so callers (the CLI,
the ROS node) can catch one type and print one clear line: a refusal.

A broken safety invariant of the planner itself (a path about to go out with an edge not checked free)
is a bug, not a refusal: it derives from :class:`InvariantError`, deliberately not a ``DrdError``, so no
refusal handler catches it. The CLI lets it raise with its traceback; the node logs it at ERROR with its
traceback, publishes nothing for that request and goes on.
"""

from __future__ import annotations


class DrdError(Exception):
    """Base class of every error drd_planner raises on purpose."""


class DatasetError(DrdError):
    """A dataset folder or file is missing, malformed or inconsistent."""


class TreeFileError(DrdError):
    """A decision-tree file is corrupt, of another format version, or built for another problem."""


class ProblemError(DrdError):
    """A problem (graph, library, worlds) is internally inconsistent."""


class PolicyError(DrdError):
    """A policy broke the episode contract (for example it chose an edge twice)."""


class InvariantError(RuntimeError):
    """A safety invariant of the planner broke: a bug in drd_planner, never the user's input."""


class UnverifiedPathError(InvariantError):
    """A path was about to be returned although one of its edges was not checked free."""


class GeometryError(DrdError):
    """A shape, pose, terrain grid, URDF or scene description is invalid or cannot be represented."""


class PlanningError(DrdError):
    """A planning request cannot be served: no maps yet, a goal no loaded tree serves, a wrong frame."""


class PriorFileError(TreeFileError):
    """A world-prior file is missing, corrupt, of another format version, or built for another domain."""


class ParameterError(DrdError):
    """A configuration value (a node parameter, a map limit) is out of range or not one of its choices."""


class SiteFileError(DatasetError):
    """A site file, or a GIS file it names (DEM, OSM, GeoJSON), is missing, malformed, too large or off the site."""
