"""``dry-run --policy FILE --onboard``: a contingency policy switched on board, flown end to end.

Each run is a live mock ArduPilot (sim/vehicle.py) on UDP loopback with the applet on its SD
card (policy.lua: the file beside policy.json, or the one generated from the policy). The
ground station sets the vehicle up, uploads the onboard mission (mission/onboard_mission.py)
and verifies it (read back), and starts it; from take-off on the link is cut: nothing reaches or
leaves the ground station, and the applet alone switches branches (sim/onboard_flight.py). The
flight runs in simulated time, as fast as the machine goes. The vehicle's own verdict says
whether the run arrived; the success rate and its Wilson interval are set against the policy's
exact probability, as the ground-switched dry run does (policies/dry_run.py).

A run whose upload or start failed, or whose applet stopped (an error, a binding the mock does
not provide), is counted as not arrived and named.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.errors import InputError, LinkError
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.params import set_parameter
from gcs_planner.mission.onboard_applet import APPLET_FILE, applet_text, point_codes
from gcs_planner.mission.onboard_mission import OnboardMission, onboard_mission
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.policies.dry_run import PolicyDryRunReport, PolicyRun
from gcs_planner.policies.flight import start_mission
from gcs_planner.scenario.model import Scenario
from gcs_planner.sim.faults import FaultRates
from gcs_planner.sim.replay import DEFAULT_CAPTURE_RADIUS_M
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

# Wall seconds a run's flight may take after the start (simulated time: a dataset 2 flight
# takes a few seconds of CPU; this only bounds a flight that hangs).
FLIGHT_WAIT_S = 600.0
UPLOAD_ATTEMPTS = 3


def load_applet(policy_path: str, policy: PolicyMissions, landmarks: Scenario) -> tuple[str, str]:
    """(applet text, where it came from): policy.lua beside ``policy_path`` when there is one
    (what the operator puts on the SD card), else generated from the policy."""
    beside = Path(policy_path).with_name(APPLET_FILE)
    if beside.is_file():
        return beside.read_text(encoding="utf-8"), str(beside)
    text = applet_text(onboard_mission(policy), point_codes(landmarks.ids), title=landmarks.name)
    return text, f"generated from {policy_path}"


def check_onboard(policy: PolicyMissions, source: str = "") -> None:
    """The policy's autopilot runs Lua applets (else one line, exit 2: PX4 switches on board
    with a companion, ``fly --onboard``)."""
    ap = autopilot_for(policy.missions[policy.primary].firmware)
    if not ap.runs_lua_applets:
        raise InputError(
            f"{ap.title} runs no Lua applets: its onboard switching is a companion's process "
            "(gcs-planner fly --onboard on the vehicle's local link)",
            file=source,
            field="--onboard",
        )


def onboard_dry_run(
    policy: PolicyMissions,
    landmarks: Scenario,
    applet: str,
    *,
    runs: int,
    probability: float | None = None,
    loss: float = 0.0,
    seed: int = 0,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    timeout: float = 0.5,
    retries: int = 5,
    navigate_on_estimate: bool = True,
    confidence: float = 0.99,
    say: Callable[[str], None] | None = None,
    set_params: dict[str, float] | None = None,
    switch_room: float | None = None,
) -> PolicyDryRunReport:
    """Fly ``policy`` switched on board by ``applet`` ``runs`` times (module docstring);
    ``loss`` is the fraction of messages dropped both ways while the link is up."""
    if runs < 1:
        raise ValueError("runs must be >= 1")
    check_onboard(policy)
    onboard = onboard_mission(policy)
    flavour = policy.missions[policy.primary].firmware
    done = []
    for k in range(runs):
        port = free_udp_port()
        vehicle = MockVehicle(
            f"udpin:127.0.0.1:{port}",
            scenario=landmarks,
            flavour=flavour,
            live=True,
            faults_in=FaultRates(drop=loss) if loss > 0 else None,
            faults_out=FaultRates(drop=loss) if loss > 0 else None,
            fault_seed=seed * 7919 + 2 * k,
            capture_radius=capture_radius,
            navigate_on_estimate=navigate_on_estimate,
        )
        vehicle.flight_seed = seed * 1_000_003 + k  # the ground-switched dry run's draws
        vehicle.applet = applet
        run = _one_run(vehicle, port, onboard, k, (timeout, retries), set_params or {})
        if say is not None:
            verdict = "arrived" if run.arrived else f"NOT arrived: {run.why}"
            say(f"run {k}: {' -> '.join(run.missions_flown)}; {verdict}")
        done.append(run)
    return PolicyDryRunReport(
        flavour, tuple(done), loss, seed, 0.0, probability, confidence, switch_room, onboard=True
    )


def _one_run(
    vehicle: MockVehicle,
    port: int,
    onboard: OnboardMission,
    k: int,
    link_timing: tuple[float, int],
    settings: dict[str, float],
) -> PolicyRun:
    """Set up, upload, verify and start over the link; then wait for the flight, cut off."""
    timeout, retries = link_timing
    why = ""
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        client = MissionClient(link, timeout=timeout, retries=retries, transfer="mission")
        try:
            client.connect(timeout=10.0)
            for name, value in settings.items():
                set_parameter(link, client._target(), name, value, timeout=timeout,
                              retries=retries)  # fmt: skip
            _upload(client, onboard)
            start_mission(client)
            vehicle.cut_link()  # take-off: from here on the applet alone
        except LinkError as exc:
            why = str(exc)
        finally:
            link.close()
        if vehicle._fly_thread is not None:
            vehicle._fly_thread.join(timeout=FLIGHT_WAIT_S)
    live = vehicle.last_live
    if why or live is None:
        return PolicyRun(k, False, (onboard.primary,), (), why or "the vehicle did not fly",
                         link_failed=True)  # fmt: skip
    flown = (onboard.primary, *(onboard.mission_at(index) for _, index in live.jumps))
    if live.applet_error:
        return PolicyRun(k, False, flown, live.points_met, f"the applet stopped: "
                         f"{live.applet_error}", link_failed=True)  # fmt: skip
    reason = "" if live.arrived else (live.run.lost_reason or "did not arrive")
    return PolicyRun(k, live.arrived, flown, live.points_met, reason, switches=live.switches)


def _upload(client: MissionClient, onboard: OnboardMission) -> None:
    """The onboard mission, uploaded and read back equal (up to UPLOAD_ATTEMPTS whole tries)."""
    error: LinkError | None = None
    for _ in range(UPLOAD_ATTEMPTS):
        try:
            client.upload_verified(onboard.mission.items)
            return
        except LinkError as exc:
            error = exc
    assert error is not None
    raise LinkError(f"the onboard mission could not be uploaded: {error}")
