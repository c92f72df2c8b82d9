"""Message construction that works with rclpy's generated classes and rosbags' dataclasses alike.

Reading needs nothing special (both expose the same field names). Building does: rclpy classes take
any subset of fields as keywords and convert types on assignment, while rosbags dataclasses need every
field and plain numpy arrays for numeric sequences. A :class:`MessageFactory` hides the difference::

    msgs = RclpyMessages()                      # or RosbagsMessages(get_typestore(Stores.ROS2_JAZZY))
    point = msgs("geometry_msgs/msg/Point", x=1.0, y=2.0, z=3.0)

Numeric sequences are passed as numpy arrays; ``byte`` fields (``DiagnosticStatus.level``) as ints.
"""

from __future__ import annotations

import array
import importlib
from typing import Any, Protocol

import numpy as np

from drd_msgs_py.exceptions import MessageError

__all__ = ["MessageFactory", "RclpyMessages", "RosbagsMessages", "header"]

_NUMPY_OF = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "uint8": np.uint8,
    "int8": np.int8,
    "uint16": np.uint16,
    "int16": np.int16,
    "uint32": np.uint32,
    "int32": np.int32,
    "uint64": np.uint64,
    "int64": np.int64,
    "float32": np.float32,
    "float64": np.float64,
}
_ARRAY_CODE = {"B": np.uint8, "b": np.int8, "H": np.uint16, "h": np.int16, "I": np.uint32, "i": np.int32}


class MessageFactory(Protocol):
    """Builds a message of ROS type ``pkg/msg/Name`` from keyword fields (missing fields: defaults)."""

    def __call__(self, type_name: str, /, **fields: Any) -> Any:
        """The message."""


def _split(type_name: str) -> tuple[str, str, str]:
    parts = type_name.split("/")
    if len(parts) != 3 or parts[1] not in ("msg", "srv"):
        raise MessageError(f"message type must look like 'pkg/msg/Name', got {type_name!r}")
    return parts[0], parts[1], parts[2]


class RclpyMessages:
    """:class:`MessageFactory` for rclpy's generated message classes (ROS install or PyPI wheels)."""

    def __init__(self) -> None:
        self._classes: dict[str, Any] = {}
        self._fields: dict[str, dict[str, str]] = {}

    def message_class(self, type_name: str) -> Any:
        """The rclpy class of ``type_name`` (imported on first use)."""
        cls = self._classes.get(type_name)
        if cls is None:
            pkg, kind, name = _split(type_name)
            try:
                cls = getattr(importlib.import_module(f"{pkg}.{kind}"), name)
            except (ImportError, AttributeError) as exc:
                raise MessageError(f"no rclpy message class for {type_name}: {exc}") from exc
            self._classes[type_name] = cls
        return cls

    def __call__(self, type_name: str, /, **fields: Any) -> Any:
        """An rclpy message; numpy arrays become ``array.array``, ints for ``byte`` fields bytes."""
        cls = self.message_class(type_name)
        if not fields:
            return cls()
        types = self._fields.get(type_name)
        if types is None:
            types = self._fields[type_name] = dict(cls.get_fields_and_field_types())
        converted: dict[str, Any] = {}
        for key, value in fields.items():
            kind = types.get(key)
            if kind is None:
                raise MessageError(f"{type_name} has no field {key!r}")
            if kind == "octet" and isinstance(value, int):
                value = bytes([value])
            elif isinstance(value, np.ndarray):
                value = _to_array(value, kind)
            converted[key] = value
        return cls(**converted)


def _to_array(value: np.ndarray, kind: str) -> Any:
    """A numpy array as rclpy wants it for a field of ``kind`` (e.g. ``sequence<uint8>``)."""
    codes = {"uint8": "B", "octet": "B", "int8": "b", "uint16": "H", "int16": "h", "uint32": "I"}
    codes |= {"int32": "i", "float": "f", "double": "d", "uint64": "Q", "int64": "q"}
    inner = kind.split("<", 1)[1].split(">", 1)[0].split(",")[0] if "<" in kind else kind.split("[")[0]
    code = codes.get(inner)
    if code is None:
        return value.tolist()
    out = array.array(code)
    out.frombytes(np.ascontiguousarray(value, dtype=np.dtype(code)).tobytes())
    return out


class RosbagsMessages:
    """:class:`MessageFactory` for a rosbags typestore (``get_typestore(Stores.ROS2_JAZZY)``)."""

    def __init__(self, typestore: Any) -> None:
        self._store = typestore

    @property
    def typestore(self) -> Any:
        """The typestore the messages come from."""
        return self._store

    def __call__(self, type_name: str, /, **fields: Any) -> Any:
        """A rosbags dataclass with every field not given set to its zero value."""
        try:
            cls = self._store.types[type_name]
            _, defs = self._store.fielddefs[type_name]
        except KeyError:
            raise MessageError(f"the typestore has no message type {type_name}") from None
        names = {name for name, _ in defs}
        unknown = set(fields) - names
        if unknown:
            raise MessageError(f"{type_name} has no field(s) {sorted(unknown)}")
        values = {}
        for name, desc in defs:
            if name in fields:
                value = fields[name]
                if isinstance(value, array.array):
                    value = np.frombuffer(value.tobytes(), dtype=_ARRAY_CODE.get(value.typecode, np.float64))
                values[name] = value
            else:
                values[name] = self._default(desc)
        return cls(**values)

    def _default(self, desc: Any) -> Any:
        node, detail = desc
        kind = int(node)
        if kind == 1:  # BASE
            base = detail[0]
            if base == "string":
                return ""
            if base == "bool":
                return False
            return 0.0 if base.startswith("float") else 0
        if kind == 2:  # NAME
            return self(detail)
        sub, size = detail  # ARRAY (3) or SEQUENCE (4)
        if int(sub[0]) == 1 and sub[1][0] in _NUMPY_OF:
            return np.zeros(size if kind == 3 else 0, dtype=_NUMPY_OF[sub[1][0]])
        return [self._default(sub) for _ in range(size)] if kind == 3 else []


def header(msgs: MessageFactory, frame_id: str, stamp: tuple[int, int]) -> Any:
    """A ``std_msgs/Header`` in ``frame_id`` stamped (sec, nanosec)."""
    return msgs(
        "std_msgs/msg/Header",
        stamp=msgs("builtin_interfaces/msg/Time", sec=int(stamp[0]), nanosec=int(stamp[1])),
        frame_id=frame_id,
    )
