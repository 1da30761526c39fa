"""A route's flight time in the design wind, and a lower bound of the time still needed to
reach B from each point (docs/model.md, "Endurance in the plan").

A leg's flight time is its flown length over the ground speed along its chord: the TAS the
aircraft holds at the leg's mean altitude (the envelope's EAS, else the cruise airspeed, by ISA)
plus the design wind along the chord, W cos b + sqrt(V^2 - W^2 sin^2 b) with b the chord's
angle off downwind. A design wind of no stated direction is taken as a headwind on every leg
(V - W), the slowest it can be. A leg the aircraft cannot make good over the ground (a wind at
least its airspeed) takes forever.

The bound: every leg is at least as long as its chord, so chord / ground speed along it bounds
the leg's time from below, and the least sum of those over any chain of points to B (Dijkstra
over every pair of points) bounds the time of every route still to fly from there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from gcs_planner.aircraft.atmosphere import density_ratios
from gcs_planner.core.route import Route
from gcs_planner.geometry.leg_envelope import wind_towards
from gcs_planner.scenario.model import Scenario


def _airspeeds(scenario: Scenario, z: np.ndarray) -> np.ndarray:
    """TAS (m/s) at scenario altitudes ``z``: the derived envelope's EAS, else the cruise
    airspeed, by ISA (both autopilots hold the airspeed they are given as EAS:
    aircraft/profile.py ``tas_at``)."""
    env = scenario.envelope
    eas = float(scenario.cruise_airspeed if env is None else env.eas)
    base = scenario.origin.alt if scenario.origin else 0.0
    return eas / np.sqrt(density_ratios(np.asarray(z, float) + base))


def _design_wind(scenario: Scenario) -> tuple[float, np.ndarray | None]:
    """(speed m/s, (east, north) vector it blows towards or None when from any direction)."""
    env = scenario.envelope
    if env is None or float(env.wind) <= 0.0:
        return 0.0, np.zeros(2)
    if env.wind_from is None:
        return float(env.wind), None
    return float(env.wind), wind_towards(float(env.wind), float(env.wind_from))


def ground_speeds(scenario: Scenario, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Ground speed (m/s) along each chord from ``starts`` to ``ends`` ((m, 3) or (3,), each
    broadcast against the other) in the design wind, at the TAS of each chord's mean altitude;
    0 where the wind leaves none."""
    starts = np.atleast_2d(np.asarray(starts, float))
    ends = np.atleast_2d(np.asarray(ends, float))
    v = _airspeeds(scenario, 0.5 * (ends[:, 2] + starts[:, 2]))
    speed, towards = _design_wind(scenario)
    if speed == 0.0:
        return v
    if towards is None:
        return np.maximum(v - speed, 0.0)
    d = ends[:, :2] - starts[:, :2]
    h = np.hypot(d[:, 0], d[:, 1])
    along = (d[:, 0] * towards[0] + d[:, 1] * towards[1]) / (speed * np.where(h > 0, h, 1.0))
    # A vertical chord (no track): the slowest ground speed any heading gives.
    cos_b = np.where(h > 0, np.clip(along, -1.0, 1.0), -1.0)
    cross = v * v - speed * speed * (1.0 - cos_b * cos_b)
    vg = speed * cos_b + np.sqrt(np.maximum(cross, 0.0))
    return np.where((cross >= 0.0) & (vg > 0.0), vg, 0.0)


def _seconds(length: np.ndarray, vg: np.ndarray) -> np.ndarray:
    return np.where(vg > 0.0, np.asarray(length, float) / np.where(vg > 0.0, vg, 1.0), math.inf)


def leg_seconds(scenario: Scenario, i: int, j: int, length: float) -> float:
    """Flight time (s) of a leg of flown ``length`` from point ``i`` to point ``j``."""
    xyz = scenario.xyz
    vg = ground_speeds(scenario, xyz[i], xyz[j])
    return float(_seconds(np.array([length]), vg)[0])


def route_seconds(scenario: Scenario, points: Sequence[int], lengths: Sequence[float]) -> float:
    """Flight time (s) of the route through ``points`` whose legs are ``lengths`` long."""
    return float(
        sum(leg_seconds(scenario, a, b, d) for a, b, d in zip(points, points[1:], lengths))
    )


def route_minutes(scenario: Scenario, route: Route) -> float:
    """Flight time (minutes) of a planned route (its stops' legs) in the design wind."""
    lengths = [s.leg.length if s.leg is not None else 0.0 for s in route.stops[1:]]
    return route_seconds(scenario, route.points, lengths) / 60.0


def seconds_to_b(scenario: Scenario) -> np.ndarray:
    """Per point, a lower bound (s) of the time any route from it to B needs: the least sum of
    chord times over chains of points to B (Dijkstra over every pair). inf: B cannot be made
    good from it in the design wind."""
    xyz, n, end = scenario.xyz, scenario.n, scenario.end
    best = np.full(n, math.inf)
    best[end] = 0.0
    done = np.zeros(n, bool)
    for _ in range(n):
        open_ = np.where(done, math.inf, best)
        j = int(np.argmin(open_))
        if not math.isfinite(open_[j]):
            break
        done[j] = True
        # Legs from every point into j: chord over the ground speed along it.
        chords = np.linalg.norm(xyz[j] - xyz, axis=1)
        vg = ground_speeds(scenario, xyz, xyz[j])
        through = best[j] + _seconds(chords, vg)
        best = np.where(done, best, np.minimum(best, through))
    return best
