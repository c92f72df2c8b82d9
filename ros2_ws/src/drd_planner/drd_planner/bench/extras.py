"""The optional extras of ``setup.py`` (``plots``: matplotlib, ``peer``: OMPL) and the message naming them.

Modules that need an extra import it only where it is used; a command or option that needs one calls
:func:`require_extra` first, so a plain install (no extras) fails early with what to install instead of a
bare ``No module named ...``.
"""

from __future__ import annotations

import importlib

from drd_planner.exceptions import DrdError

__all__ = ["EXTRAS", "MissingExtraError", "install_hint", "require_extra"]

#: Extra name -> the module it provides.
EXTRAS = {"plots": "matplotlib", "peer": "ompl"}


class MissingExtraError(DrdError):
    """A command or option needs an optional extra that is not installed."""


def install_hint(extra: str) -> str:
    """The pip command that installs ``extra`` into an editable checkout of the package."""
    return f"pip install -e 'ros2_ws/src/drd_planner[{extra}]'"


def require_extra(extra: str, what: str) -> None:
    """Raise :class:`MissingExtraError` when the module of ``extra`` cannot be imported.

    Args:
        extra: a key of :data:`EXTRAS`.
        what: what needs it, for the message (e.g. ``drd bench --figures``).
    """
    module = EXTRAS[extra]
    try:
        importlib.import_module(module)
    except ImportError as exc:
        raise MissingExtraError(f"{what} needs the '{extra}' extra ({module}): {install_hint(extra)}") from exc
