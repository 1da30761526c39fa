"""The lateral guidance both navigators steer by: L1 on a line and on a circle, on the ground
velocity (sim/navigators/base.py has the why and the sources).

Each law takes the estimate of where the aircraft is, its ground course and speed, and gives
the lateral acceleration (m/s^2, + left) it asks for; the compiled flight (sim/flight_kernel.py)
evaluates the same formulas in the same order.
"""

from __future__ import annotations

import math

from gcs_planner.aircraft.autopilot import ARDUPLANE

# ArduPlane's shipped NAVL1_PERIOD (s) and NAVL1_DAMPING: the guidance of both navigators.
L1_PERIOD_S = ARDUPLANE.defaults["NAVL1_PERIOD"]
L1_DAMPING = ARDUPLANE.defaults["NAVL1_DAMPING"]


def wrap(a: float) -> float:
    """The angle ``a`` (rad) in [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def l1_line(
    position: tuple[float, ...], course: float, ground_speed: float, a: tuple, b: tuple
) -> tuple[float, bool]:
    """(lateral acceleration of L1 guidance on the line a -> b, settled: on the track and along
    it) for an aircraft at ``position`` (x, y first) flying ``course`` (rad) at
    ``ground_speed`` (m/s)."""
    v = ground_speed
    x, y = position[0], position[1]
    l1 = L1_DAMPING * L1_PERIOD_S * v / math.pi
    abx, aby = b[0] - a[0], b[1] - a[1]
    n = math.hypot(abx, aby)
    if n < 1e-6:
        abx, aby = b[0] - x, b[1] - y
        n = math.hypot(abx, aby) or 1.0
    ux, uy = abx / n, aby / n
    ax, ay = x - a[0], y - a[1]
    cx, cy = math.cos(course), math.sin(course)
    dist_a = math.hypot(ax, ay)
    along = ax * ux + ay * uy
    settled = False
    if dist_a > l1 and along < -0.7071 * dist_a:
        # Behind the start of the leg and far: head for it (AP_L1_Control).
        nu = wrap(math.atan2(-ay, -ax) - course)
    else:
        xtrack = ux * ay - uy * ax  # > 0: left of the track
        nu1 = math.asin(max(-0.7071, min(0.7071, xtrack / l1)))
        eta = math.atan2(ux * cy - uy * cx, ux * cx + uy * cy)  # course left of track: > 0
        nu = -(nu1 + eta)
        settled = abs(xtrack) < 0.5 and abs(eta) < 0.005
    nu = max(-math.pi / 2, min(math.pi / 2, nu))
    k = 4.0 * L1_DAMPING * L1_DAMPING
    return k * v * v / l1 * math.sin(nu), settled


def circle(
    position: tuple[float, ...],
    course: float,
    ground_speed: float,
    centre: tuple,
    radius: float,
    direction: int,
) -> float:
    """Lateral acceleration holding a circle of ``radius`` about ``centre`` (``direction`` +1
    counter-clockwise, -1 clockwise): the centripetal term of the ground speed plus L1 on the
    tangent's course with an intercept angle."""
    v = ground_speed
    l1 = L1_DAMPING * L1_PERIOD_S * v / math.pi
    rx, ry = position[0] - centre[0], position[1] - centre[1]
    r = math.hypot(rx, ry)
    theta = math.atan2(ry, rx)
    intercept = math.atan((r - radius) / (0.5 * l1))
    want = theta + direction * (math.pi / 2 + intercept)
    err = wrap(want - course)
    ff = direction * v * v / radius if radius > 0 and abs(r - radius) < l1 else 0.0
    k = 4.0 * L1_DAMPING * L1_DAMPING
    return ff + k * v * v / l1 * math.sin(max(-math.pi / 2, min(math.pi / 2, err)))
