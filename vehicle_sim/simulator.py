"""The in-process simulated vehicle: physics + PX4-like flight control + commander.

Stepped deterministically on simulated time; the same config, seed and call sequence give the
same numbers. See the package docstring for the contract.
"""

from __future__ import annotations

import copy
import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from vehicle_sim import flight_control as fc
from vehicle_sim import physics as ph
from vehicle_sim.anchor import (
    AnchorState,
    IntegralMode,
    body_z_ned,
    check_integral_mode,
    velocity_integral_for_thrust,
)
from vehicle_sim.backends import backend_name, make_backend
from vehicle_sim.builtin_plant import BuiltinPlant, PlantBackend
from vehicle_sim.commander import ActiveSetpoint, Commander, CommandResult
from vehicle_sim.config import GRAVITY_MPS2, SimConfig
from vehicle_sim.manual_control import Sticks, check_sticks
from vehicle_sim.mission_plan import MissionItem
from vehicle_sim.orbit import Orbit
from vehicle_sim.params import Px4Params
from vehicle_sim.setpoint_schedule import plan_stream
from vehicle_sim.truth_log import truth_row
from vehicle_sim.vehicle_types import (
    MAX_SETPOINT_POS_M,
    CheckedSetpoint,
    FlightMode,
    LandedState,
    VehicleState,
    VelocitySetpoint,
    check_setpoint,
)
from vehicle_sim.world_contact import (
    CONTACT_CHECK_STEPS,
    DEFAULT_VEHICLE_RADIUS_M,
    Contact,
    ContactWorld,
    RangeScan,
    RangeSensorSpec,
    scan_world,
)

NOISE_BLOCK_ROWS = 4096
# A stream flies in one compiled call only if its setpoints stay this much younger than
# COM_OF_LOSS_T [s] (the loss would be a deadline between its legs).
STREAM_FRESH_MARGIN_S = 1e-6
BATTERY_MARGIN = 1e-9  # of charge: rounding of a stream's discharge bound (far above it)
_NO_POSITION = (math.nan, math.nan, math.nan)
ATOMIC_TYPES = frozenset({bool, int, float, str, type(None)})  # deepcopy returns them as they are


@dataclass(frozen=True)
class StreamedLegs:
    """What :meth:`Simulator.stream_setpoints` flew: at the end of each of its n legs, the
    true velocity NED ``vel_ned_mps`` (n, 3) [m/s] and total rotor thrust ``thrust_n`` (n,)
    [N] (as :attr:`Simulator.vel_ned_mps` and :attr:`Simulator.thrust_n`)."""

    vel_ned_mps: np.ndarray
    thrust_n: np.ndarray

    @classmethod
    def of(cls, record: np.ndarray) -> StreamedLegs:
        """From a stream's record (n, 4): velocity, thrust."""
        return cls(record[:, 0:3], record[:, 3])


class Simulator:
    """A simulated PX4 multicopter, stepped in-process.

    Args:
        config: vehicle preset and effects (:func:`vehicle_sim.load_sim_config`).
        seed: seed of the vehicle's own random generator (gusts).
        backend: physics backend, or its name: "builtin" (the rigid body) or "jsbsim" (JSBSim's
            F450; use preset "f450"), see :mod:`vehicle_sim.backends`; None: the config's
            ``[sim] backend`` (by default "builtin").

    ``backend_name`` is the backend flown (its class name for a backend object). The vehicle
    starts disarmed, on the ground at the NED origin, in HOLD.
    """

    def __init__(
        self, config: SimConfig, seed: int = 0, backend: PlantBackend | str | None = None
    ) -> None:
        self.config = config
        self.seed = seed
        self.physics_dt_s = config.physics_dt_s
        self.backend_name = backend_name(backend, config)
        self._plant = make_backend(backend, config)
        self._params = Px4Params(
            {"MPC_THR_HOVER": config.vehicle.hover_thrust_norm, **dict(config.px4_params)}
        )
        self._cp = self._params.control_vector(GRAVITY_MPS2)
        self._cp_version = self._params.version
        v = config.vehicle
        self._mix = fc.mixer_matrix(
            np.array(v.rotor_positions_frd_m),
            np.array(v.rotor_spin),
            v.torque_coeff_nm_per_radps2 / v.thrust_coeff_n_per_radps2,
        )
        self._max_total_thrust_n = len(v.rotor_spin) * v.max_rotor_thrust_n
        self._cs = np.zeros(fc.N_CTRL)
        self._sp = np.zeros(fc.N_SP)
        self._commander = Commander(self._params)
        self._epoch = self._commander.mode_epoch
        self._k = 0
        self._rng = np.random.default_rng(seed)
        gusts = config.effect("gusts")
        self._gust_on = gusts is not None and gusts.intensity_mps > 0.0
        self._noise = np.zeros((0, 3))
        self._noise_pos = 0
        if self._gust_on:
            start = gusts.intensity_mps * self._rng.standard_normal(3)
            self._plant.x[ph.GUST : ph.GUST + 3] = start
        delay = config.effect("command_delay")
        self._delay_steps = 0 if delay is None else round(delay.delay_s / self.physics_dt_s)
        self._pending: deque[tuple[int, VelocitySetpoint]] = deque()
        self._active: ActiveSetpoint | None = None
        fc.reset_controller(self._plant.x, self._cs)
        self._world: ContactWorld | None = None
        self._vehicle_radius_m = DEFAULT_VEHICLE_RADIUS_M
        self._range_sensor = RangeSensorSpec()
        self.contacts: list[Contact] = []

    def __deepcopy__(self, memo: dict[int, object]) -> Simulator:
        """An independent copy (``copy.deepcopy``): it shares the config (immutable) and its
        generator continues from this one's state (the same gust noise from here on).

        A replay copies the vehicle for every window: the generator's state is set on a new
        one (``copy.copy`` of a bit generator seeds it from the OS first), and attributes of
        the types deepcopy returns unchanged (numbers, strings, None) are taken as they are.
        """
        memo[id(self.config)] = self.config
        bit_generator = type(self._rng.bit_generator)(0)  # its state is set next
        bit_generator.state = self._rng.bit_generator.state
        memo[id(self._rng)] = np.random.Generator(bit_generator)
        clone = object.__new__(type(self))
        memo[id(self)] = clone
        clone.__dict__.update(
            {
                name: value if type(value) in ATOMIC_TYPES else copy.deepcopy(value, memo)
                for name, value in self.__dict__.items()
            }
        )
        return clone

    # --- the world ------------------------------------------------------------------------------
    def set_world(
        self,
        world: ContactWorld | None,
        vehicle_radius_m: float = DEFAULT_VEHICLE_RADIUS_M,
        range_sensor: RangeSensorSpec | None = None,
    ) -> None:
        """Obstacles the vehicle can hit and its range sensor sees (see
        :mod:`vehicle_sim.world_contact`); None removes them. ``vehicle_radius_m`` [m] is the
        radius of the sphere around the centre that counts as the vehicle."""
        if not vehicle_radius_m > 0:
            raise ValueError(f"vehicle_radius_m must be > 0, got {vehicle_radius_m}")
        self._world = world
        self._vehicle_radius_m = float(vehicle_radius_m)
        self._range_sensor = range_sensor or RangeSensorSpec()

    @property
    def world(self) -> ContactWorld | None:
        return self._world

    @property
    def range_sensor(self) -> RangeSensorSpec:
        return self._range_sensor

    @property
    def crashed(self) -> bool:
        """True once the vehicle has touched an obstacle."""
        return bool(self.contacts)

    def range_scan(self) -> RangeScan | None:
        """A scan of the world from the vehicle's position now, None without a world."""
        if self._world is None:
            return None
        pos = self._plant.x[ph.POS : ph.POS + 3].copy()
        return scan_world(self._world, self._range_sensor, self.t_s, pos)

    # --- time ---------------------------------------------------------------------------------
    @property
    def t_s(self) -> float:
        """Simulated time [s]."""
        return self._k * self.physics_dt_s

    def step(self, duration_s: float) -> VehicleState:
        """Advance by ``duration_s`` (rounded to whole physics steps); returns the new state."""
        self.advance(duration_s)
        return self.state

    def advance(self, duration_s: float) -> None:
        """:meth:`step` without building the new state (a fifth of a short step's cost), for
        loops that do not read it, e.g. a replay's anchored follower."""
        if not (math.isfinite(duration_s) and duration_s >= 0.0):
            raise ValueError(f"step duration {duration_s!r} s must be finite and >= 0")
        # (a NumPy scalar's round takes microseconds)
        self._advance_steps(round(float(duration_s) / self.physics_dt_s))

    def stream_setpoints(
        self,
        setpoints: Sequence[VelocitySetpoint | None],
        durations_s: Sequence[float],
        anchors: Sequence[AnchorState | None] | None = None,
    ) -> StreamedLegs:
        """Fly a row of legs; returns the true velocity and thrust at the end of each.
        Leg i takes ``setpoints[i]`` (None: keeps the one in force), is anchored at
        ``anchors[i]`` if given (:meth:`anchor`, the integral kept) and advances
        ``durations_s[i]`` [s]: the numbers of :meth:`set_velocity_setpoint`, :meth:`anchor`,
        :meth:`advance`, :attr:`vel_ned_mps` and :attr:`thrust_n` leg by leg, to the last
        bit. In an OFFBOARD flight whose commander only watches the setpoints' age
        (``Commander.idle_in_offboard``), streamed NED setpoints already checked
        (``CheckedSetpoint``), the built-in plant without obstacles or gusts and with a battery
        that cannot reach a failsafe threshold within the legs, and
        anchors without thrust or acceleration on legs of at least one step, the whole row is
        one compiled call instead of Python steps around each leg (a replay's follower and its
        windows); from a touchdown on, and otherwise, leg by leg.

        Raises:
            ValueError: ``setpoints`` and ``durations_s`` differ in length; or a leg's setpoint
                or duration :meth:`set_velocity_setpoint` or :meth:`advance` refuses (the legs
                before it flown).
        """
        if len(setpoints) != len(durations_s):
            raise ValueError(
                f"{len(setpoints)} setpoints for {len(durations_s)} leg durations: give one "
                "per leg (None keeps the one in force)"
            )
        if anchors is not None and len(anchors) != len(setpoints):
            raise ValueError(f"{len(anchors)} anchors for {len(setpoints)} legs: give one per leg")
        out = np.empty((len(setpoints), 4))
        steps = [
            round(float(d) / self.physics_dt_s) if math.isfinite(d) and d >= 0.0 else -1
            for d in durations_s
        ]
        if min(steps, default=0) < 0 or not self._streams_compiled(setpoints, steps, anchors):
            return StreamedLegs.of(self._stream_legs(setpoints, durations_s, anchors, 0, out))
        plan = plan_stream(
            self._k, steps, setpoints, self._delay_steps, self._active, tuple(self._pending)
        )
        first, later = np.empty((1, fc.N_SP)), plan.changes[1:]
        self._commander.fill_setpoint(first[0], False, plan.changes[0])
        rows = np.vstack(
            [
                first,
                self._commander.offboard_rows(
                    [sp.vel_mps for sp in later],
                    [sp.yaw_rate_radps for sp in later],
                    [math.nan if sp.yaw_rad is None else sp.yaw_rad for sp in later],
                    [_NO_POSITION if sp.pos_ned_m is None else sp.pos_ned_m for sp in later],
                ),
            ]
        )
        anchored = [i for i, a in enumerate(anchors or ()) if a is not None]
        anchor_rows = np.array([anchors[i].physics_state for i in anchored]).reshape(-1, 13)
        self._refresh_control_params()
        done = self._plant.advance_scheduled(
            self.physics_dt_s, self._sp, rows, plan.change_at, anchor_rows,
            plan.leg_start[anchored], plan.leg_end, out, self._cs, self._cp, self._mix,
        )  # fmt: skip
        total = int(plan.leg_end[-1]) if steps else 0
        now = plan.state_after(done, at_end=done == total)
        if now.last_set_at is not None:
            self._commander.on_setpoint((self._k + now.last_set_at) * self.physics_dt_s)
        if now.in_force is not plan.changes[0]:
            self._active = self._to_ned(now.in_force)
        self._pending = deque(now.queued)
        self._k += done
        if done > 0:
            self._update_commander()
        if done < total:  # touched down: the leg under way and the rest, leg by leg
            leg = now.legs_begun - 1
            self._advance_steps(int(plan.leg_end[leg]) - done)
            self._record_leg(out, leg)
            self._stream_legs(setpoints, durations_s, anchors, now.legs_begun, out)
        return StreamedLegs.of(out)

    def _streams_compiled(
        self,
        setpoints: Sequence[VelocitySetpoint | None],
        steps: list[int],
        anchors: Sequence[AnchorState | None] | None,
    ) -> bool:
        """Whether :meth:`stream_setpoints` may fly these legs in one compiled call (see there):
        nothing but the setpoints and anchors changes what the commander and the flight
        control do, and no setpoint grows older than COM_OF_LOSS_T before the next."""
        if anchors is not None and (
            min(steps, default=1) < 1
            or any(a is not None and (a.thrust_n or a.acc_ned_mps2 is not None) for a in anchors)
        ):
            return False
        plant = self._plant
        if not (
            type(plant) is BuiltinPlant
            and self._world is None
            and not self._gust_on
            and self._battery_level_holds(sum(steps))
            and plant.aux[ph.AUX_CONTACT] <= 0.5
            and self._commander.idle_in_offboard(self.t_s)
        ):
            return False
        queued = [sp for _, sp in self._pending]
        if any(
            sp is not None and (type(sp) is not CheckedSetpoint or sp.frame != "ned")
            for sp in (*setpoints, *queued)
        ):
            return False
        dt, loss_s = self.physics_dt_s, self._commander.offboard_loss_s()
        last_set_s, k = self._commander.last_setpoint_s, self._k
        for sp, n in zip(setpoints, steps, strict=True):
            if sp is not None:
                last_set_s = k * dt
            k += n
            if k * dt - last_set_s >= loss_s - STREAM_FRESH_MARGIN_S:
                return False
        return True

    def _battery_level_holds(self, n_steps: int) -> bool:
        """Whether the battery cannot fall below a failsafe threshold
        (:meth:`FailsafeMonitor.battery_thresholds`) within ``n_steps`` physics steps: not
        even at full thrust all along (the physics discharges ``dt`` nominal thrust / weight /
        BATTERY_TIME per step, the nominal thrust at most four rotors' maximum). Then the
        commander has nothing to do with the battery while they fly."""
        plant = self._plant
        battery_time_s = plant.ep[ph.BATTERY_TIME]
        if battery_time_s == 0.0:
            return True
        pp = plant.pp
        most = n_steps * self.physics_dt_s * 4.0 * pp[ph.P_TMAX]
        most /= pp[ph.P_MASS] * pp[ph.P_G] * battery_time_s
        remaining = 1.0 - float(plant.x[ph.DISCHARGE])
        lowest = remaining - most - BATTERY_MARGIN
        thresholds = self._commander.failsafes.battery_thresholds()
        return not any(lowest < t <= remaining for t in thresholds)

    def _stream_legs(
        self,
        setpoints: Sequence[VelocitySetpoint | None],
        durations_s: Sequence[float],
        anchors: Sequence[AnchorState | None] | None,
        first: int,
        out: np.ndarray,
    ) -> np.ndarray:
        """Legs ``first``.. of :meth:`stream_setpoints` one by one, velocities into ``out``."""
        for i in range(first, len(setpoints)):
            if setpoints[i] is not None:
                self.set_velocity_setpoint(setpoints[i])
            if anchors is not None and anchors[i] is not None:
                self.anchor(anchors[i])
            self.advance(durations_s[i])
            self._record_leg(out, i)
        return out

    def _record_leg(self, out: np.ndarray, i: int) -> None:
        """Row ``i`` of a stream's record (n, 4): velocity NED [m/s], nominal thrust [N]."""
        out[i, 0:3] = self._plant.x[ph.VEL : ph.VEL + 3]
        out[i, 3] = self._plant.aux[ph.AUX_THRUST_NOM]

    def _advance_steps(self, remaining: int) -> None:
        """:meth:`advance` by ``remaining`` physics steps."""
        dt = self.physics_dt_s
        plant, commander, aux = self._plant, self._commander, self._plant.aux
        self._refresh_control_params()
        while remaining > 0:
            if self._pending:
                self._release_setpoints()
            commander.fill_setpoint(self._sp, aux[ph.AUX_CONTACT] > 0.5, self._active)
            n = remaining
            t_s = self._k * dt
            steps_to_deadline = (commander.next_deadline(t_s) - t_s) / dt
            if steps_to_deadline < n:  # (rounded to 1e-6, steps_to_deadline >= n cuts nothing)
                n = min(n, max(1, math.ceil(round(steps_to_deadline, 6))))
            if self._pending:
                n = min(n, max(1, self._pending[0][0] - self._k))
            if self._world is not None:
                n = min(n, CONTACT_CHECK_STEPS)
                before = plant.x[ph.POS : ph.POS + 3].copy()
            noise = self._noise_rows(n) if self._gust_on else self._noise
            done = plant.advance(n, dt, self._sp, self._cs, self._cp, self._mix, noise)
            if not 0 < done <= n:
                raise RuntimeError(f"physics backend did {done} of {n} steps; it must do 1..{n}")
            if self._world is not None:
                self._check_contact(before, done)
            if self._gust_on:
                self._noise_pos += done
            self._k += done
            remaining -= done
            self._update_commander()

    # --- commands -----------------------------------------------------------------------------
    def arm(self, force: bool = False) -> CommandResult:
        """Arm (on the ground; in OFFBOARD only with a fresh setpoint stream)."""
        return self._command(lambda c, t, p, y: c.arm(t, p, force))

    def disarm(self, force: bool = False) -> CommandResult:
        """Disarm; refused in the air unless ``force`` (then the vehicle falls)."""
        return self._command(lambda c, t, p, y: c.disarm(t, force))

    def takeoff(self, alt_m: float | None = None) -> CommandResult:
        """TAKEOFF to ``alt_m`` above home (None/NaN: MIS_TAKEOFF_ALT) at MPC_TKO_SPEED, then
        HOLD. Needs the vehicle armed."""
        return self._command(lambda c, t, p, y: c.takeoff(t, p, y, alt_m))

    def land(self) -> CommandResult:
        """LAND here at MPC_LAND_SPEED; disarms COM_DISARM_LAND after touchdown."""
        return self._command(lambda c, t, p, y: c.land(t, p, y))

    def set_mode(self, mode: FlightMode) -> CommandResult:
        """Switch mode. OFFBOARD needs a setpoint younger than COM_OF_LOSS_T; HOLD holds where
        the vehicle stops (PX4's braking distance ahead), POSCTL brakes, then holds; RTL
        climbs to RTL_RETURN_ALT, returns home and lands; MISSION flies the uploaded mission
        (taking off first when on the ground)."""
        if not isinstance(mode, FlightMode):
            raise ValueError(f"mode must be a FlightMode, got {mode!r}; use FlightMode.parse(name)")
        return self._command(lambda c, t, p, y: c.set_mode(mode, t, p, y))

    def set_mission(self, items: tuple[MissionItem, ...]) -> None:
        """Replace the mission (see :mod:`vehicle_sim.mission_plan`); () clears it."""
        self._commander.set_mission(tuple(items))
        self._sync_mode()

    def set_mission_current(self, seq: int) -> CommandResult:
        """Make item ``seq`` the next one flown (MISSION_SET_CURRENT)."""
        return self._commander.set_mission_current(seq)

    @property
    def mission(self) -> tuple[MissionItem, ...]:
        """The mission as uploaded."""
        return self._commander.mission

    @property
    def mission_current(self) -> int:
        """The item flown now (== len(mission) when the mission is complete)."""
        return self._commander.mission_current

    def drain_mission_reached(self) -> list[int]:
        """Items reached since the last call, in order (MISSION_ITEM_REACHED)."""
        reached = self._commander.mission_reached
        self._commander.mission_reached = []
        return reached

    def on_gcs_heartbeat(self) -> None:
        """A ground station's heartbeat arrived now (watched for NAV_DLL_ACT)."""
        self._commander.failsafes.gcs_heartbeat(self.t_s)

    def reposition(self, target_ned_m: tuple[float, float, float]) -> CommandResult:
        """Fly to ``target_ned_m`` (NaN components keep the current ones) and hold there, as
        PX4 does for MAV_CMD_DO_REPOSITION; needs the vehicle flying."""
        target = np.asarray(target_ned_m, dtype=float)
        if target.shape != (3,) or np.any(np.isinf(target)):
            raise ValueError(
                f"reposition target must be 3 finite or NaN values, got {target_ned_m}"
            )
        return self._command(lambda c, t, p, y: c.reposition(p, target))

    def orbit(
        self,
        radius_m: float = math.nan,
        velocity_mps: float = math.nan,
        yaw_behaviour: float = math.nan,
        centre_ne_m: tuple[float, float] | None = None,
        down_m: float | None = None,
    ) -> CommandResult:
        """Fly PX4's Orbit mode (MAV_CMD_DO_ORBIT): circle ``centre_ne_m`` (local north, east
        [m]; None: the current orbit's centre, else here) at ``radius_m`` [m] (negative:
        counter-clockwise) and ``velocity_mps`` [m/s] at ``down_m`` (local NED [m]; None: the
        current orbit's, else here), yaw per ``yaw_behaviour`` (ORBIT_YAW_BEHAVIOUR 0-4; 5,
        UNCHANGED, as NaN); NaN keeps a value of the orbit flown (see :mod:`vehicle_sim.orbit`
        for defaults and limits). Needs the vehicle flying.

        Raises:
            ValueError: an infinite value, or a centre or altitude that is not finite.
        """
        values = (radius_m, velocity_mps, yaw_behaviour)
        if any(math.isinf(v) for v in values) or (
            centre_ne_m is not None and not all(math.isfinite(v) for v in centre_ne_m)
        ):
            raise ValueError(f"orbit {values} around {centre_ne_m} needs finite or NaN values")
        if centre_ne_m is not None and max(map(abs, centre_ne_m)) > MAX_SETPOINT_POS_M:
            north, east = centre_ne_m
            raise ValueError(
                f"orbit centre N {north:.0f} E {east:.0f} m is beyond "
                f"{MAX_SETPOINT_POS_M / 1e3:g} km of home"
            )
        if down_m is not None and not abs(down_m) <= MAX_SETPOINT_POS_M:
            raise ValueError(f"orbit altitude {down_m!r} must be finite and within reach")
        return self._command(
            lambda c, t, p, y: c.start_orbit(
                p, y, radius_m, velocity_mps, yaw_behaviour, centre_ne_m, down_m
            )
        )

    @property
    def orbit_status(self) -> Orbit | None:
        """The orbit flown now (None outside ORBIT), for ORBIT_EXECUTION_STATUS."""
        return self._commander.orbit if self._commander.mode is FlightMode.ORBIT else None

    def set_velocity_setpoint(self, sp: VelocitySetpoint) -> None:
        """Take a velocity setpoint (acted on in OFFBOARD, after any command delay).

        Raises:
            ValueError: non-finite or absurd values, or an unknown frame; nothing changes then.
        """
        if type(sp) is not CheckedSetpoint:  # (one is valid and immutable: checked when built)
            check_setpoint(sp)
        self._commander.on_setpoint(self.t_s)
        if self._delay_steps == 0:
            self._active = self._to_ned(sp)
        else:
            self._pending.append((self._k + self._delay_steps, sp))

    def set_sticks(self, sticks: Sticks) -> bool:
        """Take a pilot's stick reading (an RC or a joystick's MANUAL_CONTROL, normalised: see
        :class:`vehicle_sim.manual_control.Sticks`). It flies POSCTL and ALTCTL, may take the
        vehicle out of an auto mode or OFFBOARD (COM_RC_OVERRIDE) and keeps the
        manual-control-loss failsafe (COM_RC_LOSS_T, NAV_RCL_ACT) quiet. Returns False, and
        does nothing, when COM_RC_IN_MODE is 0 (RC only) or 4 (stick input disabled): PX4 then
        ignores a MAVLink joystick.

        Raises:
            ValueError: a value that is not finite or outside its range; nothing changes then.
        """
        check_sticks(sticks)
        if int(self._params.get("COM_RC_IN_MODE")) in (0, 4):
            return False
        x = self._plant.x
        self._commander.on_sticks(self.t_s, sticks, x[ph.POS : ph.POS + 3].copy(), fc.yaw_of(x))
        self._sync_mode()
        return True

    def drain_events(self) -> list[tuple[int, str]]:
        """(MAV_SEVERITY, text) events since the last drain."""
        events = list(self._commander.events)
        self._commander.events.clear()
        return events

    # --- parameters -----------------------------------------------------------------------------
    @property
    def params(self) -> Px4Params:
        """The PX4-named parameters (changes through it also take effect at the next step)."""
        return self._params

    def get_param(self, name: str) -> float:
        """A PX4 parameter's value; unknown names raise ValueError listing the known ones."""
        return self._params.get(name)

    def set_param(self, name: str, value: float) -> None:
        """Set a PX4 parameter (takes effect at the next step)."""
        self._params.set(name, value)

    def param_type(self, name: str) -> str:
        """PX4's type of a parameter: "FLOAT" or "INT32"."""
        return self._params.spec(name).type

    def param_names(self) -> tuple[str, ...]:
        """All parameter names in a stable order (the PARAM_VALUE index)."""
        return self._params.names()

    # --- anchoring (replay from measured states) ---------------------------------------------
    def anchor(self, state: AnchorState, integral: IntegralMode = "keep") -> None:
        """Put the vehicle into the measured ``state``, to replay logged setpoints from it.

        Writes position, velocity, attitude and body rates; scales the rotor speeds to
        ``state.thrust_n`` and takes ``state.acc_ned_mps2`` as the acceleration the velocity
        loop sees next, when given. Time, mode, setpoints (also those delayed in flight), gust
        and battery state are kept. ``integral`` says what happens to the flight control state:
        "keep" leaves it; "reset" clears the integrators and aligns the yaw setpoint with the
        new yaw; "match_thrust" clears the rate integral and sets the velocity integral so that,
        with the velocity setpoint in force now (give the setpoint first), the flight control
        commands the measured thrust vector (``thrust_n`` along the new body -z): the integral
        the measured vehicle had built up, e.g. for a payload. Needs thrust_n and acc_ned_mps2.

        Raises:
            ValueError: an unknown ``integral`` mode, or "match_thrust" without thrust or
                acceleration (the state itself is validated by :class:`AnchorState`).
            NotImplementedError: a backend other than the built-in one (JSBSim owns its state).
        """
        check_integral_mode(integral, state)
        if not isinstance(self._plant, BuiltinPlant):
            raise NotImplementedError(
                f"anchor() needs the builtin backend; {type(self._plant).__name__} owns its state"
            )
        x, aux = self._plant.x, self._plant.aux
        x[ph.POS : ph.RATES + 3] = state.physics_state
        if state.thrust_n:
            t_max = self.config.vehicle.max_rotor_thrust_n
            r0, r1, r2, r3 = x[ph.MOTORS : ph.MOTORS + 4].tolist()
            sim_thrust_n = t_max * (r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3)
            if sim_thrust_n > 0.0:
                scale = math.sqrt(state.thrust_n / sim_thrust_n)
                r0, r1, r2, r3 = (min(max(r * scale, 0.0), 1.0) for r in (r0, r1, r2, r3))
                x[ph.MOTORS : ph.MOTORS + 4] = (r0, r1, r2, r3)
                aux[ph.AUX_THRUST_NOM] = t_max * (r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3)
        if state.acc_ned_mps2 is not None:
            aux[ph.AUX_ACC : ph.AUX_ACC + 3] = state.acc_ned_mps2
        if integral == "reset":
            fc.reset_controller(x, self._cs)
        elif integral == "match_thrust":
            self._refresh_control_params()
            self._cs[fc.CS_RATE_INT : fc.CS_RATE_INT + 3] = 0.0
            vsp = np.zeros(3) if self._active is None else np.array(self._active.vel_ned_mps)
            thr = -body_z_ned(state.q_wxyz) * (state.thrust_n / self._max_total_thrust_n)
            vel_int = velocity_integral_for_thrust(state, vsp, thr, self._cp)
            if vel_int is not None:
                self._cs[fc.CS_VEL_INT : fc.CS_VEL_INT + 3] = vel_int

    @property
    def velocity_integral_mps2(self) -> np.ndarray:
        """(3,) the velocity loop's integral term, NED [m/s^2] (a copy)."""
        return self._cs[fc.CS_VEL_INT : fc.CS_VEL_INT + 3].copy()

    def set_velocity_integral(self, value_mps2: np.ndarray) -> None:
        """Set the velocity loop's integral term (3,) NED [m/s^2], e.g. the integral a replayed
        run starts with, fitted to its measured velocities.

        Raises:
            ValueError: not 3 finite numbers; nothing changes then.
        """
        value = np.asarray(value_mps2, dtype=float)
        if value.shape != (3,) or not np.all(np.isfinite(value)):
            raise ValueError(f"velocity integral {value_mps2!r} must be 3 finite numbers [m/s^2]")
        self._cs[fc.CS_VEL_INT : fc.CS_VEL_INT + 3] = value

    # parts of :attr:`state` without building it, for loops that read only them (a replay)
    @property
    def vel_ned_mps(self) -> np.ndarray:
        """(3,) the true velocity NED now [m/s] (a copy), as ``state.vel_ned_mps``."""
        return self._plant.x[ph.VEL : ph.VEL + 3].copy()

    @property
    def thrust_n(self) -> float:
        """The total rotor thrust now [N], as ``state.thrust_n``."""
        return float(self._plant.aux[ph.AUX_THRUST_NOM])

    @property
    def landed_state(self) -> LandedState:
        """The flight controller's landed state now, as ``state.landed_state``."""
        return self._commander.landed_state(self._plant.aux[ph.AUX_CONTACT] > 0.5)

    # --- state and logging ----------------------------------------------------------------------
    @property
    def state(self) -> VehicleState:
        """The true state now. ``thrust_n`` is the total rotor thrust [N]: on the built-in
        backend what the nominal rotor model gives for the current rotor speeds (what a vehicle
        with RPM telemetry would report), on "jsbsim" JSBSim's propeller thrust."""
        x, aux = self._plant.x, self._plant.aux
        v = self.config.vehicle
        discharge = x[ph.DISCHARGE]
        return VehicleState(
            t_s=self.t_s,
            pos_ned_m=x[ph.POS : ph.POS + 3].copy(),
            vel_ned_mps=self.vel_ned_mps,
            acc_ned_mps2=aux[ph.AUX_ACC : ph.AUX_ACC + 3].copy(),
            q_wxyz=x[ph.QUAT : ph.QUAT + 4].copy(),
            rates_frd_radps=x[ph.RATES : ph.RATES + 3].copy(),
            thrust_n=self.thrust_n,
            motor_speeds_norm=x[ph.MOTORS : ph.MOTORS + 4].copy(),
            battery_v=v.battery_full_v - (v.battery_full_v - v.battery_empty_v) * discharge,
            armed=self._commander.armed,
            mode=self._commander.mode,
            landed_state=self.landed_state,
            home_ned_m=self._commander.home_ned_m,
        )

    def log_row(self, cmd: VelocitySetpoint | None = None) -> dict[str, float | str]:
        """One schema-v1 row of the true state with the command ``cmd`` (body converted to NED);
        with None, the velocity setpoint the flight control is tracking now."""
        if cmd is None:
            vel = tuple(float(v) for v in self._cs[fc.CS_VEL_SP : fc.CS_VEL_SP + 3])
            yaw_rate = float(self._sp[fc.SP_YAW_RATE])
        else:
            check_setpoint(cmd)
            active = self._to_ned(cmd)
            vel, yaw_rate = active.vel_ned_mps, active.yaw_rate_radps
        row = truth_row(self.state, vel, yaw_rate)
        if self._world is not None:
            row["crash"] = 1.0 if self.crashed else 0.0
        return row

    def log_metadata(self) -> dict[str, object]:
        """Sidecar metadata for a truth log of this vehicle (no effect ground truth)."""
        return {
            "source": "vehicle_sim",
            "vehicle": self.config.preset_name,
            "backend": self.backend_name,
            "mass_kg": self.config.mass_kg,
            "physics_dt_s": self.physics_dt_s,
        }

    # --- internals ------------------------------------------------------------------------------
    def _command(
        self, fn: Callable[[Commander, float, np.ndarray, float], CommandResult]
    ) -> CommandResult:
        x = self._plant.x
        result = fn(self._commander, self.t_s, x[ph.POS : ph.POS + 3].copy(), fc.yaw_of(x))
        self._sync_mode()
        return result

    def _check_contact(self, before_ned_m: np.ndarray, steps: int) -> None:
        """A contact on the segment swept since ``before_ned_m`` crashes the vehicle once."""
        x = self._plant.x
        after = x[ph.POS : ph.POS + 3].copy()
        clearance = self._world.segment_clearance_m(before_ned_m, after)
        if clearance >= self._vehicle_radius_m or self.crashed:
            return
        t_s = (self._k + steps) * self.physics_dt_s
        speed = float(np.linalg.norm(x[ph.VEL : ph.VEL + 3]))
        pos = tuple(float(v) for v in after)
        self.contacts.append(Contact(t_s, pos, speed, float(clearance)))
        self._commander.disarm(t_s, force=True)
        self._commander.events.append(
            (
                2,  # MAV_SEVERITY_CRITICAL
                f"Crash: contact with an obstacle at N {pos[0]:.1f} E {pos[1]:.1f} m, "
                f"{speed:.1f} m/s; motors cut",
            )
        )
        self._sync_mode()

    def _refresh_control_params(self) -> None:
        if self._cp_version != self._params.version:
            self._cp = self._params.control_vector(GRAVITY_MPS2)
            self._cp_version = self._params.version

    def _update_commander(self) -> None:
        x = self._plant.x
        contact = self._plant.aux[ph.AUX_CONTACT] > 0.5
        self._commander.update(
            self._k * self.physics_dt_s,
            x[ph.POS : ph.POS + 3],
            fc.yaw_of(x),
            contact,
            1.0 - float(x[ph.DISCHARGE]),
            x[ph.VEL : ph.VEL + 3],
        )
        self._sync_mode()

    def _sync_mode(self) -> None:
        if self._commander.mode_epoch != self._epoch:
            self._epoch = self._commander.mode_epoch
            self._cs[fc.CS_YAW_SP] = fc.yaw_of(self._plant.x)

    def _release_setpoints(self) -> None:
        while self._pending and self._pending[0][0] <= self._k:
            self._active = self._to_ned(self._pending.popleft()[1])

    def _to_ned(self, sp: VelocitySetpoint) -> ActiveSetpoint:
        if type(sp) is CheckedSetpoint and sp.frame == "ned":  # (its numbers are floats)
            return ActiveSetpoint(sp.vel_mps, sp.yaw_rate_radps, sp.yaw_rad, sp.pos_ned_m)
        vx, vy, vz = map(float, sp.vel_mps)
        if sp.frame == "body":
            yaw = fc.yaw_of(self._plant.x)
            c, s = math.cos(yaw), math.sin(yaw)
            vx, vy = c * vx - s * vy, s * vx + c * vy
        yaw_rad = None if sp.yaw_rad is None else float(sp.yaw_rad)
        pos = None if sp.pos_ned_m is None else tuple(float(v) for v in sp.pos_ned_m)
        return ActiveSetpoint((vx, vy, vz), float(sp.yaw_rate_radps), yaw_rad, pos)

    def _noise_rows(self, n: int) -> np.ndarray:
        """The next ``n`` rows (n, 3) of the gusts' white noise (gusts on)."""
        if self._noise_pos + n > len(self._noise):
            rest = self._noise[self._noise_pos :]
            block = self._rng.standard_normal((max(NOISE_BLOCK_ROWS, n), 3))
            self._noise = np.ascontiguousarray(np.vstack([rest, block]))
            self._noise_pos = 0
        return self._noise[self._noise_pos : self._noise_pos + n]
