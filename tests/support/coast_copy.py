"""missions/coast copied into a test's folder with its landmarks' altitudes changed: scaled, then
lifted, with or without its stated [vehicle] (for the airframes' tests, whose aircraft cannot
climb to the coast's 3.4 km)."""

from __future__ import annotations

from pathlib import Path

from .paths import MISSIONS

COAST = MISSIONS / "coast"


def coast_copy(
    folder: Path, *, scale: float = 1.0, lift: float = 0.0, keep_vehicle: bool = True
) -> Path:
    """The copy's scenario.toml: every landmark at ``altitude * scale + lift`` m; without its
    [vehicle] section unless ``keep_vehicle`` (the plan then derives an envelope)."""
    text = (COAST / "scenario.toml").read_text()
    (folder / "scenario.toml").write_text(text if keep_vehicle else text[: text.index("[vehicle]")])
    lines = (COAST / "landmarks.csv").read_text().splitlines()
    out = [lines[0]]
    for line in lines[1:]:
        f = line.split(",")
        f[3] = f"{float(f[3]) * scale + lift:.2f}"
        out.append(",".join(f))
    (folder / "landmarks.csv").write_text("\n".join(out) + "\n")
    return folder / "scenario.toml"
