"""Crafting hostile tree and prior files byte by byte, as an attacker would: checksums recomputed.

Shared by ``test_crafted_files.py`` and ``test_crafted_priors.py``. Zip members are written by hand
(local headers, central directory, end record) so that a member can lie about its size, claim to be
encrypted or hold a corrupt deflate stream; header JSON can carry raw text (deep nesting, huge integers,
``Infinity``) spliced in with the payload checksum a loader that parsed it would compute.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import io
import json
import struct
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from drd_planner.data.npz_format import array_digest
from drd_planner.data.tree_file import load_tree
from drd_planner.exceptions import PriorFileError, TreeFileError
from drd_planner.planner.prior_file import load_prior, load_tree_bundle

REPO = Path(__file__).resolve().parents[2]
Arrays = dict[str, np.ndarray]


def tree_file_of(name: str, folder: Path) -> Path:
    """The shipped prior ``trees/<name>.npz``'s own tree written as a tree file (``drd_planner.tree`` v2)."""
    from drd_planner.data.tree_file import save_tree

    return save_tree(folder / f"{name}_tree.npz", load_tree_bundle(REPO / "trees" / f"{name}.npz"))


MEMORY_BOUND = 48 * 2**20
"""Largest Python/NumPy allocation peak while a zip bomb is refused."""

# --------------------------------------------------------------------------------------------------
# Crafting: zip members written by hand, checksums recomputed
# --------------------------------------------------------------------------------------------------


@dataclass
class Member:
    """One zip member: ``data`` uncompressed; the other fields let it lie about itself."""

    name: str
    data: bytes
    method: int = 8  # deflate
    payload: bytes | None = None  # the member's stored bytes (default: data, deflated when method 8)
    file_size: int | None = None  # declared uncompressed size (default: len(data))
    flags: int = 0
    crc: int | None = None  # default: the CRC-32 of data


def deflate(data: bytes, level: int = 6) -> bytes:
    c = zlib.compressobj(level, zlib.DEFLATED, -15)
    return c.compress(data) + c.flush()


def zip_bytes(members: list[Member]) -> bytes:
    """A zip archive exactly as described: local headers, central directory and end record."""
    out, central = bytearray(), bytearray()
    for m in members:
        payload = m.payload if m.payload is not None else (deflate(m.data) if m.method == 8 else m.data)
        size = len(m.data) if m.file_size is None else m.file_size
        crc = zlib.crc32(m.data) if m.crc is None else m.crc
        name, offset = m.name.encode(), len(out)
        fields = (m.flags, m.method, 0, 0x21, crc, len(payload), size, len(name), 0)
        out += struct.pack("<4s5H3L2H", b"PK\x03\x04", 20, *fields) + name + payload
        central += struct.pack("<4s6H3L5H2L", b"PK\x01\x02", 20, 20, *fields, 0, 0, 0, 0, offset) + name
    end = struct.pack("<4s4H2LH", b"PK\x05\x06", 0, 0, len(members), len(members), len(central), len(out), 0)
    return bytes(out + central + end)


def npy_bytes(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arr, allow_pickle=arr.dtype.hasobject)
    return buf.getvalue()


def npy_head(shape: tuple[int, ...], dtype: str) -> bytes:
    """A .npy preamble and header declaring ``shape`` and ``dtype`` (no data)."""
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": dtype, "fortran_order": False, "shape": shape})
    return buf.getvalue()


def read_trusted(path: Path) -> tuple[dict[str, Any], Arrays]:
    """Header and arrays of a trusted file."""
    with np.load(path, allow_pickle=False) as archive:
        arrays = {k: archive[k] for k in archive.files}
    header = json.loads(arrays.pop("header").tobytes().decode())
    return header, arrays


def sealed_header(header: dict[str, Any], digests: dict[str, str], splice: dict[str, tuple[str, str]]) -> str:
    """The header text with checksums recomputed; ``splice`` replaces placeholder strings by raw JSON.

    Each splice is (text in the file, text ``json.dumps`` gives after parsing it), so that the payload
    checksum is the one a loader that parsed the file would compute.
    """
    header = {k: v for k, v in header.items() if k not in ("array_sha256", "payload_sha256")}
    fields = json.dumps(header, sort_keys=True)
    for placeholder, (_, echoed) in splice.items():
        fields = fields.replace(json.dumps(placeholder), echoed)
    h = hashlib.sha256("".join(f"{k}:{digests[k]};" for k in sorted(digests)).encode())
    h.update(fields.encode())
    text = json.dumps({**header, "array_sha256": digests, "payload_sha256": h.hexdigest()}, sort_keys=True)
    for placeholder, (raw, _) in splice.items():
        text = text.replace(json.dumps(placeholder), raw)
    return text


@dataclass
class Craft:
    """How to make one hostile file from a base header and arrays (checksums recomputed after the edits)."""

    words: tuple[str, ...]
    arrays: Callable[[Arrays], None] | None = None
    header: Callable[[dict[str, Any]], None] | None = None
    splice: dict[str, tuple[str, str]] = field(default_factory=dict)
    members: Callable[[list[Member], dict[str, str]], None] | None = None
    bounded: bool = False  # a bomb: loading must stay under MEMORY_BOUND

    def write(self, base: tuple[dict[str, Any], Arrays], path: Path) -> Path:
        header, arrays = copy.deepcopy(base[0]), {k: v.copy() for k, v in base[1].items()}
        if self.arrays:
            self.arrays(arrays)
        if self.header:
            self.header(header)
        digests = {k: array_digest(k, v) for k, v in arrays.items()}
        members = [Member(f"{k}.npy", npy_bytes(v)) for k, v in arrays.items()]
        if self.members:
            self.members(members, digests)  # may add members and their digests
        text = sealed_header(header, digests, self.splice)
        members.insert(0, Member("header.npy", npy_bytes(np.frombuffer(text.encode(), dtype=np.uint8))))
        path.write_bytes(zip_bytes(members))
        return path


def set_item(name: str, index: Any, value: Any) -> Callable[[Arrays], None]:
    def edit(arrays: Arrays) -> None:
        arrays[name] = np.array(arrays[name])
        arrays[name][index] = value

    return edit


def set_field(keys: tuple[str | int, ...], value: Any) -> Callable[[dict[str, Any]], None]:
    def edit(header: dict[str, Any]) -> None:
        target: Any = header
        for key in keys[:-1]:
            target = target[key]
        target[keys[-1]] = value

    return edit


def edit_member(name: str, **changes: Any) -> Callable[[list[Member], dict[str, str]], None]:
    def edit(members: list[Member], digests: dict[str, str]) -> None:
        (m,) = [m for m in members if m.name == name]
        for key, value in changes.items():
            setattr(m, key, value)

    return edit


def single_edge_paths(prefix: str = "") -> Callable[[Arrays], None]:
    """Every library path replaced by its last edge: it ends at the goal but starts far from the start."""

    def edit(arrays: Arrays) -> None:
        offsets = arrays[f"{prefix}path_offsets"]
        last = arrays[f"{prefix}path_edges"][offsets[1:] - 1]
        lib = np.unique(last)
        cols = np.searchsorted(arrays[f"{prefix}library_edges"], lib)
        if "world_free_bits" in arrays:
            k = arrays["library_edges"].size
            free = np.unpackbits(arrays["world_free_bits"], axis=1, count=k)
            arrays["world_free_bits"] = np.packbits(free[:, cols], axis=1)
        arrays[f"{prefix}path_edges"] = last.astype(np.int64)
        arrays[f"{prefix}path_offsets"] = np.arange(last.size + 1, dtype=np.int64)
        arrays[f"{prefix}library_edges"] = lib.astype(np.int64)
        arrays[f"{prefix}free_fraction"] = np.ascontiguousarray(arrays[f"{prefix}free_fraction"][:, cols])
        arrays.pop(f"{prefix}vertex_paths", None)
        arrays.pop(f"{prefix}vertex_offsets", None)

    return edit


def reverse_path(arrays: Arrays) -> None:
    """Library path 0 flown backwards (goal to start) on the directed lattice."""
    offsets = arrays["path_offsets"]
    edges = np.array(arrays["path_edges"])
    edges[offsets[0] : offsets[1]] = edges[offsets[0] : offsets[1]][::-1]
    arrays["path_edges"] = edges
    del arrays["vertex_paths"], arrays["vertex_offsets"]


def scale_lattice(header: dict[str, Any]) -> None:
    lattice = header["problem_metadata"]["domain_spec"]["lattice"]
    lattice["x_range"] = [0.0, 1e9]
    lattice["goal"] = [1e9, 0.0]


@functools.lru_cache(maxsize=1)
def zeros_bomb() -> tuple[bytes, int, int, str]:
    """(head, declared size, CRC, digest) of an honest 200 MB .npy of float64 zeros, and its 0.2 MB deflate."""
    count = 25_000_000
    head = npy_head((count,), "<f8")
    c = zlib.compressobj(9, zlib.DEFLATED, -15)
    chunks, crc = [c.compress(head)], zlib.crc32(head)
    digest = hashlib.sha256(b"bomb")
    digest.update(b"<f8")
    digest.update(repr((count,)).encode())
    block = bytes(1 << 20)
    left = count * 8
    while left:
        piece = block[: min(left, len(block))]
        chunks.append(c.compress(piece))
        crc = zlib.crc32(piece, crc)
        digest.update(piece)
        left -= len(piece)
    chunks.append(c.flush())
    return b"".join(chunks), len(head) + count * 8, crc, digest.hexdigest()


def add_zeros_bomb(members: list[Member], digests: dict[str, str]) -> None:
    payload, size, crc, digest = zeros_bomb()
    members.append(Member("bomb.npy", b"", payload=payload, file_size=size, crc=crc))
    digests["bomb"] = digest


def add_lying_member(members: list[Member], digests: dict[str, str]) -> None:
    """A member whose zip entry and .npy header claim 3 GiB; it holds 1 KiB."""
    count = 3 * 2**30 // 8
    data = npy_head((count,), "<f8") + bytes(1024)
    members.append(Member("bomb.npy", data, file_size=len(data) - 1024 + count * 8))
    digests["bomb"] = "0" * 64


def shape_lie(members: list[Member], digests: dict[str, str]) -> None:
    """``node_edge``'s .npy header declares 10**12 entries; the member holds its 11 real ones."""
    (m,) = [m for m in members if m.name == "node_edge.npy"]
    real = np.lib.format.read_array(io.BytesIO(m.data))
    m.data = npy_head((10**12,), "<i4") + real.tobytes()


def huge_npy_header(members: list[Member], digests: dict[str, str]) -> None:
    """``costs``' .npy header claims 60 000 bytes (numpy reads it, then suggests trusting pickles)."""
    (m,) = [m for m in members if m.name == "costs.npy"]
    text = b"{'descr': '<f8', 'fortran_order': False, 'shape': (3012,), }"
    m.data = b"\x93NUMPY\x01\x00" + struct.pack("<H", 60_000) + text.ljust(59_999) + b"\n" + bytes(3012 * 8)


def add_text_member(members: list[Member], digests: dict[str, str]) -> None:
    members.append(Member("notes.txt", b"no array here"))
    digests["notes.txt"] = "0" * 64


def add_object_array(members: list[Member], digests: dict[str, str]) -> None:
    payload = np.empty(2, dtype=object)
    payload[:] = ["a", "b"]
    members.append(Member("smuggled.npy", npy_bytes(payload)))
    digests["smuggled"] = array_digest("smuggled", np.zeros(2))


def corrupt_deflate(members: list[Member], digests: dict[str, str]) -> None:
    (m,) = [m for m in members if m.name == "edges.npy"]
    m.payload = b"\xff" * 64  # not a deflate stream (invalid block type)


def refusal(load: Callable[[Path], object], path: Path, error: type[Exception]) -> str:
    """The one-line message of the refusal, which must be exactly of type ``error``."""
    with pytest.raises(error) as info:
        load(path)
    assert type(info.value) is error, f"{type(info.value).__name__}: {info.value}"
    message = str(info.value)
    assert "\n" not in message, message
    assert len(message) < 700, message
    assert path.name in message, message
    assert "allow_pickle" not in message, message
    assert "pickle.load" not in message, message
    return message


LOADERS: dict[str, tuple[Callable[[Path], object], type[Exception]]] = {
    "load_tree": (load_tree, TreeFileError),
    "load_prior": (load_prior, PriorFileError),
    "load_tree_bundle": (load_tree_bundle, PriorFileError),
}
