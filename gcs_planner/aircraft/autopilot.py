"""Each autopilot as one record: what ArduPlane and PX4 (fixed wing) are, in one place each rule.

A record holds what the ground station, the exporters and the mock vehicle need to agree on:
the MAV_AUTOPILOT id, whether the autopilot keeps home at mission seq 0, the parameter holding
the loiter radius, the acceptance rule and its parameters, the item a helix is written as, the
custom mode of the mission mode, and the parameters as the firmware ships them (default, type,
and the range within which the flight can use a value). :func:`effective` turns a parameter
table into the numbers a flight model reads (:class:`EffectiveParameters`).

Sources (read, modelled, not copied):

* ArduPlane 4.x: ``ArduPlane/Parameters.cpp`` (WP_RADIUS, WP_LOITER_RAD, ROLL_LIMIT_DEG,
  AIRSPEED_CRUISE), ``ArduPlane/config.h`` (AIRSPEED_CRUISE 12 m/s, WP_RADIUS_DEFAULT 90,
  LOITER_RADIUS_DEFAULT 60, HEAD_MAX 45), ``libraries/AP_TECS/AP_TECS.cpp`` ``var_info``
  (CLMB_MAX 5, SINK_MAX 5 m/s), ``libraries/AP_L1_Control/AP_L1_Control.cpp`` ``var_info``
  (PERIOD 17 s, DAMPING 0.75, LIM_BANK 0: loiter radii scaled by EAS2TAS^2),
  ``ArduPlane/mode.h`` (Mode::Number::AUTO = 10), ``ArduPlane/commands_logic.cpp``
  (``verify_nav_wp``: param2 acceptance radius, else WP_RADIUS, or the finish line);
* PX4 main: ``src/modules/fw_pos_control/fw_path_navigation_params.c`` (FW_R_LIM 50,
  FW_T_CLMB_MAX 5, FW_T_SINK_MAX 5, FW_T_CLMB_R_SP 3, FW_T_SINK_R_SP 2, NPFG_PERIOD 10,
  NPFG_DAMPING 0.7, NPFG_SW_DST_MLT 0.32), the airspeed parameters (FW_AIRSPD_TRIM 15),
  ``src/modules/navigator/navigator_params.c`` (NAV_LOITER_RAD 80, NAV_ACC_RAD 10; "for fixed
  wing the npfg switch distance is used for horizontal acceptance"),
  ``navigator_main.cpp`` ``Navigator::get_acceptance_radius`` (the larger of NAV_ACC_RAD and
  the position controller's switch distance), ``FixedwingPositionControl`` (missions climb and
  sink at FW_T_CLMB_R_SP / FW_T_SINK_R_SP, TECS bounding them by FW_T_CLMB_MAX /
  FW_T_SINK_MAX), ``px4_custom_mode.h`` (main mode AUTO 4, sub mode MISSION 4).

This module imports nothing of the planner, the link or the simulator (like
:mod:`gcs_planner.aircraft.profile`, which states its words from it), so every room can import it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

# MAV_PARAM_TYPE (common.xml): INT16 = 4, REAL32 = 9.
PARAM_TYPE_INT16 = 4
PARAM_TYPE_REAL32 = 9
INT16_MAX = 2**15 - 1

# MAVLink commands the records name (common.xml).
MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_LOITER_TURNS = 18
MAV_CMD_NAV_LOITER_TO_ALT = 31


@dataclass(frozen=True)
class ParamSpec:
    """One parameter as the firmware ships it: its default, MAVLink type, and the range a value
    must lie in for the flight to use it (``low_open``: the low end itself is not usable, e.g. a
    roll limit of 0 deg; ``min_abs``: a signed value whose magnitude must reach this, e.g. a
    loiter radius whose sign is the turn's sense)."""

    name: str
    default: float
    ptype: int = PARAM_TYPE_REAL32
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    min_abs: float = 0.0
    unit: str = ""

    def refusal(self, value: float) -> str | None:
        """Why ``value`` cannot be this parameter's, or None when it can."""
        if not math.isfinite(value):
            return f"{self.name} {value!r} is not a number"
        if self.ptype == PARAM_TYPE_INT16:
            value = float(round(value))
        too_low = value <= self.low if self.low_open else value < self.low
        if too_low or value > self.high:
            low = "(" if self.low_open else "["
            return f"{self.name} {value:g} outside {low}{self.low:g}, {self.high:g}]"
        if abs(value) < self.min_abs:
            return f"{self.name} {value:g}: magnitude below {self.min_abs:g}"
        return None

    def stored(self, value: float) -> float:
        """The value as the autopilot stores it (an int16 parameter rounds)."""
        return float(round(value)) if self.ptype == PARAM_TYPE_INT16 else float(value)


@dataclass(frozen=True)
class MissionProtocol:
    """How an autopilot's mission protocol answers where the MAVLink spec leaves it open.

    ArduPilot: ``GCS_MAVLINK`` (``GCS_Common.cpp``) and ``MissionItemProtocol.cpp``; PX4:
    ``src/modules/mavlink/mavlink_mission.cpp`` (``MavlinkMissionManager``)."""

    # PX4 asks and answers in the spelling it last heard (MISSION_ITEM or MISSION_ITEM_INT,
    # ``_int_mode``); ArduPilot asks with the one request it always sends
    # (``MissionItemProtocol::queued_request_send``, MISSION_REQUEST) and takes either item.
    answers_in_heard_spelling: bool
    # ArduPilot lets the same system and component ids restart an upload in progress
    # (``MissionItemProtocol::handle_mission_count``); PX4 only the transfer's owner.
    restarts_upload_by_ids: bool
    # PX4 refuses a new MISSION_COUNT while items are still expected (``Mission upload busy``,
    # MAV_MISSION_ERROR), another ground station's with the same result, and asks again for
    # item 0 when its partner's count comes again before it (``handle_mission_count``);
    # ArduPilot refuses another's MAV_MISSION_DENIED.
    busy_while_receiving: bool
    # Which MISSION_ACK cancels an upload: PX4 only MAV_MISSION_OPERATION_CANCELLED; ArduPilot
    # any result but ACCEPTED.
    cancelled_only_by_cancel: bool
    # The answer to the final item sent again after the upload ended (a lost acknowledgement):
    # PX4 MAV_MISSION_ACCEPTED again; ArduPilot, no longer receiving, MAV_MISSION_ERROR.
    final_item_again: int
    # ArduPilot writes each item into the flown mission as it arrives; PX4 receives into the
    # storage it is not flying (dataman's other slot) and switches when complete.
    writes_in_place: bool
    # ArduPilot serves the mission as the file @MISSION/mission.dat over MAVLink FTP
    # (``AP_Filesystem_Mission``); PX4 sets the FTP bit for its file system only.
    serves_mission_file: bool
    # PX4 sets MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT in AUTOPILOT_VERSION.
    announces_mission_float: bool
    # PX4 takes a command only in the frame ``MavlinkMissionManager::parse_mavlink_mission_item``
    # maps it for (``mavlink_mission.cpp``: NAV items in a global frame, DO/CONDITION items in
    # frame MISSION) and refuses any other MAV_MISSION_UNSUPPORTED; ArduPilot stores a command
    # it knows whatever the frame (``AP_Mission::mavlink_int_to_mission_cmd``).
    commands_by_frame: bool = False
    # PX4 answers a download request only for the next item or the last one again and ends the
    # transfer with MISSION_ACK MAV_MISSION_ERROR on any other
    # (``MavlinkMissionManager::handle_mission_request_both``), so a client keeps one request
    # out; ArduPilot answers each request on its own, whatever came before
    # (``MissionItemProtocol::handle_mission_request_int``), so requests can be pipelined.
    requests_in_sequence: bool = False
    # An uploaded item other than the one asked for: PX4 ignores it ("Item sequence not
    # expected, ignore item", ``handle_mission_item_both``); ArduPilot answers
    # MAV_MISSION_INVALID_SEQUENCE (``MissionItemProtocol::handle_mission_item``).
    ignores_items_out_of_sequence: bool = False
    # How long the vehicle waits for an item before asking again (s): PX4 0.25
    # (MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT, mavlink_mission.h); ArduPilot 1 plus its radio's
    # stream slowdown (``MissionItemProtocol::update``, wp_recv_timeout_ms).
    request_resend_s: float = 1.0
    # How long a transfer may hear nothing before the vehicle ends it (s): PX4 5, downloads
    # too (MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT); ArduPilot 8, uploads only
    # (``MissionItemProtocol::upload_timeout_ms``).
    transfer_timeout_s: float = 8.0
    # PX4 answers with a status text only, no MISSION_ACK, what another ground station sends
    # during a transfer (partner id mismatch) and a download request or a clear while it is busy
    # ("Mission download request ignored, already active", "REJ. CMD: Busy", "IGN CLEAR CMD:
    # Busy"), and ends a timed-out transfer the same way ("Operation timeout"); ArduPilot
    # answers MAV_MISSION_DENIED (a clear: MAV_MISSION_ERROR) and a timed-out upload with
    # MISSION_ACK MAV_MISSION_OPERATION_CANCELLED (``MissionItemProtocol``).
    refuses_quietly: bool = False
    # ArduPilot keeps a position as a Location (whole centimetres, the frame as its altitude
    # reference) and gives every item back through ``AP_Mission::get_item`` (autocontinue 1,
    # x/y/z a command does not store 0), by the mission protocol
    # (``MissionItemProtocol_Waypoints::get_item``) as in its mission file; PX4 gives back its
    # ``mission_item_s`` (``format_mavlink_mission_item``: float altitude).
    stores_locations: bool = False


# MAV_MISSION_RESULT (common.xml)
MAV_MISSION_ACCEPTED = 0
MAV_MISSION_ERROR = 1


@dataclass(frozen=True)
class Autopilot:
    """One firmware: its ids, mission rules, mission mode and shipped parameters.

    ``envelope`` names the parameter behind each word of the flight envelope (cruise_airspeed,
    bank_limit, climb_rate, sink_rate, acceptance_radius) as the ground station reads it with
    ``plan --vehicle-from``; ``mission_climb`` the parameters a mission's climb and sink
    follow (PX4: the rate setpoints, bounded by the maxima).
    """

    firmware: str
    autopilot_id: int  # MAV_AUTOPILOT: ARDUPILOTMEGA 3, PX4 12
    home_at_seq0: bool  # ArduPilot keeps home as mission item 0; PX4 holds no home item
    loiter_radius_param: str
    acceptance_param: str  # the vehicle-wide acceptance radius
    helix_command: int  # the item a helix is written as (mission/builder.py)
    auto_custom_mode: int  # HEARTBEAT custom_mode of the mission mode
    params: tuple[ParamSpec, ...]
    envelope: Mapping[str, str]
    mission_climb: tuple[str, ...]  # climb then sink parameters a mission flies with
    mission_climb_bounds: tuple[str, ...] = ()  # PX4: the TECS maxima bounding them
    # The path follower's tuning: the settle distance (run-in and run-out), how late a turn is
    # entered and how much of a gust reaches the track are derived from it.
    guidance: tuple[str, ...] = ()
    # The airspeed range a commanded speed (DO_CHANGE_SPEED) must lie in, and what the autopilot
    # does with one outside it: ArduPlane ignores it, PX4 constrains it (see the params above).
    airspeed_range: tuple[str, str] = ("", "")
    speed_outside_range: str = "clamped"
    title: str = ""  # the name a reader knows it by
    code_name: str = ""  # the short name its code goes by ("ArduPlane's L1", "PX4's npfg")
    path_follower: str = ""  # "L1" (AP_L1_Control) or "npfg" (PX4's npfg)
    # ArduPlane counts a waypoint reached within its param2 (else WP_RADIUS); PX4 fixed wing
    # ignores param2 and uses the vehicle-wide NAV_ACC_RAD or npfg's switch distance.
    item_acceptance: bool = False
    # PX4 climbs at once towards its current item's altitude (FixedwingPositionControl's
    # altitude setpoint is the item's); ArduPlane slopes the altitude along the leg
    # (Plane::setup_glide_slope).
    climbs_at_once: bool = False
    # PX4 switches to the next item npfg's switch distance before it reaches the current one
    # (Navigator::get_acceptance_radius); ArduPlane at the item (or its finish line).
    switches_early: bool = False
    # ArduPlane widens a loiter with the true airspeed (radius * EAS2TAS^2) unless
    # NAVL1_LIM_BANK holds it (AP_L1_Control::loiter_radius).
    loiter_widens_with_tas: bool = False
    # PX4 ends a NAV_LOITER_TO_ALT on the altitude and only on its last turn's exit course
    # (mission_block.cpp): a helix at the leg's own limit has nothing to spare.
    helix_exits_on_course: bool = False
    # PX4 counts a waypoint reached only within NAV_FW_ALT_RAD of its altitude and circles it
    # until then (mission_block.cpp, MissionBlock::is_mission_item_reached_or_completed);
    # ArduPlane passes a waypoint at any altitude (commands_logic.cpp, Plane::verify_nav_wp).
    circles_for_altitude: bool = False
    # The altitude loop's parameters: the time constant TECS flies a height error out over,
    # the pitch limit of auto flight, and (ArduPlane) the limit that caps it and stands in for
    # a pitch limit of 0. ArduPlane AP_TECS.cpp (_update_pitch: SEB_error / timeConstant();
    # update_pitch_throttle: TECS_PITCH_MAX, 0 -> PTCH_LIM_MAX_DEG, else the smaller); PX4
    # TECS.cpp (_calcAltitudeControlOutput: height error / FW_T_ALT_TC) and
    # fw_path_navigation_params.c (FW_P_LIM_MAX, the pitch setpoint's limit).
    altitude_loop: tuple[str, ...] = ()
    # The ground-speed floor (parameter, m/s per unit): airspeed demand raised by the shortfall,
    # up to the largest airspeed. ArduPlane MIN_GNDSPD_CM (ArduPlane/navigation.cpp
    # calc_gndspeed_undershoot, added in Attitude.cpp calc_airspeed_errors); PX4 FW_GND_SPD_MIN
    # (FixedwingPositionControl.cpp get_auto_airspeed_setpoint, "groundspeed undershoot").
    ground_speed_floor: tuple[str, float] = ("", 1.0)
    # ArduPilot reads its radio's RADIO_STATUS and slows mission requests to match
    # (GCS_MAVLINK::handle_radio_status, stream_slowdown_ms).
    reads_radio_status: bool = False
    # A mode change it cannot make: PX4 answers MAV_RESULT_TEMPORARILY_REJECTED always
    # (Commander::handle_command); ArduPilot DENIED without the custom-mode flag, else FAILED
    # (GCS_MAVLINK::_set_mode_common).
    refuses_mode_temporarily: bool = False
    # ArduPilot runs Lua applets from its SD card's scripts folder (libraries/AP_Scripting,
    # lua_scripts.cpp); PX4 runs none, so its onboard switching is a companion's process.
    runs_lua_applets: bool = False
    protocol: MissionProtocol | None = None

    def commanded_airspeed(self, speed: float, values: Mapping[str, float]) -> float | None:
        """The airspeed the aircraft flies after a mission's DO_CHANGE_SPEED to ``speed`` (m/s)
        with the parameter table ``values`` (missing names: shipped defaults); None when the
        autopilot ignores the command (the previous airspeed stays)."""
        table = {**self.defaults, **values}
        low, high = (float(table[name]) for name in self.airspeed_range)
        if low <= speed <= high:
            return speed
        if self.speed_outside_range == "ignored":
            return None
        return min(max(speed, low), high)

    @property
    def defaults(self) -> dict[str, float]:
        return {p.name: p.default for p in self.params}

    def spec(self, name: str) -> ParamSpec | None:
        for p in self.params:
            if p.name == name:
                return p
        return None

    @property
    def loiter_radius_type(self) -> int:
        spec = self.spec(self.loiter_radius_param)
        assert spec is not None
        return spec.ptype

    def refusal(self, name: str, value: float) -> str | None:
        """Why this autopilot's flight cannot use ``value`` for ``name`` (None: it can, or the
        parameter is not one of the record's)."""
        spec = self.spec(name)
        return None if spec is None else spec.refusal(value)

    def is_auto_mode(self, base_mode: float, custom_main: float, custom_sub: float) -> bool:
        """Whether MAV_CMD_DO_SET_MODE's params 1-3 ask for this autopilot's mission mode.

        ArduPilot (``GCS_MAVLINK::_set_mode_common``): with MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        in param1, param2 is the mode number (Plane AUTO = 10). PX4 (``Commander``,
        ``handle_command`` for VEHICLE_CMD_DO_SET_MODE): param2 the main mode (AUTO = 4),
        param3 the sub mode (MISSION = 4)."""
        if not all(math.isfinite(v) for v in (base_mode, custom_main, custom_sub)):
            return False
        if not int(base_mode) & MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return False
        if self.auto_custom_mode < 1 << 16:  # ArduPilot: the mode number itself
            return int(custom_main) == self.auto_custom_mode
        main = (self.auto_custom_mode >> 16) & 0xFF
        sub = (self.auto_custom_mode >> 24) & 0xFF
        return int(custom_main) == main and int(custom_sub) == sub


MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
ARDUPLANE_MODE_AUTO = 10  # ArduPlane/mode.h, Mode::Number::AUTO
PX4_MAIN_MODE_AUTO = 4  # px4_custom_mode.h, PX4_CUSTOM_MAIN_MODE_AUTO
PX4_SUB_MODE_AUTO_MISSION = 4  # PX4_CUSTOM_SUB_MODE_AUTO_MISSION
# PX4 packs its modes into HEARTBEAT custom_mode: main mode in byte 2, sub mode in byte 3.
PX4_MODE_AUTO_MISSION = (PX4_MAIN_MODE_AUTO << 16) | (PX4_SUB_MODE_AUTO_MISSION << 24)

# A loiter or acceptance radius the ground station writes comes from the plan, not from a
# tuning list: the mock takes any radius a flight can fly (int16 metres, ArduPlane's storage),
# where PX4's metadata shows NAV_LOITER_RAD as 25..1000 (PX4 does not enforce metadata ranges
# on PARAM_SET, and a plan's radius outside them is still flown).
_RADIUS_MAX = float(INT16_MAX)

ARDUPLANE = Autopilot(
    firmware="ardupilot",
    autopilot_id=3,
    home_at_seq0=True,
    loiter_radius_param="WP_LOITER_RAD",
    acceptance_param="WP_RADIUS",
    helix_command=MAV_CMD_NAV_LOITER_TURNS,
    auto_custom_mode=ARDUPLANE_MODE_AUTO,
    params=(
        # AIRSPEED_CRUISE has no @Range; AIRSPEED_MIN / AIRSPEED_MAX are 5..100 m/s.
        ParamSpec("AIRSPEED_CRUISE", 12.0, low=5.0, high=100.0, unit="m/s"),
        # A mission's DO_CHANGE_SPEED outside AIRSPEED_MIN..AIRSPEED_MAX is ignored
        # (ArduPlane/commands_logic.cpp, Plane::do_change_speed): the aircraft stays at cruise.
        ParamSpec("AIRSPEED_MIN", 9.0, low=5.0, high=100.0, unit="m/s"),
        ParamSpec("AIRSPEED_MAX", 22.0, low=5.0, high=100.0, unit="m/s"),
        ParamSpec("ROLL_LIMIT_DEG", 45.0, low=0.0, high=90.0, low_open=True, unit="deg"),
        ParamSpec("TECS_CLMB_MAX", 5.0, low=0.1, high=20.0, unit="m/s"),
        ParamSpec("TECS_SINK_MAX", 5.0, low=0.0, high=20.0, low_open=True, unit="m/s"),
        # AP_TECS.cpp var_info: TIME_CONST 5 s (3..10), PITCH_MAX 15 deg (0..45, 0: use
        # PTCH_LIM_MAX_DEG; an AP_Int8: whole degrees); ArduPlane/Parameters.cpp
        # PTCH_LIM_MAX_DEG 20 deg (0..90), MIN_GNDSPD_CM 0 cm/s (off).
        ParamSpec("TECS_TIME_CONST", 5.0, low=3.0, high=10.0, unit="s"),
        ParamSpec("TECS_PITCH_MAX", 15.0, low=0.0, high=45.0, unit="deg"),
        ParamSpec("PTCH_LIM_MAX_DEG", 20.0, low=0.0, high=90.0, unit="deg"),
        ParamSpec("MIN_GNDSPD_CM", 0.0, low=0.0, high=10_000.0, unit="cm/s"),
        ParamSpec("WP_RADIUS", 90.0, PARAM_TYPE_INT16, low=1.0, high=_RADIUS_MAX, unit="m"),
        ParamSpec(
            "WP_LOITER_RAD",
            60.0,
            PARAM_TYPE_INT16,
            low=-_RADIUS_MAX,
            high=_RADIUS_MAX,
            min_abs=1.0,
            unit="m",
        ),
        ParamSpec("NAVL1_PERIOD", 17.0, low=1.0, high=60.0, unit="s"),
        ParamSpec("NAVL1_DAMPING", 0.75, low=0.6, high=1.0),
        ParamSpec("NAVL1_LIM_BANK", 0.0, low=0.0, high=89.0, unit="deg"),
    ),
    envelope={
        "cruise_airspeed": "AIRSPEED_CRUISE",
        "bank_limit": "ROLL_LIMIT_DEG",
        "climb_rate": "TECS_CLMB_MAX",
        "sink_rate": "TECS_SINK_MAX",
        "acceptance_radius": "WP_RADIUS",
    },
    mission_climb=("TECS_CLMB_MAX", "TECS_SINK_MAX"),
    guidance=("NAVL1_PERIOD", "NAVL1_DAMPING"),
    airspeed_range=("AIRSPEED_MIN", "AIRSPEED_MAX"),
    speed_outside_range="ignored",
    title="ArduPlane",
    code_name="ArduPlane",
    path_follower="L1",
    item_acceptance=True,
    altitude_loop=("TECS_TIME_CONST", "TECS_PITCH_MAX", "PTCH_LIM_MAX_DEG"),
    ground_speed_floor=("MIN_GNDSPD_CM", 0.01),
    loiter_widens_with_tas=True,
    reads_radio_status=True,
    runs_lua_applets=True,
    protocol=MissionProtocol(
        answers_in_heard_spelling=False,
        restarts_upload_by_ids=True,
        busy_while_receiving=False,
        cancelled_only_by_cancel=False,
        final_item_again=MAV_MISSION_ERROR,
        writes_in_place=True,
        serves_mission_file=True,
        announces_mission_float=False,
        commands_by_frame=False,
        requests_in_sequence=False,
        ignores_items_out_of_sequence=False,
        request_resend_s=1.0,
        transfer_timeout_s=8.0,
        refuses_quietly=False,
        stores_locations=True,
    ),
)

PX4 = Autopilot(
    firmware="px4",
    autopilot_id=12,
    home_at_seq0=False,
    loiter_radius_param="NAV_LOITER_RAD",
    acceptance_param="NAV_ACC_RAD",
    helix_command=MAV_CMD_NAV_LOITER_TO_ALT,
    auto_custom_mode=PX4_MODE_AUTO_MISSION,
    params=(
        # PX4's metadata shows the airspeeds as 0.5..40 m/s but PX4 does not enforce metadata
        # ranges on PARAM_SET: a faster airframe (the JSBSim c172r at 45 m/s) sets them higher,
        # so the flight's range is ArduPlane's 5..100 m/s.
        ParamSpec("FW_AIRSPD_TRIM", 15.0, low=0.5, high=100.0, unit="m/s"),
        # Every airspeed setpoint is constrained to FW_AIRSPD_MIN..FW_AIRSPD_MAX
        # (FixedwingPositionControl::adapt_airspeed_setpoint, the performance model's bounds).
        ParamSpec("FW_AIRSPD_MIN", 10.0, low=0.5, high=100.0, unit="m/s"),
        ParamSpec("FW_AIRSPD_MAX", 20.0, low=0.5, high=100.0, unit="m/s"),
        ParamSpec("FW_R_LIM", 50.0, low=35.0, high=65.0, unit="deg"),
        # Metadata shows the rates up to 15 m/s; PX4 takes more (metadata is not enforced) and
        # the flight uses up to ArduPlane's TECS range, 20 m/s.
        ParamSpec("FW_T_CLMB_MAX", 5.0, low=1.0, high=20.0, unit="m/s"),
        ParamSpec("FW_T_SINK_MAX", 5.0, low=1.0, high=20.0, unit="m/s"),
        ParamSpec("FW_T_CLMB_R_SP", 3.0, low=0.5, high=20.0, unit="m/s"),
        ParamSpec("FW_T_SINK_R_SP", 2.0, low=0.5, high=20.0, unit="m/s"),
        # fw_path_navigation_params.c: FW_T_ALT_TC 5 s (min 2), FW_P_LIM_MAX 30 deg (0..60),
        # FW_GND_SPD_MIN 5 m/s (0..40).
        ParamSpec("FW_T_ALT_TC", 5.0, low=2.0, unit="s"),
        ParamSpec("FW_P_LIM_MAX", 30.0, low=0.0, high=60.0, unit="deg"),
        ParamSpec("FW_GND_SPD_MIN", 5.0, low=0.0, high=40.0, unit="m/s"),
        ParamSpec("NAV_LOITER_RAD", 80.0, low=1.0, high=_RADIUS_MAX, unit="m"),
        ParamSpec("NAV_ACC_RAD", 10.0, low=0.05, high=200.0, unit="m"),
        ParamSpec("NPFG_PERIOD", 10.0, low=1.0, high=100.0, unit="s"),
        ParamSpec("NPFG_DAMPING", 0.7, low=0.1, high=1.0),
        ParamSpec("NPFG_SW_DST_MLT", 0.32, low=0.1, high=1.0),
    ),
    envelope={
        "cruise_airspeed": "FW_AIRSPD_TRIM",
        "bank_limit": "FW_R_LIM",
        "climb_rate": "FW_T_CLMB_MAX",
        "sink_rate": "FW_T_SINK_MAX",
        "acceptance_radius": "NAV_ACC_RAD",
    },
    mission_climb=("FW_T_CLMB_R_SP", "FW_T_SINK_R_SP"),
    mission_climb_bounds=("FW_T_CLMB_MAX", "FW_T_SINK_MAX"),
    guidance=("NPFG_PERIOD", "NPFG_DAMPING", "NPFG_SW_DST_MLT"),
    airspeed_range=("FW_AIRSPD_MIN", "FW_AIRSPD_MAX"),
    speed_outside_range="clamped",
    title="PX4 fixed wing",
    code_name="PX4",
    path_follower="npfg",
    climbs_at_once=True,
    switches_early=True,
    helix_exits_on_course=True,
    circles_for_altitude=True,
    altitude_loop=("FW_T_ALT_TC", "FW_P_LIM_MAX"),
    ground_speed_floor=("FW_GND_SPD_MIN", 1.0),
    refuses_mode_temporarily=True,
    protocol=MissionProtocol(
        answers_in_heard_spelling=True,
        restarts_upload_by_ids=False,
        busy_while_receiving=True,
        cancelled_only_by_cancel=True,
        final_item_again=MAV_MISSION_ACCEPTED,
        writes_in_place=False,
        serves_mission_file=False,
        announces_mission_float=True,
        commands_by_frame=True,
        requests_in_sequence=True,
        ignores_items_out_of_sequence=True,
        request_resend_s=0.25,
        transfer_timeout_s=5.0,
        refuses_quietly=True,
        stores_locations=False,
    ),
)

AUTOPILOTS: dict[str, Autopilot] = {ap.firmware: ap for ap in (ARDUPLANE, PX4)}
# The autopilot a command flies for when none is named: ArduPlane, the one most maritime
# fixed-wing fleets run.
DEFAULT_AUTOPILOT = ARDUPLANE.firmware


def keeps_home_item(firmware: str | None) -> bool:
    """Whether ``firmware`` keeps its home as mission item 0 (ArduPilot: the .waypoints home
    row, the read-back's skipped item 0); False for PX4 and for an autopilot without a
    record."""
    ap = AUTOPILOTS.get(firmware or "")
    return ap is not None and ap.home_at_seq0


def autopilot_for(firmware: str) -> Autopilot:
    """The record of ``firmware`` ("ardupilot" or "px4"); ValueError otherwise."""
    try:
        return AUTOPILOTS[firmware]
    except KeyError:
        known = ", ".join(AUTOPILOTS)
        raise ValueError(f"firmware must be one of {known}, got {firmware!r}") from None


@dataclass(frozen=True)
class EffectiveParameters:
    """What a flight under this autopilot flies with, from its parameter table.

    ``climb_rate`` / ``sink_rate`` (m/s) are the rates a mission climbs and sinks at: ArduPlane
    TECS_CLMB_MAX / TECS_SINK_MAX; PX4 FW_T_CLMB_R_SP / FW_T_SINK_R_SP, bounded by
    FW_T_CLMB_MAX / FW_T_SINK_MAX. ``bank_limit`` (deg): ROLL_LIMIT_DEG / FW_R_LIM.
    ``loiter_radius`` (m, signed: + clockwise), ``acceptance_radius`` (m, the vehicle-wide one:
    WP_RADIUS / NAV_ACC_RAD). ArduPlane only: ``l1_period``, ``l1_damping``,
    ``loiter_bank_limit`` (NAVL1_LIM_BANK; 0 scales loiter radii by EAS2TAS^2). PX4 only:
    ``npfg_period``, ``npfg_damping``, ``npfg_switch_multiplier``. ``values``: the whole table.
    """

    firmware: str
    cruise_airspeed: float
    bank_limit: float
    climb_rate: float
    sink_rate: float
    loiter_radius: float
    acceptance_radius: float
    values: Mapping[str, float]
    l1_period: float | None = None
    l1_damping: float | None = None
    loiter_bank_limit: float | None = None
    npfg_period: float | None = None
    npfg_damping: float | None = None
    npfg_switch_multiplier: float | None = None

    def guidance_loop(self) -> tuple[float, float]:
        """(period s, damping) of the path follower's lateral loop: NAVL1_PERIOD / NAVL1_DAMPING
        or NPFG_PERIOD / NPFG_DAMPING."""
        if self.l1_period is not None and self.l1_damping is not None:
            return self.l1_period, self.l1_damping
        assert self.npfg_period is not None and self.npfg_damping is not None
        return self.npfg_period, self.npfg_damping

    def switch_distance(self, ground_speed: float) -> float:
        """PX4: the npfg switch distance at ``ground_speed`` (m/s), NPFG_PERIOD * NPFG_DAMPING
        (the track error bound's time constant) * NPFG_SW_DST_MLT * ground speed (``npfg.cpp``
        ``switchDistance`` / ``trackErrorBound``); 0 for ArduPlane, which has none."""
        if self.npfg_period is None or self.npfg_damping is None:
            return 0.0
        assert self.npfg_switch_multiplier is not None
        t = self.npfg_period * self.npfg_damping
        return max(ground_speed, 0.0) * t * self.npfg_switch_multiplier

    def settle_distance(self, ground_speed: float) -> float:
        """The straight line (m) the autopilot's path follower needs to settle on a track after a
        turn, at ``ground_speed`` m/s: its lateral time constant times the ground speed.

        ArduPlane: the L1 distance NAVL1_PERIOD * NAVL1_DAMPING * V / pi
        (``AP_L1_Control::update_waypoint``, ``_L1_dist``): the L1 point runs that far ahead on
        the track, so the aircraft closes onto it over about that distance. PX4: npfg's track
        error bound NPFG_PERIOD * NPFG_DAMPING * V (``npfg.cpp`` ``trackErrorBound``), the
        distance off track within which it steers along the path rather than towards it; its
        switch distance is NPFG_SW_DST_MLT (0.32) of it, so a run-out this long also keeps the
        next turn beyond the landmark."""
        v = max(ground_speed, 0.0)
        if self.l1_period is not None and self.l1_damping is not None:
            return self.l1_period * self.l1_damping * v / math.pi
        if self.npfg_period is not None and self.npfg_damping is not None:
            return self.npfg_period * self.npfg_damping * v
        return 0.0

    def waypoint_acceptance(self, ground_speed: float, item_radius: float = 0.0) -> float:
        """The horizontal distance at which the autopilot counts a waypoint reached.

        ArduPlane (``Plane::verify_nav_wp``): the item's param2 when > 0, else WP_RADIUS (and
        the finish line, which the flight model draws itself). PX4 fixed wing
        (``Navigator::get_acceptance_radius``): the larger of NAV_ACC_RAD and the npfg switch
        distance; a waypoint's param2 is not used for a fixed wing."""
        if autopilot_for(self.firmware).item_acceptance:
            return item_radius if item_radius > 0 else self.acceptance_radius
        return max(self.acceptance_radius, self.switch_distance(ground_speed))


def effective(firmware: str, values: Mapping[str, float]) -> EffectiveParameters:
    """The parameters a flight under ``firmware`` uses, from ``values`` (name -> value; a name
    missing takes the shipped default)."""
    ap = autopilot_for(firmware)
    table = {**ap.defaults, **{k: float(v) for k, v in values.items()}}

    def get(name: str) -> float:
        return table[name]

    climb, sink = (get(n) for n in ap.mission_climb)
    if ap.mission_climb_bounds:
        climb_max, sink_max = (get(n) for n in ap.mission_climb_bounds)
        climb, sink = min(climb, climb_max), min(sink, sink_max)
    env = ap.envelope
    common = {
        "firmware": firmware,
        "cruise_airspeed": get(env["cruise_airspeed"]),
        "bank_limit": get(env["bank_limit"]),
        "climb_rate": climb,
        "sink_rate": sink,
        "loiter_radius": get(ap.loiter_radius_param),
        "acceptance_radius": get(ap.acceptance_param),
        "values": dict(table),
    }
    if ap.path_follower == "L1":
        return EffectiveParameters(
            **common,
            l1_period=get("NAVL1_PERIOD"),
            l1_damping=get("NAVL1_DAMPING"),
            loiter_bank_limit=get("NAVL1_LIM_BANK"),
        )
    return EffectiveParameters(
        **common,
        npfg_period=get("NPFG_PERIOD"),
        npfg_damping=get("NPFG_DAMPING"),
        npfg_switch_multiplier=get("NPFG_SW_DST_MLT"),
    )
