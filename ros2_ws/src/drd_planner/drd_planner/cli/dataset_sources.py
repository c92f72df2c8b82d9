"""The world-source flags of ``drd build-dataset`` and ``--print-spec``.

:func:`add_source_arguments` adds the flags; :func:`source_from_args` checks their combinations (argparse-style
errors through the parser's ``error``: a usage line and exit status 2) and gives the recipe's source request;
:func:`print_spec` prints a domain's spec keys; :func:`source_summary` describes a built dataset's source in one
line. The flags:

==================================== ================================================================================
``--scenes DIR``                     one world per MoveIt PlanningScene ``scene*.yaml`` (sorted by name); the
                                     ``request*.yaml`` start and goal states become graph vertices
``--no-requests``                    with ``--scenes``: leave the requests out
``--bags FILE [FILE ...]``           one world per map snapshot of recorded rosbag2 MCAP bags
``--frame FRAME``                    with ``--bags``: the planning frame (default: the first bag's map frame)
``--terrain FILE``                   the ``terrain`` world model on an ESRI ASCII grid (worlds from seeds)
``--site X,Y``                       with ``--terrain``: centre of the operating area, in the grid's coordinates
``--site-jitter M``                  with ``--terrain``: metres a crop's centre may move from the site per axis
``--crop {random,as-is}``            with ``--terrain``: random rotation, mirror, scale and relief, or north up
                                     at the grid's own cell size and heights
``--crop-scale M|LO,HI``             with ``--terrain``: metres per source cell
``--site-file FILE``                 the ``corridors`` world model over a real site from GIS files (a site file:
                                     DEM, OSM power lines, GeoJSON no-fly zones); ``--domain`` defaults to
                                     ``helicopter``, ``--worlds`` and ``--seed`` to the site file's ``dataset``
``--print-spec``                     print every spec key of ``--domain`` (default, unit, meaning) and exit
==================================== ================================================================================
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, NoReturn

from drd_planner.cli.argtypes import bounded_float
from drd_planner.data.world_sources import (
    CROP_CHOICES,
    MapBags,
    SceneFolder,
    SiteFile,
    TerrainFile,
    WorldSourceRequest,
)
from drd_planner.exceptions import DatasetError

__all__ = [
    "add_source_arguments",
    "check_required",
    "print_spec",
    "site_file_defaults",
    "source_from_args",
    "source_summary",
]

#: Flags that only go with one source: flag -> (its attribute, the source flag it needs).
_SOURCE_OPTIONS: Mapping[str, tuple[str, str]] = {
    "--no-requests": ("no_requests", "scenes"),
    "--frame": ("frame", "bags"),
    "--site": ("site", "terrain"),
    "--site-jitter": ("site_jitter", "terrain"),
    "--crop-scale": ("crop_scale", "terrain"),
}

ErrorFn = Callable[[str], NoReturn]


def _numbers(text: str, count: tuple[int, ...]) -> tuple[float, ...]:
    """Comma-separated finite numbers (as many as one of ``count``)."""
    try:
        values = tuple(float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not comma-separated numbers") from None
    if len(values) not in count or not all(math.isfinite(v) for v in values):
        wanted = " or ".join(str(c) for c in count)
        raise argparse.ArgumentTypeError(f"{text!r}: give {wanted} finite number(s), comma-separated")
    return values


def _pair(text: str) -> tuple[float, float]:
    """``X,Y``."""
    x, y = _numbers(text, (2,))
    return x, y


def _scale(text: str) -> tuple[float, float]:
    """``M`` or ``LO,HI`` metres per cell (> 0, LO <= HI)."""
    values = _numbers(text, (1, 2))
    lo, hi = values[0], values[-1]
    if not 0 < lo <= hi:
        raise argparse.ArgumentTypeError(f"{text!r}: metres per cell must be > 0 (and LO <= HI)")
    return lo, hi


def add_source_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the world-source flags and ``--print-spec`` (see the module docstring)."""
    group = parser.add_argument_group("worlds from files (instead of --world-model)")
    exclusive = group.add_mutually_exclusive_group()
    exclusive.add_argument(
        "--scenes",
        metavar="DIR",
        help="one world per MoveIt PlanningScene scene*.yaml in DIR (sorted by name)",
    )
    exclusive.add_argument(
        "--bags", metavar="FILE", nargs="+", help="one world per map snapshot of these rosbag2 MCAP bags"
    )
    exclusive.add_argument("--terrain", metavar="FILE", help="the terrain world model on this ESRI ASCII grid")
    exclusive.add_argument(
        "--site-file",
        metavar="FILE",
        help="the corridors world model over the real site this site file (drd-site/1 YAML) describes",
    )
    group.add_argument(
        "--no-requests", action="store_true", help="--scenes: do not add the request*.yaml states as vertices"
    )
    group.add_argument("--frame", help="--bags: the planning frame (default: the first bag's map frame)")
    group.add_argument(
        "--site",
        metavar="X,Y",
        type=_pair,
        help="--terrain: operating site in the grid's own coordinates (--site=X,Y when X < 0)",
    )
    group.add_argument(
        "--site-jitter",
        metavar="M",
        type=bounded_float(at_least=0.0),
        help="--terrain: metres a crop's centre may move from the site per axis",
    )
    group.add_argument(
        "--crop",
        choices=CROP_CHOICES,
        default=None,
        help="--terrain: random rotation/mirror/scale/relief (default), or as-is: north up at the grid's "
        "cell size and its own heights",
    )
    group.add_argument("--crop-scale", metavar="M|LO,HI", type=_scale, help="--terrain: metres per source cell")
    parser.add_argument(
        "--print-spec",
        action="store_true",
        help="print every spec key of --domain with its default, unit and meaning, and exit",
    )


def _kind(args: argparse.Namespace) -> str | None:
    """Which source flag was given (None: a seeded build); ``--site-file`` is kind ``site``."""
    for kind in ("scenes", "bags", "terrain"):
        if getattr(args, kind, None):
            return kind
    return "site" if getattr(args, "site_file", None) else None


def site_file_defaults(args: argparse.Namespace) -> None:
    """With ``--site-file``: ``--domain`` helicopter, and ``--worlds`` and ``--seed`` from the site file's ``dataset``.

    Raises:
        SiteFileError: the site file cannot be used.
    """
    if _kind(args) != "site":
        return
    if args.domain is None:
        args.domain = "helicopter"
    if args.worlds is None or args.seed is None:
        from drd_planner.data.site_file import load_site

        site = load_site(args.site_file)
        args.worlds = site.worlds if args.worlds is None else args.worlds
        args.seed = site.seed if args.seed is None else args.seed


def check_required(args: argparse.Namespace, error: ErrorFn) -> None:
    """Refuse a build without the arguments it needs (they are optional only for ``--print-spec``)."""
    kind = _kind(args)
    missing = [flag for flag, attr in (("--seed", "seed"), ("--out", "out")) if getattr(args, attr) is None]
    if hasattr(args, "domain") and args.domain is None and kind != "site":
        missing = ["--domain", *missing]
    if kind is None:
        missing = [
            f for f, a in (("--world-model", "world_model"), ("--worlds", "worlds")) if getattr(args, a) is None
        ] + missing
    elif kind == "terrain" and args.worlds is None:
        missing = ["--worlds", *missing]
    if missing:
        hint = (
            ""
            if kind is not None or args.world_model
            else " (or worlds from files: --scenes, --bags, --terrain or --site-file)"
        )
        error(f"the following arguments are required: {', '.join(missing)}{hint}")


def source_from_args(args: argparse.Namespace, error: ErrorFn) -> WorldSourceRequest | None:
    """The source request of the parsed flags (None: worlds from ``--world-model``).

    Flags of another source, or ``--world-model`` with a file source, are refused through ``error``.
    """
    kind = _kind(args)
    for flag, (attr, needs) in _SOURCE_OPTIONS.items():
        if getattr(args, attr, None) not in (None, False) and kind != needs:
            error(f"{flag} goes with --{needs}")
    if getattr(args, "crop", None) is not None and kind != "terrain":
        error("--crop goes with --terrain")
    if kind is not None and args.world_model is not None:
        flag = "--site-file" if kind == "site" else f"--{kind}"
        error(f"--world-model: not allowed with {flag} (its worlds come from files)")
    if kind == "scenes":
        return SceneFolder(args.scenes, requests=not args.no_requests)
    if kind == "bags":
        return MapBags(tuple(args.bags), frame=args.frame)
    if kind == "site":
        return SiteFile(args.site_file)
    if kind == "terrain":
        return TerrainFile(
            args.terrain,
            site=args.site,
            site_jitter=args.site_jitter,
            crop=args.crop or "random",
            crop_scale=args.crop_scale,
        )
    return None


def print_spec(domain: str) -> int:
    """Print the spec keys of ``domain`` (:func:`drd_planner.domains.spec_docs.spec_help`); exit status 0.

    Raises:
        DatasetError: the spec documentation is not available.
    """
    try:
        from drd_planner.domains.spec_docs import spec_help
    except ImportError as exc:
        raise DatasetError(f"--print-spec: the spec documentation is not available ({exc})") from exc
    print(spec_help(domain))
    return 0


def source_summary(provenance: Mapping[str, Any]) -> str | None:
    """One line on where a dataset's worlds came from (None: a seeded world model)."""
    source = provenance.get("world_source")
    if not isinstance(source, Mapping):
        return None
    kind = source.get("kind")
    if kind == "scenes":
        text = f"worlds: {len(source.get('scenes', []))} scene file(s) of {source.get('folder')}"
        if source.get("requests"):
            text += (
                f"; {len(source['requests'])} request file(s) gave {source.get('request_states', 0)} state(s), "
                f"{source.get('extra_states_added', 0)} added as vertices (start from {source.get('start_from')}, "
                f"goal from {source.get('goal_from')})"
            )
        return text
    if kind == "bags":
        names = ", ".join(Path(str(f.get("path"))).name for f in source.get("files", []))
        return f"worlds: {len(source.get('snapshots', []))} map snapshot(s) of {names} in frame {source.get('frame')!r}"
    if kind == "site":
        lines, zones = len(source.get("lines", [])), len(source.get("zones", []))
        dem = source.get("dem", {})
        return (
            f"worlds: site {source.get('site')!r} ({len(source.get('files', []))} files): corridors model on the DEM "
            f"{dem.get('path')} with {lines} mapped line(s) and {zones} zone(s)"
        )
    if kind == "terrain":
        keys = ", ".join(f"{k}={v}" for k, v in source.get("spec_keys", {}).items())
        return f"worlds: terrain model on {source.get('file', {}).get('path')} ({keys})"
    return f"worlds: {kind}"
