"""JSBSim's F450 quadcopter as a plant: normalised motor commands in, our state conventions out.

This is an edge around a C++ library (it owns an ``FGFDMExec``): it does no file I/O and keeps
JSBSim's console output away from the user unless ``verbose``. Conventions (docs/design.md
section 3):
local NED position relative to a fixed origin, NED velocity, quaternion (w, x, y, z) body(FRD)-to-
NED, FRD body rates, SI units. The origin is the point where the centre of gravity sits when the
vehicle just touches the ground below its initial position (the gear then compresses ~2 mm, so
resting on the ground gives pos_d ~ +0.002 m).
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass

import jsbsim
import numpy as np

from vehicle_sim.jsbsim_backend import f450
from vehicle_sim.jsbsim_backend.frames import (
    ecef_to_ned_matrix,
    ned_to_body_matrix,
    quat_wxyz_from_dcm,
)
from vehicle_sim.jsbsim_backend.quiet_log import CollectingLogger, logger_installed
from vehicle_sim.jsbsim_backend.units import (
    KG_PER_SLUG,
    M_PER_FT,
    M_PER_IN,
    N_PER_LBF,
    RADPS_PER_RPM,
)

CONTACT_TOLERANCE_M = 1e-3
"""A gear contact point this close to the ground counts as touching it [m]."""


@dataclass(frozen=True)
class PlantConfig:
    """Where and how the JSBSim plant starts and steps.

    Attributes:
        lat_deg, lon_deg: geodetic origin [deg] (default: PX4 SITL's home in Zurich).
        ground_alt_m: terrain elevation above mean sea level at the origin [m].
        height_m: initial height of the centre of gravity above the origin [m]; 0 = on the ground.
        yaw_rad: initial heading [rad], NED (0 = nose north, pi/2 = nose east).
        max_substep_s: largest JSBSim integration step [s]; ``step(dt_s)`` is split evenly into
            substeps no longer than this.
        verbose: let JSBSim print its start-up messages and warnings to the console.
    """

    lat_deg: float = 47.397742
    lon_deg: float = 8.545594
    ground_alt_m: float = 488.0
    height_m: float = 0.0
    yaw_rad: float = 0.0
    max_substep_s: float = 1e-3
    verbose: bool = False

    def __post_init__(self) -> None:
        if not -89.0 <= self.lat_deg <= 89.0:
            raise ValueError(f"lat_deg={self.lat_deg} is outside [-89, 89]")
        if self.height_m < 0.0:
            raise ValueError(f"height_m={self.height_m} is negative; use 0 to start on the ground")
        if not 0.0 < self.max_substep_s <= 0.01:
            raise ValueError(f"max_substep_s={self.max_substep_s} must be in (0, 0.01] s")


@dataclass(frozen=True)
class PlantState:
    """The JSBSim plant's state in our conventions.

    Attributes:
        t_s: JSBSim simulation time [s] since start.
        pos_ned_m: (3,) position of the centre of gravity relative to the origin, NED [m].
        vel_ned_mps: (3,) velocity over ground, NED [m/s].
        acc_ned_mps2: (3,) kinematic acceleration d(vel_ned)/dt over the last substep [m/s^2]
            (gravity included: about (0, 0, 9.8) in free fall, zero in hover).
        q_wxyz: (4,) attitude, body(FRD)-to-NED, w >= 0.
        rates_frd_radps: (3,) body rates relative to the earth, FRD axes [rad/s].
        thrust_n: total propeller thrust from JSBSim's propeller outputs [N].
        rotor_speeds_radps: (4,) propeller speeds in our motor order [rad/s].
        mass_kg: vehicle mass [kg].
        on_ground: a landing-gear contact point is within ``CONTACT_TOLERANCE_M`` of the ground
            or in it (true from the start when starting on the ground, unlike JSBSim's
            weight-on-wheels flag, which waits for the springs to compress).
    """

    t_s: float
    pos_ned_m: np.ndarray
    vel_ned_mps: np.ndarray
    acc_ned_mps2: np.ndarray
    q_wxyz: np.ndarray
    rates_frd_radps: np.ndarray
    thrust_n: float
    rotor_speeds_radps: np.ndarray
    mass_kg: float
    on_ground: bool


class JsbsimF450Plant:
    """JSBSim's F450 driven by four normalised motor commands in our (PX4 quad-X) order.

    Usage: ``set_motor_commands(cmds)`` then ``step(dt_s)``; ``state()`` reads the result.
    Commands hold until changed; they start at zero (motors stopped).
    """

    def __init__(self, config: PlantConfig | None = None) -> None:
        self.config = config if config is not None else PlantConfig()
        self._logger = None if self.config.verbose else CollectingLogger()
        with logger_installed(self._logger):
            self._fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
            self._fdm.set_debug_level(1 if self.config.verbose else 0)
            if not self._fdm.load_model(f450.MODEL_NAME):
                raise RuntimeError(f"JSBSim could not load its {f450.MODEL_NAME} model")
            self._n_gear = int(self._fdm["gear/num-units"])
            self._gear_agl_props = [f"gear/unit[{i}]/AGL-ft" for i in range(self._n_gear)]
            self._init_conditions()
            self._fdm.set_dt(self.config.max_substep_s)
            if not self._fdm.run_ic():
                raise RuntimeError("JSBSim failed to initialise the F450")
        self._ecef_to_ned = ecef_to_ned_matrix(
            self._fdm["position/lat-geod-rad"], self._fdm["position/long-gc-rad"]
        )
        self._origin_ecef_m = self._pos_ecef_m() + self.config.height_m * self._ecef_to_ned[2]
        self._acc_ned_mps2 = np.zeros(3)
        self._substep_s = self.config.max_substep_s

    def air_drag_coefficient_n_per_mps2(self) -> float:
        """JSBSim's own drag along the airspeed as k in D = k |v_air| v_air [N/(m/s)^2]: its
        DRAG axis is qbar * S * CD = (0.5 rho S CD) V^2, with the density at the current
        position, the reference area and the drag coefficient the model itself uses (the
        ``isotropic_drag`` the diagnosis should find)."""
        rho_kgpm3 = self._fdm["atmosphere/rho-slugs_ft3"] * KG_PER_SLUG / M_PER_FT**3
        area_m2 = self._fdm["metrics/Sw-sqft"] * M_PER_FT**2
        return 0.5 * rho_kgpm3 * area_m2 * self._fdm["aero/coefficient/CD"]

    def messages_kept(self) -> contextlib.AbstractContextManager[None]:
        """A block in which JSBSim's messages in this thread are kept off the terminal (unless
        verbose): around many steps, it routes them once instead of at every step."""
        return logger_installed(self._logger)

    @property
    def messages(self) -> tuple[str, ...]:
        """JSBSim's recent console messages that were kept off the terminal (empty if verbose)."""
        return tuple(self._logger.records) if self._logger is not None else ()

    def _gear_height_m(self) -> float:
        """Height of the centre of gravity above the ground when the gear just touches it [m]."""
        lowest_in = min(self._fdm[f"gear/unit[{i}]/z-position"] for i in range(self._n_gear))
        return (self._fdm["inertia/cg-z-in"] - lowest_in) * M_PER_IN

    def set_motor_commands(self, cmds_norm: np.ndarray) -> None:
        """Hold normalised motor commands (4,) in [0, 1], our motor order, until changed."""
        cmds = np.asarray(cmds_norm, dtype=float)
        if cmds.shape != (4,) or not np.isfinite(cmds).all():
            raise ValueError(
                f"motor commands must be 4 finite numbers in [0, 1], got {cmds_norm!r}"
            )
        for prop, value in zip(f450.ESC_COMMAND_PROPERTIES, cmds.tolist(), strict=True):
            self._fdm[prop] = min(max(value, 0.0), 1.0)

    def step(self, dt_s: float) -> None:
        """Advance by ``dt_s`` [s] in equal substeps no longer than ``config.max_substep_s``."""
        if not dt_s > 0.0:
            raise ValueError(f"dt_s={dt_s} must be positive")
        n_sub = max(1, math.ceil(dt_s / self.config.max_substep_s - 1e-9))
        substep_s = dt_s / n_sub
        if substep_s != self._substep_s:
            self._fdm.set_dt(substep_s)
            self._substep_s = substep_s
        with self.messages_kept():
            for _ in range(n_sub - 1):
                self._run()
            vel_before = self._vel_ecef_mps()
            self._run()
        self._acc_ned_mps2 = self._ecef_to_ned @ (self._vel_ecef_mps() - vel_before) / substep_s

    def state(self) -> PlantState:
        """The current state in our conventions (see ``PlantState``)."""
        fdm = self._fdm
        here_to_body = ned_to_body_matrix(
            fdm["attitude/phi-rad"], fdm["attitude/theta-rad"], fdm["attitude/psi-rad"]
        )
        here_ecef_to_ned = ecef_to_ned_matrix(
            fdm["position/lat-geod-rad"], fdm["position/long-gc-rad"]
        )
        body_to_ned = self._ecef_to_ned @ here_ecef_to_ned.T @ here_to_body.T
        thrust_lbf = sum(
            fdm[f"propulsion/engine[{i}]/thrust-lbs"] for i in f450.ENGINE_INDEX_OF_MOTOR
        )
        return PlantState(
            t_s=fdm.get_sim_time(),
            pos_ned_m=self._ecef_to_ned @ (self._pos_ecef_m() - self._origin_ecef_m),
            vel_ned_mps=self._ecef_to_ned @ self._vel_ecef_mps(),
            acc_ned_mps2=self._acc_ned_mps2.copy(),
            q_wxyz=quat_wxyz_from_dcm(body_to_ned),
            rates_frd_radps=np.array(
                [
                    fdm["velocities/p-rad_sec"],
                    fdm["velocities/q-rad_sec"],
                    fdm["velocities/r-rad_sec"],
                ]
            ),
            thrust_n=thrust_lbf * N_PER_LBF,
            rotor_speeds_radps=np.array(
                [fdm[f"propulsion/engine[{i}]/propeller-rpm"] for i in f450.ENGINE_INDEX_OF_MOTOR]
            )
            * RADPS_PER_RPM,
            mass_kg=fdm["inertia/mass-slugs"] * KG_PER_SLUG,
            on_ground=min(fdm[p] for p in self._gear_agl_props) * M_PER_FT <= CONTACT_TOLERANCE_M,
        )

    def _init_conditions(self) -> None:
        fdm, cfg = self._fdm, self.config
        for prop, value in f450.OWN_CONTROL_OFF.items():
            fdm[prop] = value
        fdm["ic/lat-geod-deg"] = cfg.lat_deg
        fdm["ic/long-gc-deg"] = cfg.lon_deg
        fdm["ic/terrain-elevation-ft"] = cfg.ground_alt_m / M_PER_FT
        fdm["ic/h-agl-ft"] = (self._gear_height_m() + cfg.height_m) / M_PER_FT
        fdm["ic/psi-true-rad"] = cfg.yaw_rad
        for prop in (
            "ic/u-fps",
            "ic/v-fps",
            "ic/w-fps",
            "ic/p-rad_sec",
            "ic/q-rad_sec",
            "ic/r-rad_sec",
        ):
            fdm[prop] = 0.0

    def _run(self) -> None:
        if not self._fdm.run():
            raise RuntimeError(f"JSBSim stopped at t={self._fdm.get_sim_time():.3f} s")

    def _pos_ecef_m(self) -> np.ndarray:
        fdm = self._fdm
        return (
            np.array(
                [fdm["position/ecef-x-ft"], fdm["position/ecef-y-ft"], fdm["position/ecef-z-ft"]]
            )
            * M_PER_FT
        )

    def _vel_ecef_mps(self) -> np.ndarray:
        fdm = self._fdm
        return (
            np.array(
                [
                    fdm["velocities/ecef-x-fps"],
                    fdm["velocities/ecef-y-fps"],
                    fdm["velocities/ecef-z-fps"],
                ]
            )
            * M_PER_FT
        )
