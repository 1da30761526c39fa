"""A terminal for the progress displays to draw on, and what it shows after their output."""

from __future__ import annotations

import io
import re


class FakeTerminal(io.StringIO):
    """A text stream that says it is a terminal (so the displays draw on it)."""

    def isatty(self) -> bool:
        return True


def screen(text: str) -> list[str]:
    """What a terminal shows after ``text``: carriage returns go back to the column 0 and
    overwrite, erase-to-end-of-line clears the rest, newlines start a row."""
    rows, row, col = [], [], 0
    for token in re.findall(r"\x1b\[K|\x1b\[A|\r|\n|[^\r\n\x1b]", text):
        if token == "\r":
            col = 0
        elif token == "\n":
            rows.append("".join(row).rstrip())
            row, col = [], 0
        elif token == "\x1b[K":
            del row[col:]
        elif token == "\x1b[A":
            raise AssertionError("a single line should never move the cursor up")
        else:
            if col < len(row):
                row[col] = token
            else:
                row.append(token)
            col += 1
    if row:
        rows.append("".join(row).rstrip())
    return rows
