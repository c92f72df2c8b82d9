"""Where shipped files are found: tree files (``heli_wires``) and bags (``heli_wires.mcap``) by name.

A name that is an existing path is used as it is. A bare name is looked up, in order, in the folder
named by an environment variable (``$DRD_TREES``, ``$DRD_BAGS``), the repository's ``trees/`` or
``bags/`` folder (source and editable installs) and ``share/drd_planner/trees`` or ``.../bags`` of an
installed ROS package (colcon).
"""

from __future__ import annotations

import os
from pathlib import Path

from drd_planner.exceptions import DrdError, TreeFileError

__all__ = ["resolve_bag_path", "resolve_tree_path", "shipped_dirs"]

_ENV = {"trees": "DRD_TREES", "bags": "DRD_BAGS"}


def shipped_dirs(kind: str) -> list[Path]:
    """The existing folders searched for a bare ``kind`` name (``"trees"`` or ``"bags"``), in order."""
    dirs: list[Path] = []
    env = os.environ.get(_ENV[kind])
    if env:
        dirs.append(Path(env))
    dirs.append(Path(__file__).resolve().parents[5] / kind)
    try:
        from ament_index_python.packages import (  # type: ignore[import-not-found,unused-ignore]
            PackageNotFoundError,
            get_package_share_directory,
        )

        try:
            dirs.append(Path(get_package_share_directory("drd_planner")) / kind)
        except (PackageNotFoundError, ValueError, OSError):  # not installed, or no AMENT_PREFIX_PATH
            pass
    except ImportError:
        pass
    return [d for d in dirs if d.is_dir()]


def _resolve(name: str, kind: str, suffix: str, error: type[DrdError]) -> Path:
    path = Path(name).expanduser()
    if path.is_file():
        return path
    if path.parent == Path(".") and path.suffix in ("", suffix):
        file_name = path.name if path.suffix else f"{path.name}{suffix}"
        dirs = shipped_dirs(kind)
        for folder in dirs:
            if (folder / file_name).is_file():
                return folder / file_name
        where = ", ".join(str(d) for d in dirs) or f"no {kind} folder exists"
        if path.is_dir():
            raise error(f"{name} is a directory, not a {kind[:-1]} file (and no {file_name} in: {where})")
        raise error(f"{name!r} is neither a file nor {file_name} in: {where}")
    if path.is_dir():
        raise error(f"{name} is a directory, not a {kind[:-1]} file")
    if path.exists():
        raise error(f"{name} is not a regular file (a device, pipe or socket), not a {kind[:-1]} file")
    raise error(f"{kind[:-1]} file {name} does not exist")


def resolve_tree_path(name: str) -> Path:
    """The tree file of ``name``: an existing path, or ``<name>.npz`` in :func:`shipped_dirs` ``("trees")``.

    Raises:
        TreeFileError: nothing found (the message lists where it looked).
    """
    return _resolve(name, "trees", ".npz", TreeFileError)


def resolve_bag_path(name: str) -> Path:
    """The bag of ``name``: an existing path, or ``<name>.mcap`` in :func:`shipped_dirs` ``("bags")``.

    Raises:
        DrdError: nothing found (the message lists where it looked).
    """
    return _resolve(name, "bags", ".mcap", DrdError)
