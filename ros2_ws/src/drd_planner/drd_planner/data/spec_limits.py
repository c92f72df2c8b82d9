"""Bounds on a stored domain spec, checked before the domain is rebuilt from it.

A tree or prior file stores the spec its graph was built from; the planning session rebuilds the domain
from it (:func:`drd_planner.domains.base.domain_from_spec`) and compares graphs. A crafted spec could
make that rebuild allocate without bound before the comparison refuses it (a helicopter lattice spanning
1e9 m grew the node to 24 GiB). So the loaders check here, without building anything, that the
spec's numbers are finite and bounded and that what it would build stays within a budget: the lattice
states and candidate edges, trajectory samples per edge and in all, roadmap samples and neighbours.

Only sizes are judged; everything else the domain classes validate themselves when they are built.
"""

from __future__ import annotations

import math
import stat
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, NamedTuple

from drd_planner.data.content_checks import MAX_COORDINATE_M, MAX_VERTICES
from drd_planner.exceptions import ProblemError

__all__ = [
    "MAX_LATTICE_CANDIDATE_EDGES",
    "MAX_LATTICE_STATES",
    "MAX_ROADMAP_NEIGHBOURS",
    "MAX_ROADMAP_SAMPLES",
    "MAX_ROBOT_FILE_BYTES",
    "MAX_SAMPLES_PER_EDGE",
    "MAX_SPEC_LIST",
    "MAX_TRAJECTORY_SAMPLES",
    "check_domain_spec",
]

MAX_LATTICE_STATES = 2_000_000
"""Most grid states (positions x levels x 8 headings) a lattice spec may span before pruning. The
shipped helicopter lattice spans 15 x 11 x 3 x 8 = 3960 (731 kept)."""

MAX_LATTICE_CANDIDATE_EDGES = 5_000_000
"""Most candidate edges (grid states x primitives x climb variants) a lattice is built from before
pruning; about 240 MB of edge ids while it is built (the shipped lattice: about 107 000)."""

MAX_SAMPLES_PER_EDGE = 100_000
"""Most trajectory samples along one edge (the shipped helicopter edges have 11-43)."""

MAX_TRAJECTORY_SAMPLES = 10_000_000
"""Most trajectory or collision-check samples over all stored edges, estimated from the spec and the
stored edge count (the shipped trees: about 71 000 helicopter and 76 000 arm samples)."""

MAX_ROADMAP_SAMPLES = 1_000_000
"""Most roadmap samples an arm spec may ask for (the shipped arm roadmap draws 600)."""

MAX_ROADMAP_NEIGHBOURS = 256
"""Most nearest neighbours per roadmap vertex (the shipped roadmap uses 8)."""

MAX_SPEC_LIST = 10_000
"""Most items of any list in a spec (primitives, altitude levels, ...)."""

MAX_ROBOT_FILE_BYTES = 16 * 2**20
"""Largest robot description file (URDF, spherized URDF, SRDF) an arm spec may name (the Panda's
are 3-30 KiB)."""

_HEADINGS = 8


def _numbers(value: Any, path: str) -> Iterator[tuple[str, float]]:
    """Every JSON number in a spec with its dotted path (bools are not numbers)."""
    if isinstance(value, Mapping):
        for key, item in value.items():
            yield from _numbers(item, f"{path}.{key}" if path else str(key))
    elif isinstance(value, list):
        if len(value) > MAX_SPEC_LIST:
            raise ProblemError(f"domain spec {path} has {len(value)} items; at most {MAX_SPEC_LIST}")
        for i, item in enumerate(value):
            yield from _numbers(item, f"{path}[{i}]")
    elif isinstance(value, float):
        yield path, value


def _checked(value: Any, name: str) -> float:
    """``value`` as a float within +-MAX_COORDINATE_M (JSON numbers are finite already)."""
    if type(value) not in (int, float) or not abs(value) <= MAX_COORDINATE_M:
        raise ProblemError(f"domain spec {name} must be a number within +-{MAX_COORDINATE_M:g}, got {value!r:.60}")
    return float(value)


def _number(spec: Mapping[str, Any], key: str, default: float, what: str) -> float:
    """``spec[key]`` (``default`` when absent) as a float within +-MAX_COORDINATE_M."""
    return _checked(spec.get(key, default), f"{what}.{key}")


def _positive(spec: Mapping[str, Any], key: str, default: float, what: str) -> float:
    value = _number(spec, key, default, what)
    if not value > 0:
        raise ProblemError(f"domain spec {what}.{key} must be positive, got {value!r}")
    return value


def _pair(spec: Mapping[str, Any], key: str, default: tuple[float, float], what: str) -> tuple[float, float]:
    value = spec.get(key, list(default))
    if not isinstance(value, list) or len(value) != 2:
        raise ProblemError(f"domain spec {what}.{key} must be a pair of numbers, got {value!r:.60}")
    return _checked(value[0], f"{what}.{key}[0]"), _checked(value[1], f"{what}.{key}[1]")


def _count(lo: float, hi: float, spacing: float) -> int:
    """Grid points of ``spacing`` in [lo, hi] (at least 1)."""
    return max(1, math.floor(abs(hi - lo) / spacing) + 1)


def _budget(value: float, limit: float, what: str) -> None:
    if not value <= limit:
        raise ProblemError(f"domain spec {what}: about {value:.3g}; at most {limit:.3g} are built")


def _helicopter(spec: Mapping[str, Any], graph: _Stored) -> None:
    lattice = spec.get("lattice") or {}
    if not isinstance(lattice, Mapping):
        raise ProblemError("domain spec lattice must be an object")
    what = "lattice"
    x0, x1 = _pair(lattice, "x_range", (0.0, 700.0), what)
    y0, y1 = _pair(lattice, "y_range", (-250.0, 250.0), what)
    _pair(lattice, "start", (0.0, 0.0), what)
    _pair(lattice, "goal", (700.0, 0.0), what)
    spacing = _positive(lattice, "xy_spacing", 50.0, what)
    radius = _positive(lattice, "turning_radius", 100.0, what)
    sample = _positive(lattice, "sample_spacing", 5.0, what)
    levels = lattice.get("z_levels", [40.0, 65.0, 90.0])
    if not isinstance(levels, list) or not levels:
        raise ProblemError("domain spec lattice.z_levels must be a non-empty list of numbers")
    for i, level in enumerate(levels):
        _checked(level, f"{what}.z_levels[{i}]")
    states = _count(x0, x1, spacing) * _count(y0, y1, spacing) * len(levels) * _HEADINGS
    _budget(states, MAX_LATTICE_STATES, "lattice states (x cells x y cells x levels x 8 headings)")
    from drd_planner.domains.helicopter_lattice import LatticeParams

    defaults = LatticeParams()
    prims = []
    for key in ("axis_primitives", "diagonal_primitives"):
        value = lattice.get(key, [list(p) for p in getattr(defaults, key)])
        if not isinstance(value, list) or not all(
            isinstance(p, list) and len(p) == 3 and all(type(v) is int for v in p) for p in value
        ):
            raise ProblemError(f"domain spec lattice.{key} must be a list of [dx, dy, dheading] integer triples")
        prims.append(value)
    climbs = 1 if lattice.get("climb", "straight") == "none" else 3
    _budget(states * max(len(p) for p in prims) * climbs, MAX_LATTICE_CANDIDATE_EDGES, "lattice candidate edges")
    # Per edge, a loose bound: a Dubins primitive without a loop is at most its straight distance plus a
    # few turning circles. Over all stored edges, the typical length: about its straight distance.
    straight = max(math.hypot(p[0], p[1]) * spacing for p in prims[0] + prims[1])
    _budget(
        (straight + 10.0 * radius) / sample + 1,
        MAX_SAMPLES_PER_EDGE,
        "trajectory samples per edge (longest primitive / sample_spacing)",
    )
    _budget(
        graph.num_edges * (1.5 * straight / sample + 2),
        MAX_TRAJECTORY_SAMPLES,
        "trajectory samples over the stored edges",
    )
    for key, default in (
        ("vehicle_radius", 5.0),
        ("margin", 2.0),
        ("terrain_cell", 10.0),
        ("world_margin", 100.0),
    ):
        _number(spec, key, default, "helicopter")


def _se2(spec: Mapping[str, Any], graph: _Stored) -> None:
    what = "se2"
    spacing = _positive(spec, "spacing", 0.05, what)
    radius = _positive(spec, "turning_radius", 0.099, what)
    waypoint = _positive(spec, "waypoint_spacing", 0.01, what)
    bounds = spec.get("bounds", [0.0, 0.0, 1.0, 1.0])
    if not isinstance(bounds, list) or len(bounds) != 4:
        raise ProblemError("domain spec se2.bounds must be [xmin, ymin, xmax, ymax]")
    b = [_checked(v, f"se2.bounds[{i}]") for i, v in enumerate(bounds)]
    states = _count(b[0], b[2], spacing) * _count(b[1], b[3], spacing) * _HEADINGS
    _budget(states, MAX_LATTICE_STATES, "lattice states (x cells x y cells x 8 headings)")
    _budget((3.0 * spacing + 10.0 * radius) / waypoint + 1, MAX_SAMPLES_PER_EDGE, "waypoints per edge")
    _budget(
        graph.num_edges * (1.5 * 3.0 * spacing / waypoint + 2),
        MAX_TRAJECTORY_SAMPLES,
        "waypoints over the stored edges",
    )


def _robot_file(spec: Mapping[str, Any], key: str) -> None:
    """A robot file named by the spec: a path string; when it exists, a regular file of bounded size.

    A missing file is left to the domain, which says it cannot read it; a device such as ``/dev/zero``
    or a pipe would be read forever.
    """
    value = spec.get(key)
    if value is None:
        return
    if not isinstance(value, str) or not 0 < len(value) <= 4096 or "\x00" in value:
        raise ProblemError(f"domain spec arm.{key} must be a file path, got {value!r:.60}")
    path = Path(value)
    try:
        info = path.stat()
    except OSError:
        return
    if not stat.S_ISREG(info.st_mode):
        raise ProblemError(f"domain spec arm.{key} {value!r:.80} is not a regular file")
    if info.st_size > MAX_ROBOT_FILE_BYTES:
        raise ProblemError(
            f"domain spec arm.{key} {value!r:.80} has {info.st_size} bytes; at most {MAX_ROBOT_FILE_BYTES}"
        )


def _arm(spec: Mapping[str, Any], graph: _Stored) -> None:
    for key in ("urdf_path", "sphere_urdf_path", "srdf_path"):
        _robot_file(spec, key)
    samples, k = spec.get("num_samples", 600), spec.get("k", 8)
    if type(samples) is not int or not 0 <= samples <= MAX_ROADMAP_SAMPLES:
        raise ProblemError(f"domain spec arm.num_samples must be an integer in [0, {MAX_ROADMAP_SAMPLES}]")
    if type(k) is not int or not 1 <= k <= MAX_ROADMAP_NEIGHBOURS:
        raise ProblemError(f"domain spec arm.k must be an integer in [1, {MAX_ROADMAP_NEIGHBOURS}]")
    resolution = _positive(spec, "resolution", 0.05, "arm")
    # Joint-space roadmap edges are at most about 2 pi long per joint; the shipped ones reach 3.4 rad.
    _budget(
        2.0 * math.pi / resolution + 1,
        MAX_SAMPLES_PER_EDGE,
        "collision-check samples per edge (2 pi / resolution)",
    )
    candidates = samples * k
    _budget(candidates, MAX_LATTICE_CANDIDATE_EDGES, "roadmap candidate edges (num_samples x k)")
    _budget(
        max(candidates, graph.num_edges) * (graph.mean_edge_length / resolution + 1),
        MAX_TRAJECTORY_SAMPLES,
        "collision-check samples over the roadmap's edges (mean stored edge length / resolution)",
    )


def _planar(spec: Mapping[str, Any], graph: _Stored) -> None:
    n = spec.get("num_vertices", 100)
    if type(n) is not int or not 2 <= n <= MAX_VERTICES:
        raise ProblemError(f"domain spec planar.num_vertices must be an integer in [2, {MAX_VERTICES}]")
    eta = _positive(spec, "eta", 1.0, "planar")
    # The random geometric graph joins points closer than r = 2 eta sqrt(1.5 / pi) sqrt(log N / N).
    radius = 2.0 * eta * math.sqrt(1.5 / math.pi) * math.sqrt(math.log(n) / n)
    pairs = n * (n - 1) / 2 * min(1.0, math.pi * radius * radius)
    _budget(pairs, MAX_LATTICE_CANDIDATE_EDGES, "random geometric graph edges")


_CHECKS: dict[str, Callable[[Mapping[str, Any], _Stored], None]] = {
    "helicopter": _helicopter,
    "se2": _se2,
    "arm": _arm,
    "planar": _planar,
}


class _Stored(NamedTuple):
    """What the stored graph tells about the size of what the spec must rebuild."""

    num_edges: int
    mean_edge_length: float


def check_domain_spec(domain: str, spec: Any, *, num_edges: int, mean_edge_length: float) -> None:
    """Refuse a spec whose numbers are not finite and bounded, or that would build beyond the budgets.

    Args:
        domain: the domain name stored with the spec.
        spec: the stored spec (None or absent: nothing to check; the session then refuses the file).
        num_edges: E of the stored graph (the rebuilt graph must equal it).
        mean_edge_length: the stored graph's mean edge length (finite; checked before).

    Raises:
        ProblemError: what is out of bounds, with the limit.
    """
    if spec is None:
        return
    if not isinstance(spec, Mapping):
        raise ProblemError(f"the domain spec must be an object, got {type(spec).__name__}")
    for path, value in _numbers(spec, ""):
        if not abs(value) <= MAX_COORDINATE_M:
            raise ProblemError(f"domain spec {path} is {value!r}; numbers must lie within +-{MAX_COORDINATE_M:g}")
    check = _CHECKS.get(domain)
    if check is not None:
        check(spec, _Stored(num_edges, mean_edge_length))
