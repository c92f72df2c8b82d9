"""The one exception type of drd_msgs_py."""

from __future__ import annotations


class MessageError(ValueError):
    """A message that cannot be turned into library types.

    NaN, ragged or empty data, unknown marker types, zero-size shapes, a wrong frame: the text says
    which message part and why.
    """
