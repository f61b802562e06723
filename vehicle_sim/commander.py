"""PX4-like commander: arming, modes, takeoff/land sequencing, auto-disarm, offboard failsafe,
return to launch, reposition, AUTO.MISSION (through :class:`MissionNavigator`) and a pilot's
sticks (:mod:`vehicle_sim.manual_control`); Orbit (MAV_CMD_DO_ORBIT, :mod:`vehicle_sim.orbit`).

RTL follows PX4's navigator ([PX4-params] RTL_RETURN_ALT): climb to RTL_RETURN_ALT above home
(or stay higher), fly to above home at MPC_XY_CRUISE, then land there. Home is where the
vehicle was armed. A reposition (MAV_CMD_DO_REPOSITION, MAVSDK's goto) flies to a point in HOLD.
HOLD entered in the air (a pilot's or a ground station's switch, a failsafe) holds where the
vehicle stops, PX4's braking distance ahead along its horizontal velocity ([PX4-braking-stop]).

Sticks (MANUAL_CONTROL, an RC or a joystick) fly POSCTL and ALTCTL as PX4's manual position /
altitude modes: velocity from the sticks, and where a stick is centred the vehicle brakes, then
holds position (POSCTL only; ALTCTL only stops), altitude and heading. Without sticks (none
received yet, or lost in a mode COM_RCL_EXCEPT exempts) they fly as with centred sticks: a
vehicle entering POSCTL at speed brakes and holds where it stopped, as PX4's does (PX4 itself
refuses both modes without manual control input, [PX4-mode-requirements]; the simulator lets
a ground station or a test switch without a joystick). Moving a stick faster than
COM_RC_STICK_OV [% of travel per s] (:class:`StickMotion`; a stick held still does not) takes a
flying vehicle out of an auto mode (COM_RC_OVERRIDE bit 0, PX4's default) or OFFBOARD (bit 1,
off by default) into POSCTL ("Pilot took over using sticks").
Sticks that stop for COM_RC_LOSS_T trigger NAV_RCL_ACT, in every mode but those PX4 exempts
(see :meth:`Commander.update`).

A pure state machine on simulated time: the simulator calls the command methods, calls
:meth:`Commander.update` after each stretch of physics, asks :meth:`Commander.next_deadline`
how far physics may run before the commander must look again, and lets
:meth:`Commander.fill_setpoint` translate the mode into the flight-control setpoint vector.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from vehicle_sim import flight_control as fc
from vehicle_sim.failsafe import FailsafeAction, FailsafeMonitor, Trigger
from vehicle_sim.manual_control import StickCommand, StickMotion, Sticks, stick_command
from vehicle_sim.mission_plan import MissionItem
from vehicle_sim.navigator import MissionNavigator
from vehicle_sim.orbit import (
    DEFAULT_VELOCITY_MPS,
    RADIUS_MIN_M,
    YAW_UNCHANGED,
    Orbit,
    OrbitSetpoint,
    limit_orbit,
    orbit_setpoint,
)
from vehicle_sim.params import Px4Params
from vehicle_sim.vehicle_types import FlightMode, LandedState

SEVERITY_CRITICAL, SEVERITY_NOTICE, SEVERITY_INFO = 2, 5, 6  # MAV_SEVERITY
TAKEOFF_ACCEPT_M = 0.1  # takeoff is complete this close to the target altitude
TAKEOFF_POLL_S = 0.02  # how often takeoff progress is checked
CLIMB_INTENT_MPS = 0.3  # on the ground, an offboard climb faster than this lifts off
LIFT_OFF_M = 0.3  # on the ground, an offboard position this far above home lifts off
MAX_TAKEOFF_ALT_M = 500.0
RTL_ACCEPT_ALT_M = 0.3  # the RTL climb is done this close to the return altitude
RTL_ACCEPT_XY_M = 0.5  # the RTL return is done this close above home (then it lands)
RTL_POLL_S = 0.05  # how often RTL progress is checked
MANUAL_POLL_S = 0.05  # how often the brake-then-hold of centred sticks is checked
ORBIT_POLL_S = 0.02  # how often the orbit's setpoint follows the vehicle round
BRAKED_XY_MPS = 0.3  # a centred horizontal stick holds position below this speed
BRAKED_Z_MPS = 0.2  # a centred throttle holds altitude below this vertical speed
BRAKING_DELAY_S = 0.6  # PX4's braking distance: accel_delay_max / jerk = 0.6 MPC_JERK_AUTO / jerk
CENTRED_COMMAND = StickCommand(0.0, 0.0, 0.0, 0.0)  # what the manual modes fly without sticks
MANUAL_MODES = frozenset({FlightMode.POSCTL, FlightMode.ALTCTL})
AUTO_MODES = frozenset(
    {FlightMode.HOLD, FlightMode.TAKEOFF, FlightMode.LAND, FlightMode.RTL, FlightMode.MISSION}
)
OVERRIDE_AUTO_BIT, OVERRIDE_OFFBOARD_BIT = 1, 2  # COM_RC_OVERRIDE
# The modes the per-step methods (update, next_deadline, fill_setpoint) compare with, as plain
# names: reading a member off its Enum class costs about 0.2 us in Python 3.11, a dozen times
# per physics stretch, and a replay runs hundreds of thousands of stretches.
_HOLD, _TAKEOFF, _LAND, _RTL = FlightMode.HOLD, FlightMode.TAKEOFF, FlightMode.LAND, FlightMode.RTL
_MISSION, _OFFBOARD, _ORBIT = FlightMode.MISSION, FlightMode.OFFBOARD, FlightMode.ORBIT
RCL_EXCEPT_MISSION_BIT, RCL_EXCEPT_HOLD_BIT, RCL_EXCEPT_OFFBOARD_BIT = 1, 2, 4  # COM_RCL_EXCEPT

# Commander.fill_setpoint writes the whole setpoint vector in this order
SETPOINT_LAYOUT = (
    (fc.SP_POS, fc.SP_VEL, fc.SP_YAW, fc.SP_YAW_RATE, fc.SP_VMAX_XY, fc.SP_VMAX_UP),
    (fc.SP_VMAX_DN, fc.SP_TILT, fc.SP_IDLE, fc.SP_ARMED, fc.SP_ACC_MAX, fc.SP_ACC_FF, fc.N_SP),
)
if SETPOINT_LAYOUT != ((0, 3, 6, 7, 8, 9), (10, 11, 12, 13, 14, 15, 18)):
    raise ImportError(f"setpoint layout {SETPOINT_LAYOUT} changed: update Commander.fill_setpoint")

RtlPhase = Literal["climb", "return"]
_VERB: dict[str, str] = {"rtl": "returning", "land": "landing", "disarm": "disarming"}


@dataclass(frozen=True)
class CommandResult:
    """Outcome of a command, as a COMMAND_ACK would carry it."""

    accepted: bool
    result: Literal["accepted", "denied", "temporarily_rejected", "failed"]
    reason: str


@dataclass(frozen=True)
class ActiveSetpoint:
    """The offboard setpoint the flight control is acting on (NED, after any delay)."""

    vel_ned_mps: tuple[float, float, float]
    yaw_rate_radps: float
    yaw_rad: float | None
    pos_ned_m: tuple[float, float, float] | None = None

    def __deepcopy__(self, memo: dict[int, object]) -> ActiveSetpoint:
        return self  # immutable: tuples of numbers


@dataclass(frozen=True)
class _StretchParams:
    """The parameters read around every stretch of physics: those the setpoint vector is built
    from (velocities [m/s], tilt [rad], acceleration [m/s^2]) and the timeouts [s] of
    :meth:`Commander.update` and :meth:`Commander.next_deadline`; read once per parameter
    version."""

    tilt_rad: float
    xy_cruise: float
    xy_vel_max: float
    z_v_auto_up: float
    z_v_auto_dn: float
    z_vel_max_up: float
    z_vel_max_dn: float
    tko_speed: float
    land_speed: float
    land_alt1: float
    land_alt2: float
    acc_hor: float
    vel_manual: float
    disarm_prflt_s: float
    disarm_land_s: float
    offboard_loss_s: float
    rc_loss_s: float

    @classmethod
    def of(cls, params: Px4Params) -> _StretchParams:
        p = params.get
        return cls(
            math.radians(p("MPC_TILTMAX_AIR")),
            p("MPC_XY_CRUISE"),
            p("MPC_XY_VEL_MAX"),
            p("MPC_Z_V_AUTO_UP"),
            p("MPC_Z_V_AUTO_DN"),
            p("MPC_Z_VEL_MAX_UP"),
            p("MPC_Z_VEL_MAX_DN"),
            p("MPC_TKO_SPEED"),
            p("MPC_LAND_SPEED"),
            p("MPC_LAND_ALT1"),
            p("MPC_LAND_ALT2"),
            p("MPC_ACC_HOR"),
            p("MPC_VEL_MANUAL"),
            p("COM_DISARM_PRFLT"),
            p("COM_DISARM_LAND"),
            p("COM_OF_LOSS_T"),
            p("COM_RC_LOSS_T"),
        )


def braking_distance_m(speed_mps: float, acc_hor_mps2: float) -> float:
    """PX4's multirotor braking distance [m] from horizontal speed ``speed_mps`` [m/s]:
    ``computeBrakingDistanceFromVelocity(v, MPC_JERK_AUTO, MPC_ACC_HOR, 0.6 MPC_JERK_AUTO)``,
    that is ``v (v / (2 MPC_ACC_HOR) + 0.6 s)`` ([PX4-braking-stop]; the jerk cancels)."""
    return speed_mps * (speed_mps / (2.0 * acc_hor_mps2) + BRAKING_DELAY_S)


def _earlier(deadline: float, candidate: float) -> float:
    """``candidate`` if it is earlier than ``deadline``, else ``deadline`` (as ``min`` over the
    deadlines in the order given)."""
    return candidate if candidate < deadline else deadline


def _land_speed_mps(p: _StretchParams, height_m: float) -> float:
    """PX4's landing descent speed [m/s] at ``height_m`` above home (FlightTaskAuto,
    math::gradual): MPC_Z_V_AUTO_DN above MPC_LAND_ALT1, MPC_LAND_SPEED below MPC_LAND_ALT2,
    linear between."""
    if height_m <= p.land_alt2:
        return p.land_speed
    if height_m >= p.land_alt1:
        return p.z_v_auto_dn
    frac = (height_m - p.land_alt2) / (p.land_alt1 - p.land_alt2)
    return p.land_speed + frac * (p.z_v_auto_dn - p.land_speed)


def manual_control_loss_ignored(mode: FlightMode, rcl_except: int) -> bool:
    """Whether PX4's failsafe ignores a manual-control loss in ``mode`` (v1.14+,
    Failsafe::checkStateAndMode): returning and landing always; MISSION with COM_RCL_EXCEPT
    bit 0, HOLD and TAKEOFF with bit 1, OFFBOARD with bit 2. Every other mode (the manual
    ones, Orbit) runs NAV_RCL_ACT."""
    return (
        mode in (FlightMode.RTL, FlightMode.LAND)
        or (mode is FlightMode.MISSION and bool(rcl_except & RCL_EXCEPT_MISSION_BIT))
        or (
            mode in (FlightMode.HOLD, FlightMode.TAKEOFF) and bool(rcl_except & RCL_EXCEPT_HOLD_BIT)
        )
        or (mode is FlightMode.OFFBOARD and bool(rcl_except & RCL_EXCEPT_OFFBOARD_BIT))
    )


def _ok(reason: str = "") -> CommandResult:
    return CommandResult(True, "accepted", reason)


class Commander:
    """Modes and arming of one simulated vehicle. Times are simulated seconds."""

    def __init__(self, params: Px4Params) -> None:
        self.params = params
        self.armed = False
        self.mode = FlightMode.HOLD
        self.events: list[tuple[int, str]] = []
        self._t_armed = 0.0
        self._took_off = False
        self._touchdown_t: float | None = None
        self._last_sp_t: float | None = None
        self._hold_pos = np.zeros(3)
        self._hold_yaw = 0.0
        self._landed = True
        self._home = np.zeros(3)
        self._height_m = 0.0  # above home, as of the last update [m]
        self._rtl_phase: RtlPhase = "climb"
        self.mission: tuple[MissionItem, ...] = ()
        self.mission_current = 0
        self.mission_reached: list[int] = []  # drained by the simulator's user
        self._navigator: MissionNavigator | None = None
        self._mission_takeoff = False
        self.failsafes = FailsafeMonitor(params)
        self._pending: tuple[FailsafeAction, float] | None = None  # action and when it runs
        self.mode_epoch = 0  # increments on every mode change (the simulator resets yaw then)
        self._sticks_t: float | None = None  # when sticks last arrived (None: never)
        self._sticks_lost = False
        self._stick_cmd: StickCommand | None = None  # None: no live sticks
        self._stick_motion = StickMotion()  # for the stick override
        self._xy_locked = self._z_locked = True  # centred sticks hold (after braking)
        self._yaw_rad = 0.0  # as of the last update [rad]
        self._vel_ne_mps = (0.0, 0.0)  # horizontal velocity as of the last update [m/s]
        self.orbit: Orbit | None = None  # the orbit flown in ORBIT (kept for a new command)
        self._orbit_sp: OrbitSetpoint | None = None

    # --- commands -------------------------------------------------------------------------
    def arm(self, t: float, pos_ned_m: np.ndarray, force: bool = False) -> CommandResult:
        if self.armed:
            return _ok("already armed")
        if not self._landed and not force:
            return self._deny("Arming denied: vehicle is not on the ground")
        if self.mode is FlightMode.OFFBOARD and not self._setpoint_fresh(t):
            return self._reject("Arming denied: no offboard setpoint stream")
        self.armed = True
        self._t_armed = t
        self._home = np.array(pos_ned_m, dtype=float)
        self._took_off = False
        self._touchdown_t = None
        self.events.append((SEVERITY_INFO, "Armed"))
        return _ok()

    def disarm(self, t: float, force: bool = False) -> CommandResult:
        if not self.armed:
            return _ok("already disarmed")
        if not self._landed and not force:
            return self._deny("Disarming denied: vehicle is in the air (use force)")
        self._disarm("Disarmed" + (" (forced)" if force else ""), SEVERITY_INFO)
        return _ok()

    def takeoff(
        self, t: float, pos_ned_m: np.ndarray, yaw_rad: float, alt_m: float | None
    ) -> CommandResult:
        if alt_m is None or math.isnan(alt_m):
            alt_m = self.params.get("MIS_TAKEOFF_ALT")
        if not (math.isfinite(alt_m) and 0.0 < alt_m <= MAX_TAKEOFF_ALT_M):
            return self._deny(f"Takeoff denied: altitude {alt_m} m not in (0, {MAX_TAKEOFF_ALT_M}]")
        if not self.armed:
            return self._deny("Takeoff denied: arm first")
        self._hold_pos = np.array([pos_ned_m[0], pos_ned_m[1], -alt_m])
        self._hold_yaw = yaw_rad
        self._set_mode(FlightMode.TAKEOFF)
        return _ok()

    def land(self, t: float, pos_ned_m: np.ndarray, yaw_rad: float) -> CommandResult:
        if not self.armed:
            return self._deny("Land denied: not armed")
        self._hold_pos = np.array([pos_ned_m[0], pos_ned_m[1], math.nan])
        self._hold_yaw = yaw_rad
        self._set_mode(FlightMode.LAND)
        return _ok()

    def set_mode(
        self, mode: FlightMode, t: float, pos_ned_m: np.ndarray, yaw_rad: float
    ) -> CommandResult:
        self._pending = None  # a pilot's mode change takes over from a pending failsafe
        if mode is FlightMode.TAKEOFF:
            return self.takeoff(t, pos_ned_m, yaw_rad, None)
        if mode is FlightMode.LAND:
            return self.land(t, pos_ned_m, yaw_rad)
        if mode is FlightMode.MISSION:
            return self._start_mission(pos_ned_m, yaw_rad)
        if mode is FlightMode.RTL:
            return self._start_rtl(pos_ned_m, yaw_rad)
        if mode is FlightMode.ORBIT and mode is not self.mode:
            return self.start_orbit(pos_ned_m, yaw_rad, math.nan, math.nan, math.nan, None, None)
        if mode is FlightMode.OFFBOARD and not self._setpoint_fresh(t):
            return self._reject("Offboard denied: no setpoint stream")
        if mode is not self.mode:
            self._hold(self._stop_ahead(pos_ned_m) if mode is _HOLD else pos_ned_m, yaw_rad)
            self._set_mode(mode)
        return _ok()

    def reposition(self, pos_ned_m: np.ndarray, target_ned_m: np.ndarray) -> CommandResult:
        """Fly to ``target_ned_m`` (NaN components: keep the current one) and hold there."""
        if not self.armed or self._landed:
            return self._deny("Reposition denied: not flying")
        target = np.where(np.isfinite(target_ned_m), target_ned_m, pos_ned_m)
        self._hold_pos = np.array(target, dtype=float)
        self._set_mode(FlightMode.HOLD)
        return _ok()

    def start_orbit(
        self,
        pos_ned_m: np.ndarray,
        yaw_rad: float,
        radius_m: float,
        velocity_mps: float,
        yaw_behaviour: float,
        centre_ne_m: tuple[float, float] | None,
        down_m: float | None,
    ) -> CommandResult:
        """Orbit (MAV_CMD_DO_ORBIT as PX4's FlightTaskOrbit takes it): NaN radius, velocity or
        yaw behaviour (or ORBIT_YAW_BEHAVIOUR_UNCHANGED, 5) keep those of the orbit flown now
        (else 1 m, 1 m/s, MC_ORBIT_YAW_MOD); a negative radius orbits counter-clockwise, a
        negative velocity reverses; None centre keeps the current orbit's, else the vehicle's
        position (the MAVLink definition and FlightTaskOrbit::activate's; PX4 releases before
        the position smoothing put it 1 m south, the vehicle on the circle); None altitude:
        the current orbit's, else here."""
        if not self.armed or self._landed:
            return self._deny("Orbit denied: not flying")
        if yaw_behaviour == YAW_UNCHANGED:
            yaw_behaviour = math.nan
        if not (math.isnan(yaw_behaviour) or yaw_behaviour in (0, 1, 2, 3, 4)):
            return self._deny(
                f"Orbit denied: yaw behaviour {yaw_behaviour:g} is not 0-4, 5 (unchanged) or NaN"
            )
        now = self.orbit if self.mode is FlightMode.ORBIT else None
        clockwise = now is None or now.velocity_mps >= 0.0
        radius = RADIUS_MIN_M if now is None else now.radius_m
        if not math.isnan(radius_m):
            clockwise, radius = radius_m > 0.0, abs(radius_m)
        speed = DEFAULT_VELOCITY_MPS if now is None else abs(now.velocity_mps)
        if not math.isnan(velocity_mps):
            speed = velocity_mps
        radius, velocity, note = limit_orbit(radius, speed if clockwise else -speed, self.params)
        if math.isnan(yaw_behaviour):
            yaw_behaviour = (
                self.params.get("MC_ORBIT_YAW_MOD") if now is None else now.yaw_behaviour
            )
        if centre_ne_m is None:
            centre_ne_m = (pos_ned_m[0], pos_ned_m[1]) if now is None else now.centre_ne_m
        if down_m is None:
            down_m = pos_ned_m[2] if now is None else now.down_m
        self.orbit = Orbit(
            (float(centre_ne_m[0]), float(centre_ne_m[1])),
            float(down_m),
            radius,
            velocity,
            int(yaw_behaviour),
            float(yaw_rad),
        )
        self._orbit_sp = orbit_setpoint(self.orbit, (pos_ned_m[0], pos_ned_m[1]), self.params)
        self._hold(pos_ned_m, yaw_rad)
        self._set_mode(FlightMode.ORBIT)
        if note:
            self.events.append((SEVERITY_NOTICE, note))
        return _ok(note)

    def set_mission(self, items: tuple[MissionItem, ...]) -> None:
        """Replace the mission (an empty one clears it); it starts from its first item."""
        self.mission = tuple(items)
        self.mission_current = 0
        self._navigator = None
        if self.mode is FlightMode.MISSION:
            self._set_mode(FlightMode.HOLD)

    def set_mission_current(self, seq: int) -> CommandResult:
        if not 0 <= seq < len(self.mission):
            return self._deny(
                f"Mission item {seq} does not exist (mission has {len(self.mission)})"
            )
        self.mission_current = seq
        if self._navigator is not None:
            self._navigator = MissionNavigator(self.mission, seq)
        return _ok()

    def _start_mission(self, pos_ned_m: np.ndarray, yaw_rad: float) -> CommandResult:
        if not self.mission:
            return self._deny("Mission denied: no mission uploaded")
        if not self.armed:
            return self._deny("Mission denied: arm first")
        start = 0 if self.mission_current >= len(self.mission) else self.mission_current
        self._navigator = MissionNavigator(self.mission, start)
        self._hold(pos_ned_m, yaw_rad)
        self._mission_takeoff = self._landed  # on the ground: take off first, as PX4 does
        if self._mission_takeoff:
            floor_down_m = self._home[2] - self.params.get("MIS_TAKEOFF_ALT")
            self._hold_pos[2] = self._navigator.takeoff_down_m(floor_down_m)
        self._set_mode(FlightMode.MISSION)
        self.events.append((SEVERITY_INFO, "Mission started"))
        return _ok()

    def _update_mission(self, t: float, pos_ned_m: np.ndarray, yaw_rad: float) -> None:
        nav = self._navigator
        if nav is None:
            return
        if self._mission_takeoff:
            if pos_ned_m[2] > self._hold_pos[2] + RTL_ACCEPT_ALT_M:
                return
            self._mission_takeoff = False
        out = nav.step(t, pos_ned_m)
        self.mission_reached += nav.reached
        nav.reached.clear()
        self.mission_current = nav.current
        if out.action == "fly":
            self._hold_pos = out.target_ned_m
        elif out.action == "land":
            self._hold_pos = np.array([out.target_ned_m[0], out.target_ned_m[1], math.nan])
            self._set_mode(FlightMode.LAND)
        elif out.action == "rtl":
            self._start_rtl(pos_ned_m, yaw_rad)
        elif self._navigator is not None:  # done: hold where the mission ended
            self._hold(pos_ned_m, yaw_rad)
            self._navigator = None
            self.events.append((SEVERITY_INFO, "Mission finished, holding"))

    def _failsafe_checks(
        self, t: float, pos_ned_m: np.ndarray, yaw_rad: float, battery_remaining: float
    ) -> None:
        warnings, trigger = self.failsafes.check(
            t, self.armed and not self._landed, battery_remaining
        )
        if warnings:
            self.events += [(SEVERITY_CRITICAL, text) for text in warnings]
        if trigger is not None:
            self._trigger(trigger, t, pos_ned_m, yaw_rad)
        if self._pending is not None and t >= self._pending[1] - 1e-9:
            action, _ = self._pending
            self._pending = None
            self._execute(action, pos_ned_m, yaw_rad)

    def _trigger(self, trigger: Trigger, t: float, pos_ned_m: np.ndarray, yaw_rad: float) -> None:
        """Hold now; run the action after COM_FAIL_ACT_T (at once when that is 0)."""
        self._hold(self._stop_ahead(pos_ned_m), yaw_rad)
        self._set_mode(FlightMode.HOLD)
        delay_s = self.params.get("COM_FAIL_ACT_T")
        if trigger.action == "hold":
            text = f"Failsafe: {trigger.reason}, holding position"
        elif delay_s <= 0.0:
            text = f"Failsafe: {trigger.reason}, {_VERB[trigger.action]}"
            self._execute(trigger.action, pos_ned_m, yaw_rad)
        else:
            text = f"Failsafe: {trigger.reason}, holding; {_VERB[trigger.action]} in {delay_s:g} s"
            self._pending = (trigger.action, t + delay_s)
        self.events.append((SEVERITY_CRITICAL, text))

    def _execute(self, action: FailsafeAction, pos_ned_m: np.ndarray, yaw_rad: float) -> None:
        if action == "rtl":
            self._start_rtl(pos_ned_m, yaw_rad)
        elif action == "land":
            self._hold_pos = np.array([pos_ned_m[0], pos_ned_m[1], math.nan])
            self._hold_yaw = yaw_rad
            self._set_mode(FlightMode.LAND)
        elif action == "disarm":
            self._disarm("Failsafe: disarmed (motors off)", SEVERITY_CRITICAL)

    def _start_rtl(self, pos_ned_m: np.ndarray, yaw_rad: float) -> CommandResult:
        if not self.armed or self._landed:
            return self._deny("RTL denied: not flying")
        return_alt_m = max(-pos_ned_m[2], -self._home[2] + self.params.get("RTL_RETURN_ALT"))
        self._hold_pos = np.array([pos_ned_m[0], pos_ned_m[1], -return_alt_m])
        self._hold_yaw = yaw_rad
        self._rtl_phase = "climb"
        self._set_mode(FlightMode.RTL)
        self.events.append((SEVERITY_INFO, "RTL: climbing to return altitude"))
        return _ok()

    def _update_rtl(self, pos_ned_m: np.ndarray) -> None:
        if self._rtl_phase == "climb" and abs(pos_ned_m[2] - self._hold_pos[2]) < RTL_ACCEPT_ALT_M:
            self._rtl_phase = "return"
            self._hold_pos = np.array([self._home[0], self._home[1], self._hold_pos[2]])
            self.events.append((SEVERITY_INFO, "RTL: returning to home"))
        elif self._rtl_phase == "return" and (
            np.hypot(*(pos_ned_m[:2] - self._home[:2])) < RTL_ACCEPT_XY_M
        ):
            self._hold_pos = np.array([self._home[0], self._home[1], math.nan])
            self._set_mode(FlightMode.LAND)
            self.events.append((SEVERITY_INFO, "RTL: landing at home"))

    @property
    def home_ned_m(self) -> np.ndarray:
        """(3,) home in local NED [m]: where the vehicle last armed."""
        return self._home.copy()

    def on_setpoint(self, t: float) -> None:
        """A setpoint arrived (proof of life for offboard)."""
        self._last_sp_t = t

    def on_sticks(self, t: float, sticks: Sticks, pos_ned_m: np.ndarray, yaw_rad: float) -> None:
        """Sticks arrived (validated by the caller): they fly POSCTL/ALTCTL from now on, and a
        stick moving faster than COM_RC_STICK_OV [% of travel per s] takes a flying vehicle out
        of an auto mode or OFFBOARD as COM_RC_OVERRIDE allows (PX4's commander, "Pilot took
        over using sticks"); a stick held still, however far out, does not."""
        if self._sticks_lost:
            self.events.append((SEVERITY_INFO, "Manual control regained"))
        fresh = self._sticks_t is None or self._sticks_lost
        if fresh:
            self._stick_motion.reset()
        dt_s = 0.0 if fresh else max(t - self._sticks_t, 0.0)
        speed = self._stick_motion.update(sticks, dt_s)
        self._sticks_t, self._sticks_lost = t, False
        self._stick_cmd = stick_command(sticks, self.params)
        bits = int(self.params.get("COM_RC_OVERRIDE"))
        overridable = (self.mode in AUTO_MODES and bits & OVERRIDE_AUTO_BIT) or (
            self.mode is FlightMode.OFFBOARD and bits & OVERRIDE_OFFBOARD_BIT
        )
        moved = speed > 0.01 * self.params.get("COM_RC_STICK_OV")
        if overridable and moved and self.armed and not self._landed:
            self._pending = None  # the pilot takes over from a pending failsafe too
            self._hold(pos_ned_m, yaw_rad)
            self._set_mode(FlightMode.POSCTL)
            self.events.append((SEVERITY_INFO, "Pilot took over using sticks"))

    # --- time -------------------------------------------------------------------------------
    def update(
        self,
        t: float,
        pos_ned_m: np.ndarray,
        yaw_rad: float,
        contact: bool,
        battery_remaining: float = 1.0,
        vel_ned_mps: np.ndarray | None = None,
    ) -> None:
        """Advance the state machine to time ``t`` given the vehicle's state (battery charge
        remaining as a fraction, velocity NED [m/s] (3,) for the brake-then-hold of centred
        sticks; None counts as at rest).

        Manual-control loss: once sticks have been received, COM_RC_LOSS_T without them
        triggers NAV_RCL_ACT through the failsafe framework ("Failsafe: manual control lost,
        ...") in a flying vehicle's every mode but those PX4's failsafe exempts
        (:func:`manual_control_loss_ignored`): RTL and LAND always, MISSION, HOLD and TAKEOFF,
        OFFBOARD as COM_RCL_EXCEPT's bits say (PX4's default 0: none of them; a companion that
        wants its OFFBOARD flight to survive a joystick going away sets bit 2). There a loss is
        only noted. Never before the first sticks: PX4 without any RC or joystick does not fail
        over for it either (it has none to lose; it only refuses the manual modes, which the
        simulator lets a ground station enter, flown as centred sticks)."""
        self._landed = contact
        self._height_m = float(self._home[2]) - float(pos_ned_m[2])  # (NumPy scalars: slower)
        if vel_ned_mps is not None:
            self._vel_ne_mps = (float(vel_ned_mps[0]), float(vel_ned_mps[1]))
        self._yaw_rad = float(yaw_rad)
        self._check_sticks_lost(t, pos_ned_m, yaw_rad)
        if not self.armed:
            return
        if not contact:
            self._took_off = True
            self._touchdown_t = None
        elif self._took_off and self._touchdown_t is None:
            self._touchdown_t = t
            self.events.append((SEVERITY_INFO, "Landing detected"))
        eps = 1e-9
        p = self._params_now()
        prflt = p.disarm_prflt_s
        if not self._took_off and prflt > 0 and t - self._t_armed >= prflt - eps:
            self._disarm(f"Disarmed: no takeoff within {prflt:g} s of arming", SEVERITY_NOTICE)
            return
        land_t = p.disarm_land_s
        if self._touchdown_t is not None and land_t > 0 and t - self._touchdown_t >= land_t - eps:
            self._disarm("Disarmed after landing", SEVERITY_INFO)
            return
        if self.mode is _RTL:
            self._update_rtl(pos_ned_m)
        if self.mode is _MISSION:
            self._update_mission(t, pos_ned_m, yaw_rad)
        if self.mode is _TAKEOFF and self._climbed(pos_ned_m, contact):
            self._set_mode(_HOLD)
            self.events.append((SEVERITY_INFO, "Takeoff complete, holding"))
        if self.mode is _OFFBOARD and not self._setpoint_fresh(t):
            self._trigger(self.failsafes.offboard_lost(), t, pos_ned_m, yaw_rad)
        if self.mode in MANUAL_MODES:
            self._lock_centred_sticks(pos_ned_m, vel_ned_mps)
        if self.mode is _ORBIT and self.orbit is not None:
            self._orbit_sp = orbit_setpoint(self.orbit, (pos_ned_m[0], pos_ned_m[1]), self.params)
        self._failsafe_checks(t, pos_ned_m, yaw_rad, battery_remaining)

    def _check_sticks_lost(self, t: float, pos_ned_m: np.ndarray, yaw_rad: float) -> None:
        """Sticks older than COM_RC_LOSS_T are lost: no longer flown, and in a manual mode of
        a flying vehicle NAV_RCL_ACT runs (see :meth:`update`)."""
        if self._sticks_t is None or self._sticks_lost:
            return
        if t - self._sticks_t < self._params_now().rc_loss_s - 1e-9:
            return
        self._sticks_lost = True
        self._stick_cmd = None
        exempt = manual_control_loss_ignored(self.mode, int(self.params.get("COM_RCL_EXCEPT")))
        if self.armed and not self._landed and not exempt:
            self._trigger(self.failsafes.manual_control_lost(), t, pos_ned_m, yaw_rad)
        else:
            self.events.append((SEVERITY_NOTICE, "Manual control lost"))

    def _lock_centred_sticks(self, pos_ned_m: np.ndarray, vel_ned_mps: np.ndarray | None) -> None:
        """A centred stick lets the vehicle brake, then holds where it stopped (PX4's manual
        position/altitude tasks lock the position once slow)."""
        cmd = self._manual_command()
        vel = np.zeros(3) if vel_ned_mps is None else vel_ned_mps
        if cmd.horizontal or self.mode is FlightMode.ALTCTL:
            self._xy_locked = False
        elif not self._xy_locked and math.hypot(vel[0], vel[1]) < BRAKED_XY_MPS:
            self._hold_pos[:2] = pos_ned_m[:2]
            self._xy_locked = True
        if cmd.down_mps != 0.0:
            self._z_locked = False
        elif not self._z_locked and abs(vel[2]) < BRAKED_Z_MPS:
            self._hold_pos[2] = pos_ned_m[2]
            self._z_locked = True

    def _manual_command(self) -> StickCommand:
        """What the sticks command now; centred without sticks (see the module docstring)."""
        return CENTRED_COMMAND if self._stick_cmd is None else self._stick_cmd

    def next_deadline(self, t: float) -> float:
        """Latest simulated time to which physics may run before :meth:`update` is due."""
        if not self.armed:
            return math.inf
        deadline = math.inf
        p = self._params_now()
        prflt = p.disarm_prflt_s
        if not self._took_off and prflt > 0:
            deadline = _earlier(deadline, self._t_armed + prflt)
        land_t = p.disarm_land_s
        if self._touchdown_t is not None and land_t > 0:
            deadline = _earlier(deadline, self._touchdown_t + land_t)
        mode = self.mode
        if mode is _TAKEOFF:
            deadline = _earlier(deadline, t + TAKEOFF_POLL_S)
        if mode is _RTL or mode is _MISSION:
            deadline = _earlier(deadline, t + RTL_POLL_S)
        if mode is _ORBIT:
            deadline = _earlier(deadline, t + ORBIT_POLL_S)
        if mode is _LAND and self._height_m > p.land_alt2:
            deadline = _earlier(deadline, t + RTL_POLL_S)  # the descent slows with height
        if self._pending is not None:
            deadline = _earlier(deadline, self._pending[1])
        link_lost_s = self.failsafes.next_check_s(t)
        if link_lost_s is not None:
            deadline = _earlier(deadline, link_lost_s + 1e-3)
        if mode is _OFFBOARD and self._last_sp_t is not None:
            deadline = _earlier(deadline, self._last_sp_t + p.offboard_loss_s)
        if self._sticks_t is not None and not self._sticks_lost:
            deadline = _earlier(deadline, self._sticks_t + p.rc_loss_s)
        if mode in MANUAL_MODES and (
            self._stick_cmd is not None or not (self._xy_locked and self._z_locked)
        ):
            deadline = _earlier(deadline, t + MANUAL_POLL_S)
        return deadline

    def idle_in_offboard(self, t: float) -> bool:
        """Whether, from time ``t`` on, :meth:`update` only records the vehicle's height and
        yaw and :meth:`fill_setpoint` depends only on the setpoint in force, as long as the
        vehicle stays in the air, its setpoints stay younger than :meth:`offboard_loss_s` and
        its battery level does not change: an OFFBOARD flight with no pilot, no ground station
        being watched and no failsafe pending (then no deadline but the setpoints' falls)."""
        return (
            self.armed
            and self.mode is _OFFBOARD
            and self._took_off
            and self._touchdown_t is None
            and self._pending is None
            and self._sticks_t is None
            and self._last_sp_t is not None
            and self.failsafes.next_check_s(t) is None
        )

    def offboard_loss_s(self) -> float:
        """COM_OF_LOSS_T [s]: a setpoint this old ends OFFBOARD."""
        return self._params_now().offboard_loss_s

    @property
    def last_setpoint_s(self) -> float | None:
        """When the last setpoint arrived [s] (None: none yet)."""
        return self._last_sp_t

    def landed_state(self, contact: bool) -> LandedState:
        """As PX4 reports it ([PX4-extended-sys-state]): ON_GROUND while the vehicle touches the
        ground (``contact``), else TAKEOFF for the whole of an automatic take-off (TAKEOFF; a
        mission's climb from the ground, to :meth:`MissionNavigator.takeoff_down_m`), LANDING while
        it lands (LAND, RTL's last phase), IN_AIR otherwise: also while a NAV_TAKEOFF item that
        became current in the air climbs, which PX4 flies as a position setpoint
        ([PX4-mission-takeoff])."""
        if contact:
            return LandedState.ON_GROUND
        if self.armed and (
            self.mode is FlightMode.TAKEOFF
            or (self.mode is FlightMode.MISSION and self._mission_takeoff)
        ):
            return LandedState.TAKEOFF
        if self.armed and self.mode is FlightMode.LAND:
            return LandedState.LANDING
        return LandedState.IN_AIR

    def fill_setpoint(self, sp: np.ndarray, contact: bool, active: ActiveSetpoint | None) -> None:
        """Write the flight-control setpoint vector for the current mode into ``sp`` (all of its
        N_SP entries in one assignment; called before every stretch of physics)."""
        p = self._params_now()
        pos = self._hold_pos
        pos_n, pos_e, pos_d = pos[0], pos[1], pos[2]
        vel_n = vel_e = vel_d = math.nan
        acc_n = acc_e = 0.0
        yaw, yaw_rate = self._hold_yaw, 0.0
        vmax_xy, vmax_up, vmax_dn, acc_max = p.xy_cruise, p.z_v_auto_up, p.z_v_auto_dn, p.acc_hor
        idle = contact
        mode = self.mode
        if mode is _TAKEOFF or (mode is _MISSION and self._mission_takeoff):
            vmax_up = p.tko_speed
            idle = False
        elif mode is _MISSION and self._navigator is not None:
            speed = self._navigator.speed_mps
            if speed is not None:
                vmax_xy = min(speed, p.xy_vel_max)
        elif mode is _LAND:
            vel_d = vmax_dn = _land_speed_mps(p, self._height_m)
        elif mode is _OFFBOARD and active is not None:
            if active.pos_ned_m is None:
                pos_n = pos_e = pos_d = math.nan
            else:
                pos_n, pos_e, pos_d = active.pos_ned_m
            vel_n, vel_e, vel_d = active.vel_ned_mps
            yaw = math.nan if active.yaw_rad is None else active.yaw_rad
            yaw_rate = 0.0 if active.yaw_rad is not None else active.yaw_rate_radps
            vmax_xy, vmax_up, vmax_dn = p.xy_vel_max, p.z_vel_max_up, p.z_vel_max_dn
            acc_max = 0.0
            wants_climb = -active.vel_ned_mps[2] >= CLIMB_INTENT_MPS or (
                active.pos_ned_m is not None and active.pos_ned_m[2] < self._home[2] - LIFT_OFF_M
            )
            idle = contact and not wants_climb
        elif mode is _ORBIT and self._orbit_sp is not None:
            pos_n = pos_e = math.nan
            pos_d = self.orbit.down_m
            vel_n, vel_e = self._orbit_sp.vel_ne_mps
            acc_n, acc_e = self._orbit_sp.acc_ne_mps2
            yaw = self._orbit_sp.yaw_rad
            if math.isnan(yaw):  # uncontrolled or on the yaw stick
                stick = self._stick_cmd
                yaw_rate = 0.0 if stick is None else stick.yaw_rate_radps
            vmax_xy, acc_max = p.xy_vel_max, 0.0
        elif mode in MANUAL_MODES:
            cmd = self._manual_command()
            c, s = math.cos(self._yaw_rad), math.sin(self._yaw_rad)
            if not self._xy_locked:
                pos_n = pos_e = math.nan
                vel_n = c * cmd.forward_mps - s * cmd.right_mps
                vel_e = s * cmd.forward_mps + c * cmd.right_mps
            if not self._z_locked:
                pos_d, vel_d = math.nan, cmd.down_mps
            yaw, yaw_rate = math.nan, cmd.yaw_rate_radps
            vmax_xy = min(p.vel_manual, p.xy_vel_max)
            vmax_up, vmax_dn = p.z_vel_max_up, p.z_vel_max_dn
            idle = contact and not -cmd.down_mps >= CLIMB_INTENT_MPS
        sp[:] = (
            pos_n, pos_e, pos_d, vel_n, vel_e, vel_d, yaw, yaw_rate,
            vmax_xy, vmax_up, vmax_dn, p.tilt_rad,
            1.0 if idle else 0.0, 1.0 if self.armed else 0.0, acc_max, acc_n, acc_e, 0.0,
        )  # fmt: skip

    def offboard_rows(
        self,
        vel_ned_mps: np.ndarray,
        yaw_rate_radps: np.ndarray,
        yaw_rad: np.ndarray,
        pos_ned_m: np.ndarray,
    ) -> np.ndarray:
        """(m, N_SP) the vectors :meth:`fill_setpoint` writes for m OFFBOARD setpoints in the
        air (while :meth:`idle_in_offboard`), all at once: velocity NED (m, 3) [m/s], yaw rate
        (m,) [rad/s], yaw (m,) [rad] and position NED (m, 3) [m], NaN where a setpoint gives
        none; the yaw rate counts only without a yaw, as there."""
        yaw_rad = np.asarray(yaw_rad, dtype=float).reshape(-1)
        shared = np.empty(fc.N_SP)
        self.fill_setpoint(shared, False, ActiveSetpoint((0.0, 0.0, 0.0), 0.0, None))
        rows = np.repeat(shared[None, :], len(yaw_rad), axis=0)
        if len(yaw_rad):
            rows[:, fc.SP_POS : fc.SP_POS + 3] = pos_ned_m
            rows[:, fc.SP_VEL : fc.SP_VEL + 3] = vel_ned_mps
            rows[:, fc.SP_YAW] = yaw_rad
            rows[:, fc.SP_YAW_RATE] = np.where(np.isnan(yaw_rad), yaw_rate_radps, 0.0)
        return rows

    def _params_now(self) -> _StretchParams:
        """The parameters read at every stretch, read again only after a parameter set."""
        return self.params.derived(_StretchParams.of)

    # --- helpers ------------------------------------------------------------------------------
    def _climbed(self, pos_ned_m: np.ndarray, contact: bool) -> bool:
        """Whether a takeoff has reached its target altitude (within TAKEOFF_ACCEPT_M)."""
        target_alt_m = -self._hold_pos[2]
        accept_m = min(TAKEOFF_ACCEPT_M, 0.5 * target_alt_m)
        return not contact and -pos_ned_m[2] >= target_alt_m - accept_m

    def _setpoint_fresh(self, t: float) -> bool:
        return (
            self._last_sp_t is not None and t - self._last_sp_t < self._params_now().offboard_loss_s
        )

    def _stop_ahead(self, pos_ned_m: np.ndarray) -> np.ndarray:
        """Where a flying vehicle entering HOLD stops: ``pos_ned_m`` moved along the horizontal
        velocity by PX4's braking distance (:func:`braking_distance_m`), as PX4's Loiter sets
        a multirotor's hold point ([PX4-braking-stop]: else it overshoots and flies back)."""
        if self._landed:
            return pos_ned_m
        vn, ve = self._vel_ne_mps
        speed = math.hypot(vn, ve)
        if speed == 0.0:
            return pos_ned_m
        ahead = braking_distance_m(speed, self._params_now().acc_hor) / speed
        return np.array([pos_ned_m[0] + ahead * vn, pos_ned_m[1] + ahead * ve, pos_ned_m[2]])

    def _hold(self, pos_ned_m: np.ndarray, yaw_rad: float) -> None:
        self._hold_pos = np.array(pos_ned_m, dtype=float)
        self._hold_yaw = yaw_rad

    def _set_mode(self, mode: FlightMode) -> None:
        if mode is not self.mode:
            self.mode = mode
            self.mode_epoch += 1
            self._xy_locked = self._z_locked = mode not in MANUAL_MODES  # brake, then hold

    def _disarm(self, text: str, severity: int) -> None:
        self.armed = False
        self._touchdown_t = None
        if self.mode in (FlightMode.TAKEOFF, FlightMode.LAND):
            self._set_mode(FlightMode.HOLD)
        self.events.append((severity, text))

    def _deny(self, text: str) -> CommandResult:
        self.events.append((SEVERITY_CRITICAL, text))
        return CommandResult(False, "denied", text)

    def _reject(self, text: str) -> CommandResult:
        self.events.append((SEVERITY_CRITICAL, text))
        return CommandResult(False, "temporarily_rejected", text)
