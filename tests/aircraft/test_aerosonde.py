"""The aerosonde (issue 52): the project's JSBSim airframe from Beard & McLain's coefficients
loads and trims where a small maritime UAV flies, and ``plan --aircraft`` derives the envelope
from its trims (and another airframe's trims give another envelope)."""

from __future__ import annotations

import json
import math

# The test extra installs JSBSim: without it these tests fail at import, never skip.
import jsbsim  # noqa: F401
import pytest
from gcs_planner.sim import atmosphere  # noqa: E402
from gcs_planner.sim.jsbsim_trim import FT, _new_fdm, available_aircraft, trim  # noqa: E402
from support.coast_copy import coast_copy
from support.paths import MISSIONS

from gcs_planner.aircraft.airframe_trim import (  # noqa: E402
    GAMMA_SEARCH_DEG,
    STALL_MARGIN,
    airframe_trims,
)
from gcs_planner.aircraft.autopilot import effective  # noqa: E402
from gcs_planner.aircraft.shipped_airframes import AIRFRAMES_DIR, shipped_airframes  # noqa: E402
from gcs_planner.cli import main  # noqa: E402

COAST = MISSIONS / "coast"


def test_the_aerosonde_is_shipped_with_its_engine_files():
    assert "aerosonde" in shipped_airframes() and "aerosonde" in available_aircraft()
    folder = AIRFRAMES_DIR / "aerosonde"
    assert (folder / "aerosonde.xml").is_file()
    assert {p.name for p in (folder / "Engines").iterdir()} >= {
        "aerosonde_motor.xml",
        "aerosonde_direct.xml",
    }


@pytest.mark.parametrize(
    ("altitude", "eas"),
    # 25 m/s EAS at 5 km takes all of its throttle (the supplement's motor): not a steady test
    [(1000.0, 16.0), (1000.0, 20.0), (1000.0, 25.0), (5000.0, 16.0), (5000.0, 20.0)],
)
def test_the_aerosonde_trims_and_holds_its_airspeed_at_1_and_5_km(altitude, eas):
    fdm = _new_fdm("aerosonde", 60.0)
    got = trim(fdm, altitude, eas)
    assert got is not None, f"no trim at {eas} m/s EAS at {altitude} m"
    assert 0.0 < got.throttle < 1.0
    tas = eas * atmosphere.eas2tas(altitude)
    assert fdm["velocities/vt-fps"] * FT == pytest.approx(tas, abs=0.05)
    # Trimmed means steady: 10 s on the trim's controls, nothing steering it.
    for _ in range(600):
        fdm.run()
    assert fdm["velocities/vt-fps"] * FT == pytest.approx(tas, abs=0.5)
    assert fdm["position/h-sl-ft"] * FT == pytest.approx(altitude, abs=5.0)
    assert abs(fdm["attitude/phi-deg"]) < 1.0


def _thrust_n(fdm) -> float:
    """The supplement's propeller thrust (N) from the airframe's own properties."""
    n = fdm["propulsion/aerosonde/n-rev_sec"]
    return fdm["propulsion/aerosonde/rho-si"] * n * n * 0.508**4 * fdm["propulsion/aerosonde/CT"]


@pytest.mark.parametrize("altitude", [0.0, 1000.0, 5000.0])
def test_the_static_thrust_is_a_fraction_of_the_weight_and_falls_with_the_air(altitude):
    """The supplement's battery, motor and propeller: at full throttle standing still the
    propeller pulls well under the weight (the book's propeller pulled 6 times it), and less
    where the air is thinner; at full throttle the motor turns faster than at half."""
    fdm = _new_fdm("aerosonde", 60.0)
    fdm["ic/h-sl-ft"] = altitude / FT
    fdm["ic/vt-fps"] = 0.0
    fdm.run_ic()
    got = []
    for throttle in (0.5, 1.0):
        fdm["fcs/throttle-cmd-norm"] = throttle
        fdm.run()
        fdm.run()
        got.append((fdm["propulsion/aerosonde/omega-rad_sec"], _thrust_n(fdm)))
    weight = fdm["inertia/weight-lbs"] * 4.44822
    (half_omega, half), (omega, full) = got
    assert omega > half_omega > 0.0 and full > half > 0.0
    assert 0.3 * weight < full < 0.8 * weight
    if altitude > 0.0:
        assert full < 0.75 * weight


@pytest.mark.parametrize("altitude", [1000.0, 5000.0])
def test_below_its_stall_the_aerosonde_does_not_trim(altitude):
    """The stall is where the weight needs the wing's greatest lift coefficient (1.632 in the
    model, the XML's alphalimits), at the airframe's own weight and wing area: it trims just
    above it and not below, at any altitude (the stall is an equivalent airspeed)."""
    fdm = _new_fdm("aerosonde", 60.0)
    weight = fdm["inertia/weight-lbs"] * 4.44822
    area = fdm["metrics/Sw-sqft"] * FT * FT
    stall = math.sqrt(2.0 * weight / (1.225 * area * 1.632))
    assert trim(fdm, altitude, stall - 0.5) is None
    assert trim(fdm, altitude, stall + 0.3) is not None


def test_the_envelope_figures_come_from_the_airframe_s_trims():
    aero = airframe_trims("aerosonde", 1000.0)
    c172 = airframe_trims("c172r", 1000.0)
    # Stall, cruise and everything derived from them differ with the airframe.
    assert c172.stall_eas > aero.stall_eas + 8.0
    for t in (aero, c172):
        assert t.cruise_eas == math.ceil(STALL_MARGIN * t.stall_eas * 2.0) / 2.0
        assert t.cruise_tas == pytest.approx(t.cruise_eas * atmosphere.eas2tas(1000.0))
    # The aerosonde's bank is where its wing carries 1/cos(bank) at the stall, cos(bank) =
    # (Vs/V)^2; the c172r's turn trim (JSBSim's, with the turn's drag) stops short of that, at
    # the engine's power.
    assert math.cos(math.radians(aero.bank_deg)) == pytest.approx(
        (aero.stall_eas / aero.cruise_eas) ** 2, abs=0.02
    )
    assert 20.0 < c172.bank_deg < math.degrees(math.acos((c172.stall_eas / c172.cruise_eas) ** 2))
    # The supplement's motor climbs a few m/s, within the search (the book's propeller climbed
    # at 30 deg and more); the c172r's engine a few degrees.
    assert aero.climb_deg < GAMMA_SEARCH_DEG and 2.0 < aero.climb_rate < 10.0
    assert 2.0 < c172.climb_deg < 10.0 and c172.climb_rate < aero.climb_rate
    assert aero.sink_deg > 5.0 and c172.sink_deg < aero.sink_deg
    # Aloft the same EAS is a faster TAS, and the thinner air gives the propeller less thrust:
    # the climb falls with height; faster, it falls too (the propeller's thrust falls with
    # the advance ratio while the drag grows).
    high = airframe_trims("aerosonde", 5000.0)
    assert high.cruise_tas > aero.cruise_tas and high.climb_rate < aero.climb_rate
    fast = airframe_trims("aerosonde", 1000.0, 25.0)
    assert fast.throttle > aero.throttle and fast.climb_deg < aero.climb_deg


def _unstated(tmp_path, lift: float = 0.0, scale: float = 1.0, keep_vehicle: bool = False):
    """missions/coast without its stated envelope ([vehicle]; with it, ``keep_vehicle``), its
    altitudes scaled by ``scale`` and lifted by ``lift`` m: the plan derives an envelope."""
    return coast_copy(tmp_path, scale=scale, lift=lift, keep_vehicle=keep_vehicle)


def _planned(capsys, path, *flags):
    rc = main(["plan", str(path), "--json", *flags])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return json.loads(out), err


def test_plan_with_an_aircraft_derives_its_envelope_from_the_trims(tmp_path, capsys):
    path = _unstated(tmp_path, lift=-200.0)  # coast lowered: its top at 3,166 m
    aero = airframe_trims("aerosonde", 3166.07)
    d, err = _planned(capsys, path, "--aircraft", "aerosonde")
    assert "the aerosonde trims at 3,166 m" in err and f"stall {aero.stall_eas:.1f}" in err
    env = d["vehicle"]["envelope"]
    ap = effective("ardupilot", {})
    # The cruise airspeed is the airframe's; the bank and rates the lesser of its and the
    # autopilot's (ArduPlane's shipped ROLL_LIMIT_DEG, TECS_CLMB_MAX, TECS_SINK_MAX).
    assert env["cruise_eas"] == aero.cruise_eas
    assert env["bank_limit_deg"] == pytest.approx(min(aero.bank_deg, ap.bank_limit))
    assert env["climb_rate"] == pytest.approx(min(aero.climb_rate, ap.climb_rate))
    assert env["sink_rate"] == pytest.approx(min(aero.sink_rate, ap.sink_rate))
    assert set(env["sources"].values()) == {"the aerosonde airframe's trims"}
    plain, _ = _planned(capsys, path)
    assert plain != d  # the airframe's envelope plans another front


def test_another_airframe_plans_another_envelope(tmp_path, capsys):
    """Its altitudes a quarter (51-842 m), where the c172r flies too: its cruise, bank and
    rates are its own, and the plan's turning radius follows them."""
    path = _unstated(tmp_path, scale=0.25)
    aero, err_aero = _planned(capsys, path, "--aircraft", "aerosonde")
    c172, err_c172 = _planned(capsys, path, "--aircraft", "c172r")
    assert "the aerosonde trims at 842 m" in err_aero and "the c172r trims at 842 m" in err_c172
    a, c = aero["vehicle"]["envelope"], c172["vehicle"]["envelope"]
    assert c["cruise_eas"] == airframe_trims("c172r", 841.52).cruise_eas
    assert c["cruise_eas"] > a["cruise_eas"] + 10.0
    assert c["climb_rate"] < a["climb_rate"]  # the c172r's engine, not the autopilot, binds
    assert c["turn_radius"] > 2.0 * a["turn_radius"]


def test_a_stated_climb_steeper_than_the_airframe_s_is_planned_within_it(tmp_path, capsys):
    """missions/coast states 25 m/s and climbs of 15 deg; at a quarter of its altitudes (top
    842 m) the aerosonde climbs less than that at 25 m/s EAS: the plan climbs at the
    airframe's angle, and says so. At its full height (3,366 m) within the airframe's climb
    there is no route (the INS errors outgrow the helices): refused, exit 3."""
    path = _unstated(tmp_path, scale=0.25, keep_vehicle=True)
    aero = airframe_trims("aerosonde", 841.52, 25.0)
    assert aero.climb_deg < 15.0
    d, err = _planned(capsys, path, "--aircraft", "aerosonde")
    assert f"max_climb_angle 15 -> {aero.climb_deg:.2f} (the aerosonde's)" in err
    assert d["parameters"]["max_climb_angle"] == pytest.approx(aero.climb_deg)
    assert d["parameters"]["max_descent_angle"] == pytest.approx(min(15.0, aero.sink_deg))
    assert d["vehicle"]["cruise_airspeed"] == 25.0  # the stated one, trimmed at
    stated, _ = _planned(capsys, path)
    assert stated != d
    full = airframe_trims("aerosonde", 3366.07, 25.0)
    rc = main(["plan", str(COAST / "scenario.toml"), "--aircraft", "aerosonde"])
    _, err = capsys.readouterr()
    assert rc == 3 and f"max_climb_angle 15 -> {full.climb_deg:.2f}" in err
    assert "no feasible route" in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (["--aircraft", "nosuch"], "no JSBSim aircraft 'nosuch'"),
        (["--aircraft", "c172r"], "the c172r trims level at no airspeed"),  # coast's 3.4 km
    ],
)
def test_an_airframe_that_cannot_be_used_is_one_line_and_exit_2(tmp_path, capsys, flags, says):
    rc = main(["plan", str(_unstated(tmp_path)), *flags])
    _, err = capsys.readouterr()
    assert rc == 2
    assert says in err and "--aircraft" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
