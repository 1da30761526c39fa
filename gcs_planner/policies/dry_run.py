"""The dry run of a contingency policy: each run is a flight of the mock vehicle (a live one,
sim/live_vehicle.py) on UDP loopback with the ground station in the loop
(gcs_planner/policies/flight.py) switching missions in flight, through the link losses asked for.
The success rate, with its Wilson interval, is set against the policy's exact probability.

Time: the vehicle flies ``time_scale`` simulated seconds per wall second (sim/live_vehicle.py)
and the ground station's uploads take the link's time meanwhile, so a switch is made where the
aircraft is when the branch is verified and set current, as in the air. A run's flight lasts
its simulated duration divided by the time scale; a larger scale is faster but shortens, in
wall time, the window a switch must be made in (the distance from the failed fix to the next
item, at the ground speed, divided by the scale).

A run counts as arrived when the vehicle's own verdict says so (the replay's: B within the
capture radius with both errors within theta); a run whose ground station failed (a mission not
uploaded, a current item not confirmed, a silent vehicle) is counted as not arrived and named.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.dryrun.confidence import wilson_interval
from gcs_planner.errors import InputError, LinkError
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.params import set_parameter
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.policies.flight import PolicyFlight
from gcs_planner.scenario.model import Kind, Scenario
from gcs_planner.sim.faults import FaultRates
from gcs_planner.sim.guidance import nav_commands
from gcs_planner.sim.live_vehicle import DEFAULT_TIME_SCALE
from gcs_planner.sim.replay import DEFAULT_CAPTURE_RADIUS_M, scenario_frame
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

# After the vehicle takes a DO_SET_MISSION_CURRENT, its honest time scale holds until the ground
# station has been quiet this many of its timeouts (sim/live_vehicle.py). The ground station
# sends a copy each timeout until it is confirmed: at two timeouts, a copy taken with its
# acknowledgement lost and the next copy lost on the way left the third leaving as the window
# closed, landing at the cruise scale with the aircraft far past the item, and turning it back
# (run 59 of docs/flying-policies.md's 400 runs). At four, three copies in a row must be lost
# for one to land after the window.
SETTLE_TIMEOUTS = 4
# The dry run's waypoint acceptance radius (m): where the autopilot ignores a waypoint's own
# (PX4 fixed wing ignores param2), it is set as the vehicle-wide parameter.
DRY_RUN_ACCEPTANCE_M = 1.0


@dataclass(frozen=True)
class PolicyRun:
    seed: int
    arrived: bool
    missions_flown: tuple[str, ...]
    points_met: tuple[str, ...]
    why: str  # why it did not arrive, or what failed on the link ("" when it arrived)
    link_failed: bool = False
    # (failed or missed point, metres flown from its fix to the branch's item set current)
    switches: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class PolicyDryRunReport:
    flavour: str
    runs: tuple[PolicyRun, ...]
    loss: float
    seed: int
    time_scale: float
    probability: float | None  # the policy's exact probability of arriving, when given
    confidence: float
    switch_room: float | None = None  # m: the run-out the policy keeps for a switch, if any
    onboard: bool = False  # switched on board by its applet, the ground link cut after take-off

    @property
    def switches(self) -> list[tuple[str, float]]:
        return [s for r in self.runs for s in r.switches]

    @property
    def longest_switch(self) -> float | None:
        return max((d for _, d in self.switches), default=None)

    @property
    def switches_beyond_room(self) -> int:
        """Switches made farther from the fix than the policy's switch room: the aircraft had
        left the run-out both missions share when the branch was set current."""
        if self.switch_room is None:
            return 0
        return sum(d > self.switch_room for _, d in self.switches)

    @property
    def successes(self) -> int:
        return sum(r.arrived for r in self.runs)

    @property
    def success_rate(self) -> float:
        return self.successes / len(self.runs) if self.runs else 0.0

    @property
    def interval(self) -> tuple[float, float]:
        return wilson_interval(self.successes, len(self.runs), self.confidence)

    @property
    def link_failures(self) -> int:
        return sum(r.link_failed for r in self.runs)

    @property
    def probability_within_ci(self) -> bool | None:
        if self.probability is None or not self.runs:
            return None
        low, high = self.interval
        return low <= self.probability <= high

    @property
    def ok(self) -> bool:
        return self.link_failures == 0 and self.probability_within_ci is not False


def _policy_number(path: str, section: str, key: str, upper: float | None) -> float | None:
    """policy.json's ``section.key``: a number >= 0 (and <= ``upper``), or None when the file
    gives none; else one line naming the file and the field, exit 2."""
    from gcs_planner.mission.policy_file import load_policy_dict

    part = load_policy_dict(path).get(section)
    value = part.get(key) if isinstance(part, dict) else None
    if value is None:
        return None
    ok = not isinstance(value, bool) and isinstance(value, int | float) and value >= 0
    if not ok or (upper is not None and not value <= upper):
        wanted = f"in [0, {upper:g}]" if upper is not None else ">= 0"
        raise InputError(
            f"must be a number {wanted}, got {value!r}", file=path, field=f"{section}.{key}"
        )
    return float(value)


def policy_probability(path: str) -> float | None:
    """The policy's exact probability of arriving, as policy.json carries it
    (``value.probability``, docs/policy-json.md), or None when the file gives none."""
    return _policy_number(path, "value", "probability", 1.0)


def policy_switch_room(path: str) -> float | None:
    """The switch room (metres) policy.json was planned with (``switch_room.distance_m``,
    core/switch_room.py), or None when it has none."""
    return _policy_number(path, "switch_room", "distance_m", None)


def check_against_scenario(
    policy: PolicyMissions, scenario: Scenario, capture_radius: float, source: str = ""
) -> None:
    """Each switch's point is an unreliable correction point of the vehicle's landmark database
    and its mission item lies on it (within the capture radius): else one line, exit 2."""
    index = {pid: i for i, pid in enumerate(scenario.ids)}
    frame = scenario_frame(scenario)
    base = float(scenario.xyz[scenario.start][2] + frame.origin.alt)
    for k, s in enumerate(policy.switches):
        field = f"switches[{k}]"
        i = index.get(s.point)
        if i is None or Kind(int(scenario.kind[i])) not in (Kind.V, Kind.H):
            raise InputError(
                f"point {s.point} is not a correction point of {scenario.name}",
                file=source,
                field=field,
            )
        if not scenario.unreliable[i]:
            raise InputError(
                f"point {s.point} is reliable in {scenario.name}: its fix cannot fail",
                file=source,
                field=field,
            )
        item = policy.missions[s.mission].items[s.item]
        cmds = nav_commands([item], frame, base, home_at_seq0=False)
        pos = cmds[0].pos if cmds else None
        miss = math.inf if pos is None else math.dist(pos, scenario.xyz[i])
        if miss > capture_radius:
            raise InputError(
                f"item {s.item} of mission {s.mission!r} is {miss:.0f} m from point "
                f"{s.point} of {scenario.name}: the policy is not for this "
                "scenario",
                file=source,
                field=field,
            )


def policy_dry_run(
    policy: PolicyMissions,
    landmarks: Scenario,
    *,
    runs: int,
    probability: float | None = None,
    loss: float = 0.0,
    seed: int = 0,
    time_scale: float = DEFAULT_TIME_SCALE,
    cruise_scale: float | None = None,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    timeout: float = 0.5,
    retries: int = 5,
    navigate_on_estimate: bool = True,
    confidence: float = 0.99,
    say: Callable[[str], None] | None = None,
    set_params: dict[str, float] | None = None,
    switch_room: float | None = None,
) -> PolicyDryRunReport:
    """Fly ``policy`` ``runs`` times with a mock vehicle whose landmark database is
    ``landmarks``; ``loss`` is the fraction of messages the vehicle drops both ways;
    ``set_params`` are autopilot parameters set on the vehicle (PARAM_SET, read back) before
    the primary mission is uploaded, as a ground station sets up the aircraft."""
    if runs < 1:
        raise ValueError("runs must be >= 1")
    flavour = policy.missions[policy.primary].firmware
    done = []
    for k in range(runs):
        done.append(
            _one_run(
                policy,
                landmarks,
                flavour,
                seed,
                k,
                loss,
                (time_scale, cruise_scale),
                capture_radius,
                timeout,
                retries,
                navigate_on_estimate,
                say,
                set_params or {},
            )
        )
    return PolicyDryRunReport(
        flavour, tuple(done), loss, seed, time_scale, probability, confidence, switch_room
    )


def _one_run(
    policy,
    landmarks,
    flavour,
    seed,
    k,
    loss,
    scales,
    capture_radius,
    timeout,
    retries,
    estimate,
    say,
    settings,
) -> PolicyRun:
    port = free_udp_port()
    faults = FaultRates(drop=loss) if loss > 0 else None
    vehicle = MockVehicle(
        f"udpin:127.0.0.1:{port}",
        scenario=landmarks,
        flavour=flavour,
        live=True,
        speedup=scales[0],
        cruise_speedup=scales[1],
        faults_in=faults,
        faults_out=faults,
        fault_seed=seed * 7919 + 2 * k,
        capture_radius=capture_radius,
        navigate_on_estimate=estimate,
    )
    vehicle.flight_seed = seed * 1_000_003 + k
    # The time warp (a cruise time scale) ends only where the policy switches to a mission
    # with other items (a branch that keeps the mission flown uploads nothing: no window).
    vehicle.watch_points = frozenset(
        s.point
        for s in policy.switches
        if policy.missions[s.to_mission].items != policy.missions[s.mission].items
    )
    vehicle.settle_wall_s = SETTLE_TIMEOUTS * timeout
    flown: tuple[str, ...] = ()
    why = ""
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        client = MissionClient(link, timeout=timeout, retries=retries, transfer="mission")
        try:
            client.connect(timeout=10.0)
            ap = autopilot_for(flavour)
            if not ap.item_acceptance:
                settings = {ap.acceptance_param: DRY_RUN_ACCEPTANCE_M, **settings}
            for name, value in settings.items():
                set_parameter(link, client._target(), name, value, timeout=timeout,
                              retries=retries)  # fmt: skip
            flight = PolicyFlight(client, policy, say=say or (lambda _line: None))
            try:
                flight.run(start=True)
            finally:
                flown = tuple(flight.flown_names)
        except LinkError as exc:
            why = str(exc)
        finally:
            link.close()
        if vehicle._fly_thread is not None:
            vehicle._fly_thread.join(timeout=60.0)  # the vehicle's verdict is set at its end
    live = vehicle.last_live
    if why or live is None:
        return PolicyRun(k, False, flown, (), why or "the vehicle did not fly", link_failed=True)
    reason = "" if live.arrived else (live.run.lost_reason or "did not arrive")
    return PolicyRun(k, live.arrived, flown, live.points_met, reason, switches=live.switches)
