import sys
from pathlib import Path

import pytest

# The tests' folder on the path, so that a test in any folder under it imports ``support``.
sys.path.insert(0, str(Path(__file__).resolve().parent))

from support.paths import DATA  # noqa: E402 - found through the path set above


@pytest.fixture(scope="session")
def dataset_paths() -> dict[int, Path]:
    paths = {1: DATA / "dataset1.xlsx", 2: DATA / "dataset2.xlsx"}
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:  # CI clones the repo with ../shared beside it; without it this is a setup error
        raise FileNotFoundError(
            f"contest workbooks not found: {missing}; ../shared must be beside the repo"
        )
    return paths
