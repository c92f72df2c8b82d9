"""Checksummed ``.npz`` containers: plain arrays plus a JSON header, written reproducibly, read safely.

The layout follows the tree file (:mod:`drd_planner.data.tree_file`): a zip of ``.npy`` members, one of
them ``header``, a uint8 array of UTF-8 JSON holding the format name and version, free header fields, a
SHA-256 per array (``array_sha256``) and a SHA-256 over all array digests and header fields
(``payload_sha256``). Reading goes through :mod:`drd_planner.data.safe_npz` (never a pickle, every size checked before
it is allocated), so a crafted file is refused with one clear error and never executes code.

Two extras over ``numpy.savez_compressed``: members carry a fixed timestamp and are written in sorted
order, so equal contents give byte-identical files; and files are written to a temporary name and
renamed, so an interrupted write never leaves a half file under the final name.
"""

from __future__ import annotations

import hashlib
import json
import os
import zipfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.data.safe_npz import (
    DEFAULT_LIMITS,
    NpzLimits,
    parse_json_header,
    read_npz_arrays,
    refusing,
    short,
)
from drd_planner.exceptions import DrdError

__all__ = [
    "NpzFormat",
    "array_digest",
    "building_for_domain",
    "payload_digest",
    "read_checked_npz",
    "write_checked_npz",
]

_ZIP_EPOCH = (1980, 1, 1, 0, 0, 0)
_DIGEST_FIELDS = ("array_sha256", "payload_sha256")


def array_digest(name: str, arr: npt.NDArray[Any]) -> str:
    """SHA-256 (hex) over an array's name, dtype, shape and C-order bytes."""
    h = hashlib.sha256()
    h.update(name.encode())
    h.update(str(arr.dtype.str).encode())
    h.update(repr(tuple(arr.shape)).encode())
    h.update(np.ascontiguousarray(arr).tobytes())
    return h.hexdigest()


def payload_digest(digests: Mapping[str, str], header: Mapping[str, Any]) -> str:
    """SHA-256 (hex) over every array digest and every header field except the digests themselves."""
    h = hashlib.sha256("".join(f"{k}:{digests[k]};" for k in sorted(digests)).encode())
    fields = {k: v for k, v in header.items() if k not in _DIGEST_FIELDS}
    h.update(json.dumps(fields, sort_keys=True).encode())
    return h.hexdigest()


def _json_bytes(obj: Any, error: type[DrdError]) -> bytes:
    try:
        return json.dumps(obj, sort_keys=True, allow_nan=False).encode()
    except (TypeError, ValueError) as exc:
        raise error(f"file header is not JSON-safe: {exc}") from exc


def write_checked_npz(
    path: str | Path,
    *,
    format_name: str,
    format_version: int,
    header: Mapping[str, Any],
    arrays: Mapping[str, npt.NDArray[Any]],
    error: type[DrdError],
) -> Path:
    """Write ``arrays`` and a checksummed JSON header to ``path`` atomically and reproducibly.

    Args:
        path: destination file (its parent folder is created).
        format_name: stored as ``header["format"]``.
        format_version: stored as ``header["format_version"]``.
        header: JSON-safe fields (no NaN or infinity); must not use the keys ``format``,
            ``format_version``, ``array_sha256`` or ``payload_sha256``.
        arrays: name -> numeric array (no object dtype); the name ``header`` is reserved.
        error: exception class raised for unwritable input.

    Returns:
        The path written.
    """
    reserved = {"format", "format_version", *_DIGEST_FIELDS}
    if reserved & set(header) or "header" in arrays:
        raise error(f"header keys {sorted(reserved)} and the array name 'header' are reserved")
    plain = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
    for name, arr in plain.items():
        if arr.dtype.hasobject:
            raise error(f"array {name!r} has an object dtype; only plain numeric arrays can be stored")
    full: dict[str, Any] = {"format": format_name, "format_version": format_version, **header}
    full = json.loads(_json_bytes(full, error))  # exactly what a reader will see
    digests = {k: array_digest(k, v) for k, v in plain.items()}
    full["array_sha256"] = digests
    full["payload_sha256"] = payload_digest(digests, full)
    members = {"header": np.frombuffer(_json_bytes(full, error), dtype=np.uint8), **plain}
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    try:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
            for name in ["header", *sorted(plain)]:
                info = zipfile.ZipInfo(f"{name}.npy", date_time=_ZIP_EPOCH)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                with zf.open(info, "w", force_zip64=True) as fh:
                    np.lib.format.write_array(fh, members[name], allow_pickle=False)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)
    return out


def read_checked_npz(
    path: str | Path,
    *,
    format_name: str,
    format_version: int | tuple[int, ...],
    error: type[DrdError],
    what: str,
    limits: NpzLimits = DEFAULT_LIMITS,
) -> tuple[dict[str, Any], dict[str, npt.NDArray[Any]]]:
    """Read and verify a file written by :func:`write_checked_npz` (or a tree file, same layout).

    Reading goes through :mod:`drd_planner.data.safe_npz`: sizes, shapes and dtypes are checked before
    anything is inflated or allocated, and the JSON header is parsed within limits.

    Args:
        path: the file.
        format_name: the expected ``header["format"]``.
        format_version: the ``header["format_version"]`` accepted, or a tuple of them.
        error: exception class raised on any refusal.
        what: the file kind for messages ("dataset file", ...).
        limits: the size limits (the module constants of :mod:`~drd_planner.data.safe_npz` by default).

    Returns:
        ``(header, arrays)``: the header dict (digests included) and every array but the header.

    Raises:
        error: missing, a directory, unreadable, beyond the limits, not this format, another version,
            or a checksum mismatch (the message names the file and says which); never anything else.
    """
    versions = (format_version,) if isinstance(format_version, int) else format_version
    contents = read_npz_arrays(path, error=error, what=what, limits=limits)
    src = Path(path)
    with refusing(error, src, what):
        if "header" not in contents:
            raise error(f"{src} has no header: not a drd_planner {what}")
        header = parse_json_header(contents.pop("header"), error=error, src=src, limits=limits)
        if not isinstance(header, dict) or header.get("format") != format_name:
            raise error(f"{src} is not a drd_planner {what} (format {format_name!r} expected)")
        version = header.get("format_version")
        if type(version) is not int or version not in versions:
            readable = ", ".join(str(v) for v in versions)
            raise error(
                f"{src} has {what} format version {short(version, 40)}; this build reads "
                f"{'version' if len(versions) == 1 else 'versions'} {readable}"
            )
        digests = header.get("array_sha256")
        if not isinstance(digests, dict) or set(digests) != set(contents):
            raise error(f"{src} is corrupt: its arrays do not match the header's list")
        for name, arr in contents.items():
            if array_digest(name, arr) != digests[name]:
                raise error(f"{src} is corrupt: checksum mismatch in array {name!r}")
        if payload_digest(digests, header) != header.get("payload_sha256"):
            raise error(f"{src} is corrupt: payload checksum mismatch (header fields were changed)")
    return header, contents


@contextmanager
def building_for_domain(
    src: Path, header: Mapping[str, Any], *, error: type[DrdError], expected_domain: str | None
) -> Iterator[None]:
    """Around building the object a verified file holds: its header's ``domain`` checked first.

    Args:
        src: the file (for messages).
        header: its verified header.
        error: exception class raised on any refusal.
        expected_domain: the domain the file must be built for (None: any).

    Raises:
        error: built for another domain (on entry), or the block raised a ``DrdError``, ``KeyError``,
            ``TypeError``, ``ValueError``, ``IndexError`` or ``OverflowError`` (the file is inconsistent);
            the message names the file.
    """
    domain = header.get("domain")
    if expected_domain is not None and domain != expected_domain:
        raise error(f"{src} was built for domain {short(domain, 60)!r}, not {expected_domain!r}")
    try:
        yield
    except (DrdError, KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
        raise error(f"{src} is inconsistent: {short(exc, 400)}") from exc


@dataclass(frozen=True)
class NpzFormat:
    """One file format in this layout: its name, the version written and read, its error and its kind.

    Attributes:
        name: ``header["format"]``.
        version: the version written (and read, unless ``readable`` is given).
        error: the exception class of every refusal.
        what: the file kind for messages ("dataset file", ...).
        readable: the versions read (empty: ``version`` only).
    """

    name: str
    version: int
    error: type[DrdError]
    what: str
    readable: tuple[int, ...] = ()

    def write(self, path: str | Path, header: Mapping[str, Any], arrays: Mapping[str, npt.NDArray[Any]]) -> Path:
        """:func:`write_checked_npz` in this format; returns the path written."""
        return write_checked_npz(
            path,
            format_name=self.name,
            format_version=self.version,
            header=header,
            arrays=arrays,
            error=self.error,
        )

    def read(
        self, path: str | Path, limits: NpzLimits = DEFAULT_LIMITS
    ) -> tuple[dict[str, Any], dict[str, npt.NDArray[Any]]]:
        """:func:`read_checked_npz` in this format: ``(header, arrays)``."""
        versions = self.readable or (self.version,)
        return read_checked_npz(
            path,
            format_name=self.name,
            format_version=versions,
            error=self.error,
            what=self.what,
            limits=limits,
        )
