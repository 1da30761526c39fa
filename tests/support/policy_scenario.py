"""A small scenario whose best policy branches: the primary route A H1 P B arrives when the fix
at the unreliable V point P takes; when it fails, the vertical error left (the residual) is
over theta at B, and the branch P -> V2 -> B arrives (V2 is reliable, 2022 m on from P, 300 m
off the primary's leg).

Limits (delta 0.005: 200 m per unit): V points v <= 35 units (7 km), h <= 25 (5 km); H points
25/25; theta 38 (7.6 km); a failed fix leaves 20 units (4 km). Along the primary: P at 4 km
from A (v 4000 m, h 2000 m), B 4 km further: made, v 4000 h 6000 at B; failed, v 8000 > 7600:
lost. Along the branch: V2 at v 6022 m, h 4022 m; at B v 2022, h 6044. So the policy arrives
with probability 1 and the route with p. A switch made late costs little: the aircraft, going
on along the primary's leg, still passes near V2 (1 km late costs 22 m), so the test does not
hang on the link's speed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.policy_missions import PolicyMissions, Switch
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.model import Kind, Origin, Scenario

from .missions import make_plan

ORIGIN = Origin(lat=31.2, lon=122.8, alt=12.5)
IDS = ("A0", "H1", "P2", "V3", "B4")
XYZ = np.array([
    [0.0, 0.0, 1000.0],  # A
    [2000.0, 0.0, 1000.0],  # H1
    [4000.0, 0.0, 1000.0],  # P: unreliable V
    [6000.0, 300.0, 1000.0],  # V2: reliable V, only on the branch
    [8000.0, 0.0, 1000.0],  # B
])  # fmt: skip
PRIMARY = [0, 1, 2, 4]
BRANCH = [0, 1, 2, 3, 4]


def policy_scenario(p_success: float = 0.8) -> Scenario:
    """The scenario, corrections at P succeeding with ``p_success``."""
    params = {**DATASET1.to_dict(), "alpha1": 35.0, "alpha2": 25.0, "beta1": 25.0,
              "beta2": 25.0, "theta": 38.0, "delta": 0.005, "fail_residual": 20.0,
              "p_success": p_success, "turn_radius": 0.0}  # fmt: skip
    return Scenario(
        ids=IDS, xyz=XYZ.copy(),
        kind=np.array([Kind.A, Kind.H, Kind.V, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.array([False, False, True, False, False]),
        params=DATASET1.__class__(**params), name="policy", source="hand-made", origin=ORIGIN,
    )  # fmt: skip


def policy_missions(scenario: Scenario, firmware: str = DEFAULT_AUTOPILOT) -> PolicyMissions:
    """The primary mission and the branch taken when the fix at P fails."""
    plan = make_plan(scenario, routes=(PRIMARY, BRANCH), probability=True)
    primary = build_mission(plan, route_index=0, firmware=firmware, acceptance_radius=1)
    branch = build_mission(plan, route_index=1, firmware=firmware, acceptance_radius=1)
    seq_p = dict(primary.point_seqs)["P2"]
    return PolicyMissions(
        primary="primary",
        missions={"primary": primary, "after-P2": branch},
        switches=(Switch("primary", "P2", seq_p, "after-P2", seq_p + 1),),
    )


def write_scenario(folder: Path, p_success: float = 0.8) -> Path:
    """The scenario as files (scenario.toml and points.csv in ``folder``): the path of the
    TOML, for the command line."""
    s = policy_scenario(p_success)
    rows = ["id,x,y,z,kind,unreliable"]
    for i, pid in enumerate(s.ids):
        x, y, z = s.xyz[i]
        rows.append(f"{pid},{x},{y},{z},{Kind(int(s.kind[i])).name},{int(s.unreliable[i])}")
    (folder / "points.csv").write_text("\n".join(rows) + "\n")
    p = s.params
    (folder / "scenario.toml").write_text(
        'name = "policy"\npoints = "points.csv"\n\n[parameters]\n'
        + "".join(
            f"{k} = {getattr(p, k)!r}\n"
            for k in ("alpha1", "alpha2", "beta1", "beta2", "theta", "delta", "turn_radius",
                      "p_success", "fail_residual")
        )
        + f"\n[origin]\nlat = {ORIGIN.lat}\nlon = {ORIGIN.lon}\nalt = {ORIGIN.alt}\n"
    )  # fmt: skip
    return folder / "scenario.toml"
