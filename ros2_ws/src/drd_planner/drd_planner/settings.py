"""Where shared files are found: one settings place for every data path of the package.

Order of lookup, everywhere:

1. an environment variable (``DRD_SHARED_DATA`` for the shared data folder, ``DRD_TREES`` / ``DRD_BAGS`` for
   the shipped priors and bags);
2. the source checkout this package runs from (``<repo>/trees``, ``<repo>/bags``, ``<repo>/../shared/data``);
3. for trees and bags, the installed ROS share directory (``share/drd_planner/<kind>``, via ament_index).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Literal

__all__ = ["ShippedKind", "checkout_root", "shared_data_dir", "shipped_dirs"]

ShippedKind = Literal["trees", "bags"]
"""The kinds of files shipped with the package."""

SHARED_DATA_ENV = "DRD_SHARED_DATA"
_SHIPPED_ENV: dict[str, str] = {"trees": "DRD_TREES", "bags": "DRD_BAGS"}


def checkout_root() -> Path | None:
    """The repository root when this package runs from a source checkout (``ros2_ws/src/drd_planner``), else None."""
    root = Path(__file__).resolve().parents[4]
    return root if (root / "ros2_ws" / "src" / "drd_planner").is_dir() else None


def shared_data_dir() -> Path:
    """The shared data folder: ``$DRD_SHARED_DATA``, else ``<repo>/../shared/data`` (may not exist)."""
    env = os.environ.get(SHARED_DATA_ENV)
    if env:
        return Path(env)
    root = checkout_root()
    base = root.parent if root is not None else Path.cwd()
    return base / "shared" / "data"


def shipped_dirs(kind: ShippedKind) -> list[Path]:
    """The existing folders searched for a bare ``kind`` name (``"trees"`` or ``"bags"``), in lookup order."""
    if kind not in _SHIPPED_ENV:
        raise ValueError(f"kind must be one of {sorted(_SHIPPED_ENV)}, got {kind!r}")
    dirs: list[Path] = []
    env = os.environ.get(_SHIPPED_ENV[kind])
    if env:
        dirs.append(Path(env))
    root = checkout_root()
    if root is not None:
        dirs.append(root / kind)
    dirs.extend(_installed_share(kind))
    return [d for d in dirs if d.is_dir()]


def _installed_share(kind: str) -> list[Path]:
    """``share/drd_planner/<kind>`` of a ROS install (empty without ament_index or the package installed)."""
    try:
        from ament_index_python.packages import (  # type: ignore[import-not-found,unused-ignore]
            PackageNotFoundError,
            get_package_share_directory,
        )
    except ImportError:
        return []
    try:
        return [Path(get_package_share_directory("drd_planner")) / kind]
    except (PackageNotFoundError, ValueError, OSError):  # not installed, or no AMENT_PREFIX_PATH
        return []
