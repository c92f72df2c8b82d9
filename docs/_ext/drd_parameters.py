"""Sphinx directive ``drd-parameters``: the node's parameter table, generated from the code.

The rows come from :data:`drd_planner.ros.parameters.PARAMETERS`, the table the node declares its
parameters from, so the docs list exactly what ``ros2 param describe`` shows: name, type, default and
description, with the advertised range and read-only flag added to the description, and a deprecated
alias marked as such (its name cell says ``(deprecated)``, its description names the replacement).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from docutils import nodes
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective

from drd_planner.ros.parameters import PARAMETERS, ParameterSpec

#: Column titles of the generated table.
HEADER = ("name", "type", "default", "description")


def ros_type(default: Any) -> str:
    """The ROS 2 parameter type a default value declares (``bool`` is tested before ``int``)."""
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "integer"
    if isinstance(default, float):
        return "double"
    if isinstance(default, str):
        return "string"
    if isinstance(default, list | tuple) and all(isinstance(item, str) for item in default):
        return "string array"
    raise TypeError(f"no ROS 2 parameter type for the default {default!r}")


def _number(value: float) -> str:
    return "inf" if math.isinf(value) else f"{value:g}"


def describe(spec: ParameterSpec) -> str:
    """The description with the range ``ros2 param describe`` shows, the read-only flag and a deprecation."""
    notes = [spec.full_description]
    if spec.float_range is not None:
        notes.append(f"Range [{_number(spec.float_range[0])}, {_number(spec.float_range[1])}].")
    if spec.int_range is not None and spec.int_range[1] < 2**63 - 1:
        notes.append(f"Range [{spec.int_range[0]}, {spec.int_range[1]}].")
    if spec.read_only:
        notes.append("Read-only.")
    return " ".join(notes)


def rows(specs: Sequence[ParameterSpec] = PARAMETERS) -> list[tuple[str, str, str, str]]:
    """One row (name, type, default, description) per parameter, in declaration order.

    A deprecated alias's name reads ``<name> (deprecated)``.
    """
    return [
        (
            spec.name if spec.deprecated_for is None else f"{spec.name} (deprecated)",
            ros_type(spec.default),
            repr(spec.default),
            describe(spec),
        )
        for spec in specs
    ]


def _entry(text: str, *, code: bool) -> Any:
    paragraph = nodes.paragraph()
    paragraph += nodes.literal(text, text) if code else nodes.Text(text)
    entry = nodes.entry()
    entry += paragraph
    return entry


def _row(cells: Sequence[str], code_columns: int) -> Any:
    row = nodes.row()
    for column, text in enumerate(cells):
        row += _entry(text, code=column < code_columns)
    return row


def table(cells: Sequence[Sequence[str]]) -> Any:
    """A docutils table of ``HEADER`` over ``cells`` (name, type and default set as code)."""
    group = nodes.tgroup(cols=len(HEADER))
    for width in (20, 10, 12, 58):
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    head += _row(HEADER, code_columns=0)
    body = nodes.tbody()
    for cells_of_row in cells:
        body += _row(cells_of_row, code_columns=3)
    group += head
    group += body
    result = nodes.table(classes=["drd-parameters"])
    result += group
    return result


class ParametersDirective(SphinxDirective):
    """``drd-parameters``: the table of every parameter ``planner_node`` declares."""

    has_content = False

    def run(self) -> list[Any]:
        """Emit the table."""
        return [table(rows())]


def setup(app: Sphinx) -> dict[str, Any]:
    """Register the directive."""
    app.add_directive("drd-parameters", ParametersDirective)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
