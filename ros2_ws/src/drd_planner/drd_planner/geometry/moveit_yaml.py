"""Reading MoveIt YAML files (planning scenes, motion plan requests) within bounds, and quoting their values.

A scene or request file is user input and may be hostile. Reading it is bounded before anything is parsed:

- the file must be a regular file of at most ``max_bytes`` (its size is looked at before it is read, so a
  link to a huge sparse file or a pipe never is);
- the YAML is parsed by PyYAML's safe loader with a composer that refuses **aliases** (``*name``: a few
  hundred bytes of nested aliases expand to billions of values, and MoveIt never writes them), nesting
  deeper than ``max_depth`` (no ``RecursionError``) and more than ``max_nodes`` values;
- error texts quote offending values with :func:`quoted`, never their whole ``repr``.

Every refusal is one :class:`~drd_planner.exceptions.GeometryError` naming the file.
"""

from __future__ import annotations

import reprlib
from pathlib import Path
from typing import Any

import yaml
from yaml.composer import ComposerError

from drd_planner.bounded_files import read_bounded_text
from drd_planner.exceptions import GeometryError

__all__ = ["MAX_YAML_BYTES", "MAX_YAML_DEPTH", "MAX_YAML_NODES", "load_yaml", "quoted", "read_yaml_text"]

#: Largest MoveIt YAML file read (bytes); MotionBenchMaker's scenes are a few KiB.
MAX_YAML_BYTES = 8 * 1024 * 1024
#: Deepest nesting of YAML collections accepted (a planning scene needs about 8).
MAX_YAML_DEPTH = 64
#: Most YAML values (scalars and collections) in one document.
MAX_YAML_NODES = 500_000

_QUOTE = reprlib.Repr()
_QUOTE.maxstring = 60
_QUOTE.maxother = 60
_QUOTE.maxlist = _QUOTE.maxtuple = _QUOTE.maxdict = 6
_QUOTE.maxlevel = 3


def quoted(value: object) -> str:
    """A short ``repr`` of a value for an error text (long strings and big or deep collections cut)."""
    return _QUOTE.repr(value)


class _BoundedLoader(yaml.SafeLoader):  # type: ignore[misc]
    """PyYAML's safe loader whose composer refuses aliases, deep nesting and too many values."""

    max_depth = MAX_YAML_DEPTH
    max_nodes = MAX_YAML_NODES

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0
        self._nodes = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            mark = self.peek_event().start_mark
            raise ComposerError(None, None, "YAML aliases (*name) are not accepted in MoveIt files", mark)
        self._depth += 1
        self._nodes += 1
        if self._depth > self.max_depth:
            mark = self.peek_event().start_mark
            raise ComposerError(None, None, f"values nested deeper than {self.max_depth} levels", mark)
        if self._nodes > self.max_nodes:
            mark = self.peek_event().start_mark
            raise ComposerError(None, None, f"more than {self.max_nodes} values", mark)
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def load_yaml(text: str, *, source: str) -> Any:
    """The document of YAML ``text`` (safe types only), within the module's bounds.

    Raises:
        GeometryError: invalid YAML, an alias, nesting beyond :data:`MAX_YAML_DEPTH` or more than
            :data:`MAX_YAML_NODES` values; the message names ``source``.
    """
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_data()
    except yaml.YAMLError as exc:
        raise GeometryError(f"{source}: not valid YAML: {_one_line(exc)}") from None
    finally:
        loader.dispose()


def read_yaml_text(path: str | Path, what: str, *, max_bytes: int = MAX_YAML_BYTES) -> str:
    """The UTF-8 text of a MoveIt YAML file of at most ``max_bytes``; ``what`` names the kind of file.

    Raises:
        GeometryError: not a regular file, larger than ``max_bytes`` (checked before reading), unreadable,
            or not UTF-8.
    """
    hint = " (a MoveIt YAML file is a few KiB)"
    return read_bounded_text(path, max_bytes, f"{what} {Path(path)}", GeometryError, hint=hint)


def _one_line(exc: BaseException) -> str:
    """The exception's text on one line, at most 300 characters."""
    text = " ".join(str(exc).split())
    return text if len(text) <= 300 else f"{text[:297]}..."
