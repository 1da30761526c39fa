"""Pictures left undrawn where a test's subject is not them: ``plan --out`` and ``export``
draw up to five PNGs with matplotlib (route, front, error budget, the policy's tree and front),
most of the CPU of a small plan written out. A test of the files, the folder or the refusals
around them stands each picture in by a valid 1 x 1 PNG and may check which were asked for.

What the pictures show is tests/mission/test_pictures.py's and test_picture_layout.py's; the
pictures as `plan --out` draws them are still drawn by tests/mission/test_edges_files.py
(``test_plan_out_writes_every_file_and_replaces_an_earlier_run``) and by the documented
commands (tests/docs/test_documented_commands.py: README's `plan ... --out out/coast` and
`plan ... --policy --out out/coast-policy`), whole processes."""

from __future__ import annotations

import struct
import zlib

import pytest

from gcs_planner.mission import pictures, policy_pictures

# (module, name): the renderers as the exporters look them up (mission/export.py reads the
# plan's pictures off ``pictures``, mission/policy_export.py the policy's off
# ``policy_pictures``), so that patching them there reaches every caller.
RENDERERS = (
    (pictures, "route_png"),
    (pictures, "front_png"),
    (pictures, "error_budget_png"),
    (policy_pictures, "tree_png"),
    (policy_pictures, "policy_front_png"),
)


def _chunk(kind: bytes, data: bytes) -> bytes:
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


# One grey pixel: a PNG any reader opens.
ONE_PIXEL_PNG = (
    b"\x89PNG\r\n\x1a\n"
    + _chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0))
    + _chunk(b"IDAT", zlib.compress(b"\x00\x80"))
    + _chunk(b"IEND", b"")
)


def leave_pictures_undrawn(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Stand every picture in by ``ONE_PIXEL_PNG`` for the rest of the test; the names of the
    renderers asked, in order, are appended to the list returned."""
    asked: list[str] = []
    for module, name in RENDERERS:

        def undrawn(*args: object, _name: str = name, **kwargs: object) -> bytes:
            asked.append(_name)
            return ONE_PIXEL_PNG

        monkeypatch.setattr(module, name, undrawn)
    return asked
