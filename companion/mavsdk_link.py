"""A Link over MAVSDK 4.x (the native binding: ``Mavsdk``, ``first_autopilot``, plugins).

Uses MAVSDK's synchronous API; its own threads receive telemetry and, once a setpoint is set,
re-send it at 20 Hz, so the loop's clock is the plain wall clock. Telemetry is read with the
plugins' polling getters (newest values), commands block until the autopilot answers.

MAVSDK's NED velocity setpoint carries an absolute yaw, not a yaw rate, so the commanded yaw
rate is integrated here into a yaw target (starting from the vehicle's heading when streaming
starts); with zero yaw rate the vehicle keeps its heading. The target stays within
``YAW_LEAD_S`` of the commanded rate (at most ``MAX_YAW_LEAD_RAD``) ahead of the vehicle's
heading on the side it is to turn to, and ``YAW_HOLD_RAD`` on either side: a vehicle turning
slower than commanded (a rover at its turn-rate limit) would otherwise see the target run
away from it, past half a turn, and turn the short way round to it, the other way, or go on
turning long after the command turned the other way. A rover (MAVSDK's vehicle type) is sent
the body velocity with the yaw rate itself instead (VelocityBodyYawspeed: forward speed and
turn rate, as PX4's rover offboard takes them): through the yaw target's heading loop the
Husky repeated a path to 0.16-0.20 m, against 0.04 m so and over pymavlink.
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from typing import TypeVar

import numpy as np
from mavsdk import (
    ComponentType,
    Configuration,
    ConnectionResult,
    LogLevel,
    Mavsdk,
    MavsdkError,
    System,
    Vehicle,
    log_subscribe,
)
from mavsdk.plugins.action import Action, ActionError
from mavsdk.plugins.offboard import (
    Offboard,
    OffboardError,
    VelocityBodyYawspeed,
    VelocityNedYaw,
)
from mavsdk.plugins.param import Param
from mavsdk.plugins.telemetry import Telemetry, TelemetryError

from companion.clocks import WallClock
from companion.link import (
    FLIGHT_MODE_NAMES,
    STATUS_TEXTS_KEPT,
    CommandOutcome,
    LandedPhase,
    LinkError,
    LinkState,
    StatusText,
    VehicleKind,
    VelocityCommand,
)

_MODE_ALIASES = {"RETURN_TO_LAUNCH": "RTL"}
# MAVSDK's reading of the HEARTBEAT's MAV_TYPE; its FIXED_WING may be a VTOL, and GENERIC or
# UNKNOWN say nothing, so those are left unknown (None) as a link that says nothing is.
_KINDS_OF_VEHICLE: dict[Vehicle, VehicleKind] = {
    Vehicle.MULTICOPTER: "multirotor",
    Vehicle.ROVER: "rover",
}
YAW_LEAD_S = 1.0  # [s]: a heading loop of P gain >= 1/s turns at the commanded rate
YAW_HOLD_RAD = 0.2  # [rad]: a heading pushed off by up to this is turned back
MAX_YAW_LEAD_RAD = 1.0  # [rad]: well short of half a turn, so the short way is the commanded way
_Plugin = TypeVar("_Plugin")


def next_yaw_target_rad(
    target_rad: float, yaw_rad: float, yaw_rate_radps: float, dt_s: float
) -> float:
    """The yaw target [rad] ``dt_s`` [s] on at ``yaw_rate_radps`` [rad/s], kept within
    ``YAW_LEAD_S`` of that rate (at most ``MAX_YAW_LEAD_RAD``) ahead of the vehicle's
    ``yaw_rad`` on the side it is to turn to, and ``YAW_HOLD_RAD`` on either side. A target
    that is not finite (made of a non-finite attitude earlier) starts again at ``yaw_rad``."""
    if not math.isfinite(target_rad):
        return yaw_rad
    lead_rad = math.remainder(target_rad + yaw_rate_radps * dt_s - yaw_rad, 2.0 * math.pi)
    reach_rad = yaw_rate_radps * YAW_LEAD_S
    lo_rad = max(min(0.0, reach_rad) - YAW_HOLD_RAD, -MAX_YAW_LEAD_RAD)
    hi_rad = min(max(0.0, reach_rad) + YAW_HOLD_RAD, MAX_YAW_LEAD_RAD)
    return yaw_rad + min(max(lead_rad, lo_rad), hi_rad)


def body_velocity(vn_mps: float, ve_mps: float, yaw_rad: float) -> tuple[float, float]:
    """The horizontal NED velocity (north, east) [m/s] as (forward, right) [m/s] of a vehicle
    heading ``yaw_rad`` [rad]; a zero velocity is zero whatever the heading, so a stop is sent
    as a stop also when the attitude is not finite (0 * NaN would make it NaN)."""
    if vn_mps == 0.0 and ve_mps == 0.0:
        return 0.0, 0.0
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return vn_mps * c + ve_mps * s, -vn_mps * s + ve_mps * c


class MavsdkLink:
    """A Link to a PX4-like autopilot through MAVSDK.

    Args:
        url: MAVSDK connection URL; ``udpin://127.0.0.1:14540`` listens where PX4 SITL sends.
        telemetry_rate_hz: rate requested for position/velocity and attitude [Hz].
        verbose: let MAVSDK's own log lines through to stderr (they are dropped by default;
            the setting is process-wide, as MAVSDK's logging is).
    """

    def __init__(self, url: str, *, telemetry_rate_hz: float = 50.0, verbose: bool = False) -> None:
        self._url = url
        self._verbose = verbose
        self._telemetry_rate_hz = telemetry_rate_hz
        self._clock = WallClock()
        self._mavsdk: Mavsdk | None = None
        self._action: Action | None = None
        self._telemetry: Telemetry | None = None
        self._offboard: Offboard | None = None
        self._param: Param | None = None
        self._system: System | None = None
        self._yaw_target_rad: float | None = None
        self._yaw_updated_s = 0.0
        self._status_texts: deque[StatusText] = deque(maxlen=STATUS_TEXTS_KEPT)
        self._status_texts_lock = threading.Lock()  # MAVSDK's callback thread appends

    @property
    def name(self) -> str:
        return "mavsdk"

    @property
    def clock(self) -> WallClock:
        return self._clock

    def connect(self, timeout_s: float) -> None:
        deadline_s = self._clock.now_s() + timeout_s
        if not self._verbose:
            log_subscribe(_quiet)
        self._mavsdk = Mavsdk(
            Configuration.create_with_component_type(ComponentType.GROUND_STATION)
        )
        result = self._mavsdk.add_any_connection(self._url)
        if result != ConnectionResult.SUCCESS:
            raise LinkError(f"MAVSDK cannot open {self._url}: {result.name}")
        system = self._mavsdk.first_autopilot(max(0.1, deadline_s - self._clock.now_s()))
        if system is None:
            raise LinkError(f"no autopilot on {self._url} within {timeout_s:g} s")
        self._system = system
        self._action = Action(system)
        self._telemetry = Telemetry(system)
        self._offboard = Offboard(system)
        self._param = Param(system)
        self._telemetry.subscribe_status_text(self._on_status_text)
        for set_rate in (
            self._telemetry.set_rate_position_velocity_ned,
            self._telemetry.set_rate_attitude_quaternion,
        ):
            with contextlib.suppress(TelemetryError):  # else the default rate stays: fine
                set_rate(self._telemetry_rate_hz)
        while not (self._telemetry.health_all_ok() and self.read_state().is_finite()):
            if self._clock.now_s() >= deadline_s:
                raise LinkError(
                    f"vehicle on {self._url} not healthy or without position within {timeout_s:g} s"
                )
            time.sleep(0.05)

    def read_state(self) -> LinkState:
        telemetry = self._require(self._telemetry)
        if not self._require(self._system).is_connected():
            raise LinkError(f"link lost: MAVSDK reports the vehicle on {self._url} disconnected")
        pv = telemetry.position_velocity_ned()
        q = telemetry.attitude_quaternion()
        rates = telemetry.attitude_angular_velocity_body()
        battery_v = float(telemetry.battery().voltage_v)
        mode = telemetry.flight_mode().name
        mode = _MODE_ALIASES.get(mode, mode)
        return LinkState(
            t_s=self._clock.now_s(),
            pos_ned_m=np.array([pv.position.north_m, pv.position.east_m, pv.position.down_m]),
            vel_ned_mps=np.array(
                [pv.velocity.north_m_s, pv.velocity.east_m_s, pv.velocity.down_m_s]
            ),
            q_wxyz=np.array([q.w, q.x, q.y, q.z], dtype=float),
            rates_frd_radps=np.array([rates.roll_rad_s, rates.pitch_rad_s, rates.yaw_rad_s]),
            armed=bool(telemetry.armed()),
            mode=mode if mode in FLIGHT_MODE_NAMES else "UNKNOWN",
            landed=LandedPhase.of(int(telemetry.landed_state())),
            battery_v=battery_v if math.isfinite(battery_v) and battery_v > 0.0 else None,
            vehicle_kind=_KINDS_OF_VEHICLE.get(self._require(self._system).vehicle_type()),
        )

    def arm(self) -> CommandOutcome:
        return _call(lambda: self._require(self._action).arm())

    def takeoff(self, alt_m: float) -> CommandOutcome:
        action = self._require(self._action)
        set_alt = _call(lambda: action.set_takeoff_altitude(float(alt_m)))
        return set_alt if not set_alt.accepted else _call(action.takeoff)

    def send_velocity(self, command: VelocityCommand) -> None:
        offboard = self._require(self._offboard)
        now_s = self._clock.now_s()
        state = self.read_state()
        if self._yaw_target_rad is None:
            self._yaw_target_rad = state.yaw_rad
        else:
            dt_s = min(now_s - self._yaw_updated_s, 0.5)
            self._yaw_target_rad = next_yaw_target_rad(
                self._yaw_target_rad, state.yaw_rad, command.yaw_rate_radps, dt_s
            )
        self._yaw_updated_s = now_s
        vn, ve, vd = command.vel_ned_mps
        try:
            if state.vehicle_kind == "rover":  # PX4 rover offboard: forward speed + yaw rate
                forward, right = body_velocity(vn, ve, state.yaw_rad)
                yaw_rate_dps = math.degrees(command.yaw_rate_radps)
                offboard.set_velocity_body(VelocityBodyYawspeed(forward, right, vd, yaw_rate_dps))
            else:
                yaw_deg = math.degrees(math.remainder(self._yaw_target_rad, 2.0 * math.pi))
                offboard.set_velocity_ned(VelocityNedYaw(vn, ve, vd, yaw_deg))
        except OffboardError as exc:
            raise LinkError(f"MAVSDK refused the setpoint: {exc}") from None

    def start_offboard(self) -> CommandOutcome:
        return _call(self._require(self._offboard).start)

    def read_param(self, name: str) -> float | None:
        param = self._require(self._param)
        for getter in (param.get_param_float, param.get_param_int):
            try:
                return float(getter(name))
            except Exception:
                # A parameter is optional (PX4 limits, velocity-loop gains), so any failure of
                # the param call reads as "not reported", as a pymavlink read that gets no
                # answer does: ParamError (absent, or of the other type), MavsdkError, the
                # RuntimeError of a destroyed plugin, a timeout. KeyboardInterrupt and
                # SystemExit are no Exception: they still stop the flight.
                continue
        return None

    def stop_streaming(self) -> None:
        """MAVSDK's offboard plugin re-sends the last setpoint only while the vehicle reports
        OFFBOARD (it stops by itself on a heartbeat in another mode); ``offboard.stop()``
        would command HOLD, so it is not called: nothing else is sent from here on."""
        self._offboard = None

    def hold(self) -> CommandOutcome:
        """Stop offboard (MAVSDK stops re-sending, PX4 goes to HOLD); else plain HOLD."""
        self._yaw_target_rad = None
        stopped = _call(self._require(self._offboard).stop)
        if stopped.accepted:
            return stopped
        return _call(self._require(self._action).hold)

    def land(self) -> CommandOutcome:
        return _call(self._require(self._action).land)

    def status_texts(self) -> Sequence[StatusText]:
        with self._status_texts_lock:
            return tuple(self._status_texts)

    def _on_status_text(self, status: object, _user_data: object) -> None:
        """MAVSDK's callback, on its own thread."""
        with self._status_texts_lock:
            self._status_texts.append(StatusText(self._clock.now_s(), str(status.text)))

    def metadata(self) -> Mapping[str, object]:
        return {"link": self.name, "url": self._url}

    def close(self) -> None:
        if self._mavsdk is not None:
            self._mavsdk.destroy()
            self._mavsdk = None
            self._system = self._action = self._telemetry = self._offboard = self._param = None

    def _require(self, plugin: _Plugin | None) -> _Plugin:
        if plugin is None or self._mavsdk is None:
            raise LinkError(f"link {self._url} is not connected; call connect() first")
        return plugin


def _quiet(_level: LogLevel, _message: str, _file: str | None, _line: int) -> bool:
    """MAVSDK log filter: True suppresses a message. MAVSDK's own (coloured) log lines stay out
    of the companion's output unless it runs with --verbose; what matters reaches the user as
    the link's errors and outcomes."""
    return True


def _call(command: Callable[[], object]) -> CommandOutcome:
    """Run a blocking MAVSDK command; its exception becomes a refused outcome."""
    try:
        command()
    except (ActionError, OffboardError) as exc:
        return CommandOutcome(False, exc.result.name)
    except MavsdkError as exc:
        return CommandOutcome(False, str(exc))
    return CommandOutcome(True, "")
