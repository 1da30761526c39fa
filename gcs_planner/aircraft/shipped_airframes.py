"""The JSBSim aircraft files shipped with gcs_planner (package data under ``airframes/``): where
they are and their names."""

from __future__ import annotations

from pathlib import Path

# JSBSim's aircraft folder layout: airframes/NAME/NAME.xml, its engines in airframes/NAME/Engines.
AIRFRAMES_DIR = Path(__file__).resolve().with_name("airframes")


def shipped_airframes() -> list[str]:
    """The names of the aircraft shipped here (``aerosonde``), each a JSBSim aircraft folder."""
    if not AIRFRAMES_DIR.is_dir():
        return []
    return sorted(d.name for d in AIRFRAMES_DIR.iterdir() if (d / f"{d.name}.xml").is_file())


def is_shipped(name: str) -> bool:
    """Whether ``name`` is one of the project's own airframes (not one of jsbsim's)."""
    return name in shipped_airframes()
