"""Whether a stream is a terminal: what decides if a display draws, a notice shows or a
prompt is asked (the one test every command shares)."""

from __future__ import annotations

from typing import TextIO


def on_terminal(stream: TextIO) -> bool:
    """Whether ``stream`` is a terminal (a stream without ``isatty`` is not)."""
    isatty = getattr(stream, "isatty", None)
    try:
        return bool(isatty and isatty())
    except ValueError:  # a closed file
        return False
