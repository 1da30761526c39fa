"""The mock vehicle's replay: flown length against the plan, errors at each correction against
the planned ones, losses, and the Monte Carlo against the exact success probability."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from gcs_planner.sim.guidance import AutopilotParams
from gcs_planner.sim.replay import CHORD_SHORTFALL, QUANTISATION_M, flavour_for
from gcs_planner.sim.replay import replay as fly_and_replay

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.core.probability import success_probability
from gcs_planner.core.route import Leg, evaluate_route
from gcs_planner.geometry.dubins import cs_leg
from gcs_planner.mission.builder import arc_waypoints
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.generate import DATASET1, random_scenario
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Kind, Origin, Scenario

# The flown length may differ from the planned one: the aircraft overshoots a little after each
# turn (L1 guidance at its bank limit) and smooths the chords of densified arcs.
FLIGHT_TOLERANCE = 1e-4  # of the planned length


def replay(items, sc, **kw):
    """The replay with the exporter's small acceptance radius (1 m, also PX4's NAV_ACC_RAD as
    the dry run sets it), so that both autopilots overfly each point."""
    flavour = flavour_for(kw.get("home_at_seq0", False))
    kw.setdefault(
        "autopilot",
        AutopilotParams(flavour, acceptance_radius=1.0, loiter_radius=sc.params.turn_radius),
    )
    return fly_and_replay(items, sc, **kw)


ORIGIN = Origin(30.5, 123.5, 0.0)


@pytest.mark.parametrize("home", [True, False])
def test_the_autopilot_flown_by_default_is_the_one_that_keeps_home_as_the_mission_says(home):
    assert autopilot_for(flavour_for(home)).home_at_seq0 == home


def line_scenario(kinds: str, unreliable: str = "", spacing: float = 12_000.0) -> Scenario:
    """A, the given correction kinds, B, on a gently bent line ``spacing`` metres apart."""
    n = len(kinds) + 2
    xyz = np.array([[i * spacing, 300.0 * (i % 2), 5000.0 + 10 * i] for i in range(n)])
    kind = [Kind.A] + [Kind.V if k == "V" else Kind.H for k in kinds] + [Kind.B]
    flags = [False] + [c == "u" for c in unreliable.ljust(len(kinds), ".")] + [False]
    return Scenario(
        ids=tuple(f"P{i}" for i in range(n)),
        xyz=xyz,
        kind=np.array(kind, dtype=np.uint8),
        unreliable=np.array(flags),
        params=DATASET1,
        origin=ORIGIN,
    )


def mission_through(
    points_xyz: np.ndarray, *, home: bool, relative: bool = False, run_out: float = 1000.0
) -> list:
    """Waypoints through local points, as MAVLink items (an ArduPilot-style home at seq 0), and a
    run-out waypoint ``run_out`` metres beyond the last point on the last leg's heading: a
    fixed-wing PX4 switches to the next item at npfg's switch distance (~57-70 m before a
    waypoint), so without one it never overflies the last point."""
    frame = LocalFrame(ORIGIN)
    items: list[MissionItem] = []
    lat, lon, alt = frame.to_geodetic(*points_xyz[0])
    if home:
        items.append(MissionItem(0, 0, 16, x=round(lat * 1e7), y=round(lon * 1e7), z=alt))
    items.append(MissionItem(len(items), 2, 178, param2=25.0))
    if run_out > 0 and len(points_xyz) > 1:
        last = np.asarray(points_xyz[-1], float)
        d = last - np.asarray(points_xyz[-2], float)
        d[2] = 0.0
        d = d / (np.linalg.norm(d) or 1.0)
        points_xyz = np.vstack([points_xyz, last + run_out * d])
    for p in points_xyz:
        la, lo, al = frame.to_geodetic(*p)
        z = al - alt if relative else al
        # param2 1 m: the exporter's small acceptance radius, so that ArduPlane overflies the
        # point (0 would let it turn up to WP_RADIUS early, short of B).
        items.append(
            MissionItem(
                len(items),
                3 if relative else 0,
                16,
                param2=1.0,
                x=round(la * 1e7),
                y=round(lo * 1e7),
                z=z,
            )
        )
    return items


@pytest.mark.parametrize("home, relative", [(True, False), (False, False), (True, True)])
def test_straight_route_flies_its_planned_length_and_errors(home, relative):
    sc = line_scenario("VHVHVH")
    route = list(range(sc.n))
    planned = evaluate_route(sc, route)
    assert planned.feasible
    items = mission_through(sc.xyz[route], home=home, relative=relative)
    rep = replay(items, sc, home_at_seq0=home)
    tol = QUANTISATION_M * len(items) + FLIGHT_TOLERANCE * planned.length
    assert rep.arrived and not rep.run.lost
    assert abs(rep.flown_length - planned.length) <= tol
    assert [c.id for c in rep.run.corrections] == planned.ids()[1:-1]
    for row, stop in zip(rep.run.corrections, planned.stops[1:-1], strict=True):
        assert row.within_limits and row.succeeded
        assert abs(row.v_before - stop.v_arrival) <= sc.params.delta * tol
        assert abs(row.h_before - stop.h_arrival) <= sc.params.delta * tol
        assert row.v_margin == pytest.approx(stop.v_margin, abs=sc.params.delta * tol)
    last = planned.stops[-1]
    assert abs(rep.run.v_at_end - last.v_arrival) <= sc.params.delta * tol


def test_dubins_route_flown_on_densified_arcs_within_the_chord_tolerance():
    sc = line_scenario("VHVHV", spacing=10_000.0)
    # Bend the route so that each leg starts with a real turn.
    xyz = sc.xyz.copy()
    xyz[:, 1] = [0, 1500, -1000, 1200, -800, 1500, 0]
    sc = replace(sc, xyz=xyz)
    radius = 800.0
    heading = np.array([1.0, 0.0, 0.0])
    legs, waypoints = [], [xyz[0]]
    for i in range(sc.n - 1):
        leg = cs_leg(xyz[i], heading, xyz[i + 1], radius)
        assert leg.reachable
        legs.append(leg)
        arc = arc_waypoints(leg)
        if len(arc) and np.linalg.norm(arc[-1] - xyz[i + 1]) < 1.0:
            arc = arc[:-1]
        waypoints.extend(arc)
        waypoints.append(xyz[i + 1])
        heading = leg.heading_out
    planned = evaluate_route(
        sc, range(sc.n), [Leg(leg.length, leg.arc_length, leg.arc_angle) for leg in legs], radius
    )
    assert planned.feasible
    arcs = sum(leg.arc_length for leg in legs)
    assert arcs > 1000.0  # the test is about turns
    items = mission_through(np.array(waypoints), home=False)
    rep = replay(items, sc)
    tol = CHORD_SHORTFALL * arcs + QUANTISATION_M * len(items)
    # The mission's chords are shorter than the arcs, within the chord shortfall.
    assert rep.mission_length <= planned.length + QUANTISATION_M * len(items)
    assert planned.length - rep.mission_length <= tol
    # The aircraft flies near the arcs, not the chords.
    tol = tol + FLIGHT_TOLERANCE * planned.length
    assert abs(planned.length - rep.flown_length) <= tol
    assert rep.arrived
    for row, stop in zip(rep.run.corrections, planned.stops[1:-1], strict=True):
        assert row.id == stop.id
        assert abs(row.v_before - stop.v_arrival) <= sc.params.delta * tol
        assert abs(row.h_before - stop.h_arrival) <= sc.params.delta * tol


def test_skipping_a_correction_gets_the_vehicle_lost_where_the_limit_breaks():
    sc = line_scenario("VHVHVH")
    route = [0, 1, 2, 4, 5, 6, 7]  # leaves out the V at index 3
    planned = evaluate_route(sc, route)
    assert not planned.feasible
    rep = replay(mission_through(sc.xyz[route], home=False), sc)
    assert rep.run.lost and not rep.arrived
    assert rep.run.corrections[-1].id == planned.first_violation().id
    assert not rep.run.corrections[-1].within_limits
    assert "lost at" in rep.run.lost_reason


def test_a_mission_that_stops_short_of_b_does_not_arrive():
    sc = line_scenario("VH")
    rep = replay(mission_through(sc.xyz[:3], home=False), sc)
    assert not rep.arrived and not rep.run.reached_b
    assert "from B" in rep.run.lost_reason


def test_px4_never_overflies_a_last_waypoint_it_switches_away_from():
    """A PX4 mission ending on B: PX4 accepts B at npfg's switch distance (~67 m at 5 km, 32 m/s
    true) and the flight ends there, outside the capture radius; ArduPlane flies up to it."""
    sc = line_scenario("VH")
    px4 = replay(mission_through(sc.xyz, home=False, run_out=0.0), sc)
    assert not px4.run.reached_b and px4.run.miss_b > 50.0
    ardu = replay(mission_through(sc.xyz, home=True, run_out=0.0), sc, home_at_seq0=True)
    assert ardu.run.reached_b


def test_passing_close_to_a_landmark_corrects_there_once():
    sc = line_scenario("VHV")
    # Fly A -> P2 -> P1 -> P2 -> ... : P2 is passed twice but used once.
    route = [0, 2, 1, 2, 3, 4]
    rep = replay(mission_through(sc.xyz[route], home=False), sc)
    assert [c.id for c in rep.run.corrections].count("P2") == 1


@pytest.mark.parametrize("seed", [0, 1])
def test_monte_carlo_agrees_with_the_exact_probability(seed):
    # Unreliable V points whose failure matters (12 km legs, alpha1 = 25, r = 5).
    sc = line_scenario("VHVHVHV", unreliable="u.u.u..")
    route = list(range(sc.n))
    exact = success_probability(sc, route).probability
    assert 0.1 < exact < 0.95
    rep = replay(mission_through(sc.xyz, home=True), sc, home_at_seq0=True, runs=20_000, seed=seed)
    mc = rep.monte_carlo
    assert mc is not None and mc.runs == 20_000
    assert mc.ci_low <= exact <= mc.ci_high
    # One replay with drawn outcomes: failures only where points are unreliable.
    assert all(r.succeeded or r.unreliable for r in rep.run.corrections if r.succeeded is not None)


def test_monte_carlo_on_random_scenario_route_all_reliable_is_certain():
    sc = random_scenario(30, seed=5, unreliable_fraction=0.0)
    sc = replace(sc, origin=ORIGIN)
    # A greedy chain within reach: nearest point of the needed kind towards B.
    route = [sc.start, sc.end]
    rep = replay(mission_through(sc.xyz[route], home=False), sc, runs=500)
    planned = evaluate_route(sc, route)
    assert rep.arrived == planned.feasible
    assert rep.monte_carlo.success_rate == (1.0 if planned.feasible else 0.0)
    assert math.isclose(rep.flown_length, planned.length, rel_tol=FLIGHT_TOLERANCE)


def test_a_flight_lost_by_chance_on_its_way_away_from_b_is_lost_by_its_corrections():
    """Flights on the INS estimate, each lost where a failed correction leaves too much error:
    the route turns away from B (its closest approach to B so far is at A, kilometres back), and
    each lost run is reported lost at the landmark where the limit broke, with the failed
    correction before it, not as a flight that missed the landmarks it met and passed far from
    B (a loss by chance counted as lost by the flight: dataset 2 on ArduPlane, 8 of 200)."""
    # A, P1 (V, unreliable), P2 (H), P3 (V), B behind A. DATASET1: alpha1 25, beta1 20,
    # theta 30, residual 5: a failure at P1 arrives at P3 with v = 5 + 12 + 8.9 > 25.
    xyz = np.array(
        [
            [0.0, 0.0, 5000.0],
            [12_000.0, 300.0, 5000.0],
            [24_000.0, 0.0, 5000.0],
            [16_000.0, 4000.0, 5000.0],
            [-2000.0, 0.0, 5000.0],
        ]
    )
    sc = Scenario(
        ids=("A", "P1", "P2", "P3", "B"),
        xyz=xyz,
        kind=np.array([Kind.A, Kind.V, Kind.H, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.array([False, True, False, False, False]),
        params=DATASET1,
        origin=ORIGIN,
    )
    route = list(range(sc.n))
    exact = success_probability(sc, route).probability
    assert exact == pytest.approx(sc.params.p_success)
    items = mission_through(sc.xyz, home=True)
    rep = replay(items, sc, home_at_seq0=True, navigate_on_estimate=True, runs=30, seed=3)
    mc = rep.monte_carlo
    assert mc is not None and mc.flown
    assert 0 < mc.runs - mc.successes < mc.runs  # some runs lost, by their failure at P1
    assert mc.flight_losses == 0 and mc.correction_losses == mc.runs - mc.successes
    assert all(not r.missed and r.failed == ("P1",) for r in mc.lost_runs)
