"""Reading ``.npz`` files that may have been crafted by an attacker: bounded, pickle-free, one clear error.

The checksums of drd_planner's files (:mod:`drd_planner.data.npz_format`) catch accidents, not attacks:
whoever edits a file can recompute them. So everything here is checked *before* it costs memory or time:

- the file: a regular file (not a directory, device or pipe) of at most :data:`MAX_FILE_BYTES` that starts
  like a zip archive (otherwise the message says what it is instead: text, a lone ``.npy`` array, ...);
- the zip directory: at most :data:`MAX_CENTRAL_DIRECTORY_BYTES` and :data:`MAX_MEMBERS` entries, read from
  the end record before :mod:`zipfile` parses it;
- every member, from its :class:`zipfile.ZipInfo` before a byte is inflated: a plainly named ``.npy``,
  not encrypted, stored or deflated, at most :data:`MAX_MEMBER_BYTES` uncompressed, all of them at most
  :data:`MAX_TOTAL_BYTES`, and a declared size at most :data:`MAX_COMPRESSION_RATIO` times its
  compressed size;
- every array, from its ``.npy`` header before it is allocated: a plain boolean or numeric dtype (never an
  object dtype; pickles are never loaded) whose shape accounts for exactly the member's declared bytes;
- the JSON header: at most :data:`MAX_HEADER_BYTES`, nested at most :data:`MAX_JSON_DEPTH` deep, no
  ``NaN`` or ``Infinity``, no number that overflows a float, no integer beyond :data:`MAX_JSON_INT`.

Anything else that still goes wrong inside :mod:`zipfile`, :mod:`zlib` or NumPy (a corrupt member, a
wrong CRC, an encrypted member, even a :class:`MemoryError`) is turned into the caller's error type by
:func:`refusing`, the last line of defence at each loader's boundary.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import re
import stat
import struct
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from drd_planner.exceptions import DrdError

__all__ = [
    "DEFAULT_LIMITS",
    "MAX_CENTRAL_DIRECTORY_BYTES",
    "MAX_COMPRESSION_RATIO",
    "MAX_FILE_BYTES",
    "MAX_HEADER_BYTES",
    "MAX_JSON_DEPTH",
    "MAX_JSON_INT",
    "MAX_MEMBERS",
    "MAX_MEMBER_BYTES",
    "MAX_TOTAL_BYTES",
    "NpzLimits",
    "check_source",
    "parse_json_header",
    "read_npz_arrays",
    "refusing",
    "short",
]

_MIB = 1 << 20

MAX_FILE_BYTES = 256 * _MIB
"""Largest file read at all (bytes on disk). The shipped trees are 81 KiB-1.1 MiB, the datasets 0.1-1.3 MiB."""

MAX_MEMBER_BYTES = 128 * _MIB
"""Largest uncompressed ``.npy`` member. The largest shipped member is 6.8 MiB (``heli_lines``'s packed
training outcomes, 2700 worlds x 20 999 edges; its dataset's are 7.5 MiB); 128 MiB holds, for example, the
packed outcomes of 10 000 worlds over 100 000 edges."""

MAX_TOTAL_BYTES = 256 * _MIB
"""Largest sum of the uncompressed members of one file (the shipped files hold 0.2-8.4 MiB)."""

MAX_MEMBERS = 4096
"""Most members (arrays) in one file: a prior file holds 7 + about 11 per precomputed tree."""

MAX_CENTRAL_DIRECTORY_BYTES = 4 * _MIB
"""Largest zip central directory, checked before :mod:`zipfile` parses it (about 100 bytes per member)."""

MAX_COMPRESSION_RATIO = 1100.0
"""Largest declared uncompressed/compressed size of a member. Deflate cannot compress by more than
about 1032:1, so a member claiming more lies about its size (the shipped files reach 480:1: ``heli_lines``'s
``costs``, 20 999 equal edge costs)."""

MAX_HEADER_BYTES = 4 * _MIB
"""Largest JSON header (the shipped headers have 3-46 KiB)."""

MAX_JSON_DEPTH = 64
"""Deepest nesting of JSON arrays and objects in a header (the shipped headers nest 7 deep)."""

MAX_JSON_INT = 2**64 - 1
"""Largest magnitude of a JSON integer (seeds are below 2**63; the parser never builds huge ints)."""

_MAX_INT_DIGITS = len(str(MAX_JSON_INT))
_CHUNK_BYTES = 1 << 24
_MAX_NPY_HEADER_BYTES = 10_000  # numpy's own limit, checked here before the header is read
_NAME = re.compile(r"[A-Za-z0-9_]{1,128}")
_PLAIN_KINDS = "biuf"
_NPY_PREAMBLE_BYTES = 4096  # magic, version and the .npy header of the JSON header array
_ZIP_LOCAL = b"PK\x03\x04"
_ZIP_END = b"PK\x05\x06"
_ZIP64_LOCATOR = b"PK\x06\x07"
_END_RECORD = struct.Struct("<4s4H2LH")
_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)
_NOT_BRACKET = re.compile(r"[^\[\]{}]")


@dataclass(frozen=True)
class NpzLimits:
    """The limits applied by :func:`read_npz_arrays` and :func:`parse_json_header` (defaults: the constants)."""

    file_bytes: int = MAX_FILE_BYTES
    member_bytes: int = MAX_MEMBER_BYTES
    total_bytes: int = MAX_TOTAL_BYTES
    members: int = MAX_MEMBERS
    central_directory_bytes: int = MAX_CENTRAL_DIRECTORY_BYTES
    compression_ratio: float = MAX_COMPRESSION_RATIO
    header_bytes: int = MAX_HEADER_BYTES
    json_depth: int = MAX_JSON_DEPTH
    json_int: int = MAX_JSON_INT


DEFAULT_LIMITS = NpzLimits()


def short(value: object, limit: int = 160) -> str:
    """``str(value)`` on one line, cut to ``limit`` characters (error texts never echo large inputs)."""
    text = " ".join(str(value).split())
    return text if len(text) <= limit else f"{text[: limit - 3]}..."


@contextlib.contextmanager
def refusing(error: type[DrdError], src: Path, what: str) -> Iterator[None]:
    """Turn every exception but ``error`` raised inside into one ``error`` naming ``src``.

    The last line of defence of a loader: checks come first, this catches what they missed (a
    :class:`RecursionError`, a :class:`MemoryError`, a ``zlib.error``, ...). Other :class:`DrdError`
    types keep their message, prefixed with the file.
    """
    try:
        yield
    except error:
        raise
    except DrdError as exc:
        raise error(f"{src} is inconsistent: {short(exc, 400)}") from exc
    except MemoryError as exc:
        raise error(f"{src} is not a readable {what}: reading it needs more memory than is available") from exc
    except RecursionError as exc:
        raise error(f"{src} is not a readable {what}: its contents are nested too deeply") from exc
    except Exception as exc:
        raise error(f"{src} is not a readable {what} ({_reason(exc)})") from exc


def _reason(exc: BaseException) -> str:
    """``kind: message`` of an unexpected exception, short, and never numpy's advice to load pickles."""
    text = short(exc)
    if "pickle" in text.lower():
        text = "unreadable .npy data"
    return f"{_kind(exc)}: {text}"


def _kind(exc: BaseException) -> str:
    """The exception's class name, with its module unless built in (``zlib.error``, ``BadZipFile``)."""
    cls = type(exc)
    return cls.__name__ if cls.__module__ in ("builtins", "zipfile") else f"{cls.__module__}.{cls.__name__}"


def _describe(head: bytes, size: int) -> str:
    """What a file that is not a zip archive looks like, from its first bytes."""
    if size == 0:
        return "is empty"
    if head.startswith(b"\x93NUMPY"):
        return "is a single .npy array"
    if head.startswith(b"\x1f\x8b"):
        return "is gzip-compressed data"
    if head.startswith(b"\x89HDF") or head.startswith(b"MATLAB"):
        return "is an HDF5 or MATLAB file"
    text = head.decode("utf-8", errors="replace").rstrip("\ufffd")
    if text and all(c.isprintable() or c in "\r\n\t" for c in text):
        return f"holds text starting {short(text, 40)!r}"
    return f"starts with the bytes {head[:8].hex(' ')}"


def check_source(path: str | Path, *, error: type[DrdError], what: str, limits: NpzLimits = DEFAULT_LIMITS) -> Path:
    """``path`` as a :class:`Path` once it is known to be a regular zip file within the size limit.

    Raises:
        error: missing, a directory or special file, too large, or not a zip archive (the message
            says what was found instead).
    """
    src = Path(path)
    try:
        info = src.stat()
    except (FileNotFoundError, NotADirectoryError):
        raise error(f"{what} not found: {src}") from None
    except OSError as exc:
        raise error(f"{src}: cannot read the {what} ({short(exc)})") from exc
    if stat.S_ISDIR(info.st_mode):
        raise error(f"{src} is a directory, not a {what}")
    if not stat.S_ISREG(info.st_mode):
        raise error(f"{src} is not a regular file (a device, pipe or socket), not a {what}")
    if info.st_size > limits.file_bytes:
        raise error(f"{src} has {info.st_size} bytes; a {what} may have at most {limits.file_bytes}")
    try:
        with src.open("rb") as fh:
            head = fh.read(64)
    except OSError as exc:
        raise error(f"{src}: cannot read the {what} ({short(exc)})") from exc
    if not head.startswith((_ZIP_LOCAL, _ZIP_END)):
        raise error(
            f"{src} is not a readable {what}: a drd_planner {what} is an .npz (zip) archive of arrays, "
            f"but this file {_describe(head, info.st_size)}"
        )
    return src


def _check_end_record(src: Path, error: type[DrdError], what: str, limits: NpzLimits) -> None:
    """Refuse a zip whose end record announces too many members or too large a directory."""
    size = src.stat().st_size
    with src.open("rb") as fh:
        tail_size = min(size, _END_RECORD.size + 0xFFFF)
        fh.seek(size - tail_size)
        tail = fh.read(tail_size)
    pos = tail.rfind(_ZIP_END)
    if pos < 0 or len(tail) - pos < _END_RECORD.size:
        return  # zipfile refuses it as "not a zip file"
    _, _, _, _, entries, directory_bytes, _, _ = _END_RECORD.unpack_from(tail, pos)
    if pos >= 20 and tail[pos - 20 : pos - 16] == _ZIP64_LOCATOR:
        raise error(f"{src} is not a readable {what}: it has a ZIP64 end record, which no file within the limits needs")
    if entries > limits.members or directory_bytes > limits.central_directory_bytes:
        raise error(
            f"{src} is not a readable {what}: its zip directory lists {entries} members in {directory_bytes} "
            f"bytes (at most {limits.members} members and {limits.central_directory_bytes} bytes)"
        )


def _member_infos(
    zf: zipfile.ZipFile, src: Path, error: type[DrdError], what: str, limits: NpzLimits
) -> dict[str, zipfile.ZipInfo]:
    """Array name -> ZipInfo of every member, each checked from its directory entry alone."""
    infos = zf.infolist()
    if len(infos) > limits.members:
        raise error(f"{src} is not a readable {what}: {len(infos)} members (at most {limits.members})")
    out: dict[str, zipfile.ZipInfo] = {}
    total = 0
    for info in infos:
        name = info.filename
        key = name[:-4] if name.endswith(".npy") else ""
        if not _NAME.fullmatch(key):
            raise error(f"{src} is not a readable {what}: member {short(name, 60)!r} is not a plainly named .npy array")
        if key in out:
            raise error(f"{src} is not a readable {what}: member {name!r} appears twice")
        if info.flag_bits & 0x1:
            raise error(f"{src} is not a readable {what}: member {name!r} is encrypted")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise error(
                f"{src} is not a readable {what}: member {name!r} uses zip compression method "
                f"{info.compress_type} (only stored and deflated members are read)"
            )
        if info.file_size > limits.member_bytes:
            raise error(
                f"{src} is not a readable {what}: member {name!r} unpacks to {info.file_size} bytes "
                f"(at most {limits.member_bytes})"
            )
        stored = info.compress_type == zipfile.ZIP_STORED
        if (stored and info.compress_size != info.file_size) or (
            info.file_size > limits.compression_ratio * max(info.compress_size, 1)
        ):
            raise error(
                f"{src} is not a readable {what}: member {name!r} claims {info.file_size} bytes from "
                f"{info.compress_size} compressed (a zip bomb or a corrupt directory)"
            )
        if key == "header" and info.file_size > limits.header_bytes + _NPY_PREAMBLE_BYTES:
            raise error(
                f"{src} is not a readable {what}: its header unpacks to {info.file_size} bytes "
                f"(at most {limits.header_bytes})"
            )
        total += info.file_size
        if total > limits.total_bytes:
            raise error(f"{src} is not a readable {what}: its members unpack to more than {limits.total_bytes} bytes")
        out[key] = info
    return out


def _read_member(
    zf: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, src: Path, error: type[DrdError], what: str
) -> npt.NDArray[Any]:
    """One array, its shape and dtype checked against the member's declared size before allocation."""
    fmt = np.lib.format
    with zf.open(info) as fh:
        version = fmt.read_magic(fh)
        if version not in ((1, 0), (2, 0)):
            raise error(f"{src} is not a readable {what}: array {key!r} has .npy format version {version}")
        length_field = fh.read(2 if version == (1, 0) else 4)
        header_bytes = int.from_bytes(length_field, "little")
        if header_bytes > _MAX_NPY_HEADER_BYTES:  # numpy would read it all, then advise pickles
            raise error(
                f"{src} is not a readable {what}: array {key!r} has a .npy header of {header_bytes} bytes "
                f"(at most {_MAX_NPY_HEADER_BYTES})"
            )
        preamble = length_field + fh.read(header_bytes)
        read_header = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
        shape, fortran, dtype = read_header(io.BytesIO(preamble))
        if dtype.hasobject or dtype.fields is not None or dtype.subdtype is not None or dtype.kind not in _PLAIN_KINDS:
            raise error(
                f"{src} is not a readable {what}: array {key!r} has dtype {short(dtype, 60)} "
                "(only plain boolean and numeric arrays are read; Python objects never are)"
            )
        nbytes = math.prod(shape) * dtype.itemsize
        held = info.file_size - fmt.MAGIC_LEN - len(preamble)
        if nbytes != held:
            raise error(
                f"{src} is not a readable {what}: array {key!r} declares shape {short(shape, 60)} "
                f"({nbytes} bytes) but its member holds {held} bytes"
            )
        buffer = bytearray(nbytes)
        got = 0
        while got < nbytes:
            chunk = fh.read(min(_CHUNK_BYTES, nbytes - got))
            if not chunk:
                break
            buffer[got : got + len(chunk)] = chunk
            got += len(chunk)
        if got != nbytes or fh.read(1):
            raise error(f"{src} is not a readable {what}: array {key!r} is truncated or has trailing bytes")
    arr = np.frombuffer(buffer, dtype=dtype)
    return arr.reshape(shape, order="F" if fortran else "C")


def read_npz_arrays(
    path: str | Path,
    *,
    error: type[DrdError],
    what: str,
    names: tuple[str, ...] | None = None,
    limits: NpzLimits = DEFAULT_LIMITS,
) -> dict[str, npt.NDArray[Any]]:
    """Every array (or only ``names``, those present) of an ``.npz`` file, within ``limits``.

    Raises:
        error: any refusal of :func:`check_source`, a member or array beyond the limits, an object or
            structured dtype, or anything else that fails while reading (via :func:`refusing`).
    """
    src = check_source(path, error=error, what=what, limits=limits)
    with refusing(error, src, what):
        _check_end_record(src, error, what, limits)
        with zipfile.ZipFile(src) as zf:
            infos = _member_infos(zf, src, error, what, limits)
            wanted = infos if names is None else {k: v for k, v in infos.items() if k in names}
            arrays = {}
            for key, info in wanted.items():
                try:
                    arrays[key] = _read_member(zf, info, key, src, error, what)
                except error:
                    raise
                except MemoryError as exc:
                    raise error(
                        f"{src} is not a readable {what}: member {info.filename!r} needs more memory than is available"
                    ) from exc
                except Exception as exc:
                    raise error(
                        f"{src} is not a readable {what}: member {info.filename!r} is corrupt ({_reason(exc)})"
                    ) from exc
            return arrays


class _JsonLimitError(ValueError):
    """A JSON value beyond the header limits."""


def _no_constant(name: str) -> Any:
    raise _JsonLimitError(f"{name} is not a number drd_planner accepts")


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _JsonLimitError(f"the number {short(text, 30)} overflows")
    return value


def json_depth(text: str) -> int:
    """Deepest nesting of arrays and objects in JSON ``text`` (brackets inside strings ignored)."""
    brackets = _NOT_BRACKET.sub("", _STRING.sub("", text))
    if not brackets:
        return 0
    codes = np.frombuffer(brackets.encode("ascii"), dtype=np.uint8)
    steps = np.where((codes == ord("[")) | (codes == ord("{")), 1, -1)
    return int(np.cumsum(steps).max())


def parse_json_header(
    raw: npt.NDArray[Any], *, error: type[DrdError], src: Path, limits: NpzLimits = DEFAULT_LIMITS
) -> Any:
    """The JSON value of a header array (uint8 UTF-8 bytes), parsed within ``limits``.

    Raises:
        error: "the header is corrupt (...)": not bytes, too large, not UTF-8, not JSON, nested too
            deeply, NaN or Infinity, a float that overflows, or an integer beyond ``limits.json_int``.
    """
    if raw.dtype != np.uint8 or raw.ndim != 1:
        raise error(f"{src}: the header is corrupt (not a byte string)")
    if raw.size > limits.header_bytes:
        raise error(f"{src}: the header is corrupt ({raw.size} bytes; at most {limits.header_bytes})")

    def bounded_int(text: str) -> int:
        if len(text.lstrip("-")) > _MAX_INT_DIGITS or abs(int(text)) > limits.json_int:
            raise _JsonLimitError(f"the integer {short(text, 30)} is out of range")
        return int(text)

    try:
        text = raw.tobytes().decode("utf-8")
        depth = json_depth(text)
        if depth > limits.json_depth:
            raise _JsonLimitError(f"JSON nested {depth} deep; at most {limits.json_depth} allowed")
        return json.loads(text, parse_constant=_no_constant, parse_float=_finite_float, parse_int=bounded_int)
    except (ValueError, RecursionError) as exc:  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        raise error(f"{src}: the header is corrupt ({short(exc)})") from exc
