"""Reading a file whose size is looked at before it is read, with one error line for each way it can fail.

Every file a user hands the planner (a site file, a GeoJSON, a MoveIt YAML, a scene) is read through
:func:`read_bounded`: not a regular file (a pipe, a device, a folder), larger than the caller's limit (refused
from its size, before a byte is read), unreadable, or grown past the limit while it was read, each is one error
of the caller's own type.
"""

from __future__ import annotations

import os
import stat

from drd_planner.exceptions import DrdError

__all__ = ["read_bounded", "read_bounded_text"]


def read_bounded(
    path: str | os.PathLike[str], max_bytes: int, label: str, error: type[DrdError], *, hint: str = ""
) -> bytes:
    """The bytes of the regular file ``path`` when it has at most ``max_bytes``.

    Args:
        path: the file.
        max_bytes: the most bytes read.
        label: names the file in the error (e.g. ``"GeoJSON /x/zones.geojson"``).
        error: the error type raised.
        hint: appended to the too-large message (e.g. how to make the file smaller).

    Raises:
        error: not a regular file, larger than ``max_bytes``, or unreadable.
    """
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            raise error(f"cannot read {label}: not a regular file")
        if info.st_size > max_bytes:
            raise error(f"{label} has {info.st_size} bytes; at most {max_bytes} are read{hint}")
        with open(path, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as exc:
        raise error(f"cannot read {label}: {exc.strerror or exc}") from None
    if len(data) > max_bytes:  # it grew after its size was looked at
        raise error(f"{label} has more than {max_bytes} bytes")
    return data


def read_bounded_text(
    path: str | os.PathLike[str], max_bytes: int, label: str, error: type[DrdError], *, hint: str = ""
) -> str:
    """:func:`read_bounded`, decoded as UTF-8 (not UTF-8: one ``error`` too)."""
    data = read_bounded(path, max_bytes, label, error, hint=hint)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"cannot read {label}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None
