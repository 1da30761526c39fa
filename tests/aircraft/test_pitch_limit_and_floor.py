"""The autopilot's pitch limit and ground-speed floor in the planner's derived envelope
(gcs_planner/aircraft/derive.py ``within_pitch_limit``, ``with_ground_speed_floor``;
profile.py ``DerivedEnvelope.tas_flown``)."""

from __future__ import annotations

import math

import pytest

from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4, effective
from gcs_planner.aircraft.derive import pitch_limit, with_ground_speed_floor, within_pitch_limit
from gcs_planner.aircraft.profile import DerivedEnvelope, G


def envelope(eas: float, climb: float, wind: float = 0.0, low: float = 0.0) -> DerivedEnvelope:
    return DerivedEnvelope(
        eas, 45.0, climb, 5.0, wind, None, 5000.0, None, (("max_climb_rate", "flag"),),
        low_altitude=low,
    )  # fmt: skip


def air_path_deg(env: DerivedEnvelope, tas: float) -> float:
    return math.degrees(math.asin(env.climb_rate / tas))


def test_arduplanes_climb_keeps_within_tecs_pitch_max():
    """ArduPlane's shipped 5 m/s at 12 m/s EAS is 24.6 deg of flight path at sea level: over
    TECS_PITCH_MAX 15 deg, so the rate is capped to 12 sin 15 deg, and every leg's angle, at
    its own TAS and ground speed, is within 15 deg."""
    flier = effective(ARDUPLANE.firmware, {})
    assert pitch_limit(flier) == 15.0
    env = within_pitch_limit(envelope(12.0, 5.0), flier, set())
    assert env.climb_rate == pytest.approx(12.0 * math.sin(math.radians(15.0)))
    assert air_path_deg(env, env.tas_low) == pytest.approx(15.0)
    assert env.climb_angle <= 15.0
    assert dict(env.sources)["max_climb_rate"].startswith("flag, capped by TECS_PITCH_MAX 15 deg")
    # TECS_PITCH_MAX 0 takes PTCH_LIM_MAX_DEG; any other value is capped by it.
    assert pitch_limit(effective(ARDUPLANE.firmware, {"TECS_PITCH_MAX": 0.0})) == 20.0
    assert pitch_limit(effective(ARDUPLANE.firmware, {"TECS_PITCH_MAX": 30.0})) == 20.0


def test_px4s_shipped_limit_does_not_bind_and_a_stated_angle_is_left_alone():
    flier = effective(PX4.firmware, {})
    assert pitch_limit(flier) == 30.0
    env = envelope(15.0, 5.0)
    assert within_pitch_limit(env, flier, set()) == env  # asin(5 / 15) = 19.5 deg < 30
    tight = effective(PX4.firmware, {"FW_P_LIM_MAX": 10.0})
    capped = within_pitch_limit(env, tight, set())
    assert capped.climb_rate == pytest.approx(15.0 * math.sin(math.radians(10.0)))
    assert within_pitch_limit(env, tight, {"max_climb_angle"}) == env
    assert within_pitch_limit(env, None, set()) == env


@pytest.mark.parametrize(
    ("wind", "tas"), [(8.0, 15.0), (12.0, 17.0), (18.0, 20.0)],
    ids=["enough ground speed", "raised", "at FW_AIRSPD_MAX"],
)  # fmt: skip
def test_px4s_floor_widens_the_turns_in_a_headwind(wind, tas):
    """PX4 at 15 m/s near the sea: into more than 15 - 5 m/s of headwind it flies W + 5 (at
    most FW_AIRSPD_MAX 20), and the turning radius is that TAS plus the wind, squared, over
    g tan(bank)."""
    still = DerivedEnvelope(15.0, 45.0, 5.0, 5.0, wind, None, 0.0, None)
    env = with_ground_speed_floor(still, effective(PX4.firmware, {}))
    assert env.ground_speed_floor == 5.0 and env.airspeed_max == 20.0
    assert env.tas_flown == pytest.approx(tas)
    assert env.turn_radius == pytest.approx((tas + wind) ** 2 / G)
    assert env.turn_radius >= still.turn_radius


def test_arduplanes_floor_is_off_unless_set():
    env = DerivedEnvelope(12.0, 45.0, 5.0, 5.0, 10.0, None, 0.0, None)
    assert with_ground_speed_floor(env, effective(ARDUPLANE.firmware, {})).tas_flown == 12.0
    set_ = effective(ARDUPLANE.firmware, {"MIN_GNDSPD_CM": 600.0})
    assert with_ground_speed_floor(env, set_).tas_flown == pytest.approx(16.0)
