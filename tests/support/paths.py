"""Where the repository, the tests and the contest data are, whatever folder a test sits in."""

from __future__ import annotations

from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
REPO = TESTS.parent
# CI clones the repository with ../shared beside it (the contest workbooks).
SHARED = REPO.parent / "shared"
DATA = SHARED / "data" / "gmcm2019f"
MISSIONS = REPO / "missions"
