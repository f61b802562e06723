"""The built-in physics backend and how a backend plugs into the flight control.

A backend owns the vehicle's true state in the layout of :mod:`vehicle_sim.physics` (``x``,
``aux``) and advances it under the flight control of :mod:`vehicle_sim.flight_control`.
The built-in backend fuses both into one jitted loop (:func:`run_closed_loop`), so a whole
segment of flight is one call from Python. Another plant (e.g. JSBSim) implements
:class:`PlantBackend` by calling the jitted ``flight_control.control_step`` once per step,
feeding the motor commands to its own model and writing its state back into ``x``/``aux``.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Protocol

import numpy as np
from numba import njit

from vehicle_sim import flight_control
from vehicle_sim import physics as ph
from vehicle_sim.compile_notice import announce_compiles
from vehicle_sim.config import GRAVITY_MPS2, SimConfig
from vehicle_sim.effects import pack_effects
from vehicle_sim.flight_control import N_CONTROL_WORK, control_step_in


class PlantBackend(Protocol):
    """A physics backend the simulator's flight control can fly.

    Attributes:
        x: (physics.N_STATE,) true state, physics layout, updated in place.
        aux: (physics.N_AUX,) acceleration NED, contact flag, nominal/true thrust, commands.
    """

    x: np.ndarray
    aux: np.ndarray

    def advance(
        self,
        n_steps: int,
        dt_s: float,
        sp: np.ndarray,
        cs: np.ndarray,
        cp: np.ndarray,
        mix: np.ndarray,
        noise: np.ndarray,
    ) -> int:
        """Run up to ``n_steps`` steps of control + physics; stop early right after a step in
        which ground contact changed. ``noise`` (>= n_steps, 3): white noise for gusts.
        Returns the number of steps done."""


def sources_sha256(*modules: ModuleType) -> str:
    """sha256 (hex) of the source files of ``modules``, in order."""
    digest = hashlib.sha256()
    for module in modules:
        digest.update(Path(module.__file__).read_bytes())
    return digest.hexdigest()


def fused_loop(callees_sha256: str) -> Callable[..., int]:
    """The jitted closed loop (see :class:`PlantBackend`.advance), cached on disk by numba.

    numba keys a cached function by its own file and bytecode only, so a cached loop would keep
    running stale control or physics code after an edit of those files. Its callees' sources
    enter the key here instead: numba hashes a closure's variables into the key
    (``numba.core.caching._CacheImpl._index_key``), so the loop carries ``callees_sha256``.
    Cached, a new process skips its compile (9-14 s with its callees' on two shared cores,
    measured; said on stderr when it happens: vehicle_sim.compile_notice).
    """

    @njit(cache=True, error_model="numpy")
    def run_closed_loop(n_steps, dt, x, cs, sp, cp, mix, pp, rp, spin, ep, noise, aux):
        """Flight control + physics for up to ``n_steps``; returns the steps done."""
        _ = callees_sha256  # a closure variable: part of the cache key (see above)
        scratch = np.zeros((6, ph.N_DYN))
        u = np.zeros(4)
        n_cmd = np.zeros(4)
        work = np.empty(N_CONTROL_WORK)
        contact0 = aux[ph.AUX_CONTACT]
        for k in range(n_steps):
            control_step_in(x, aux[ph.AUX_ACC : ph.AUX_ACC + 3], sp, cs, cp, mix, dt, u, work)
            for i in range(4):
                n_cmd[i] = math.sqrt(u[i])
                aux[ph.AUX_CMD + i] = u[i]
            ph.plant_step(x, n_cmd, pp, rp, spin, ep, noise, k, dt, scratch, aux)
            if aux[ph.AUX_CONTACT] != contact0:
                return k + 1
        return n_steps

    return announce_compiles(run_closed_loop, "the simulator's compiled flight loop", 15.0)


def scheduled_loop(callees_sha256: str) -> Callable[..., int]:
    """The fused loop over a schedule of setpoint vectors and anchors, recording velocity and
    thrust: what a row of stretches of :func:`fused_loop`'s loop gives when nothing else
    happens between them (``Simulator.stream_setpoints``, ``vehicle_sim.setpoint_schedule``).
    Cached on disk as :func:`fused_loop`'s, on the same key."""

    @njit(cache=True, error_model="numpy")
    def run_scheduled(
        dt, x, cs, sp, sp_rows, change_at, anchor_rows, anchor_at, record_at, out,
        cp, mix, pp, rp, spin, ep, aux,
    ):  # fmt: skip
        """Flight control + physics for ``record_at[-1]`` steps (gusts off): ``sp`` becomes
        ``sp_rows[j]`` (m, N_SP) from step ``change_at[j]`` (m,) on (the last of equal steps
        wins), x's position to rates become ``anchor_rows[a]`` (p, 13) before step
        ``anchor_at[a]`` (p,), and ``out[i]`` (n, 4) is the velocity NED and the nominal
        thrust (aux) after step ``record_at[i]`` (n,), all in steps from the start, ascending.
        Stops right after a step in which ground contact changed. Returns the steps done."""
        _ = callees_sha256  # a closure variable: part of the cache key (see fused_loop)
        scratch = np.zeros((6, ph.N_DYN))
        u = np.zeros(4)
        n_cmd = np.zeros(4)
        work = np.empty(N_CONTROL_WORK)
        no_noise = np.zeros((1, 3))  # read only with gusts on
        contact0 = aux[ph.AUX_CONTACT]
        n_steps = record_at[-1] if len(record_at) > 0 else 0
        j = 0
        a = 0
        r = 0
        while r < len(record_at) and record_at[r] == 0:
            out[r, 0:3] = x[ph.VEL : ph.VEL + 3]
            out[r, 3] = aux[ph.AUX_THRUST_NOM]
            r += 1
        for k in range(n_steps):
            while a < len(anchor_at) and anchor_at[a] == k:
                x[ph.POS : ph.RATES + 3] = anchor_rows[a]
                a += 1
            while j < len(change_at) and change_at[j] == k:
                sp[:] = sp_rows[j]
                j += 1
            control_step_in(x, aux[ph.AUX_ACC : ph.AUX_ACC + 3], sp, cs, cp, mix, dt, u, work)
            for i in range(4):
                n_cmd[i] = math.sqrt(u[i])
                aux[ph.AUX_CMD + i] = u[i]
            ph.plant_step(x, n_cmd, pp, rp, spin, ep, no_noise, 0, dt, scratch, aux)
            while r < len(record_at) and record_at[r] == k + 1:
                out[r, 0:3] = x[ph.VEL : ph.VEL + 3]
                out[r, 3] = aux[ph.AUX_THRUST_NOM]
                r += 1
            if aux[ph.AUX_CONTACT] != contact0:
                return k + 1
        return n_steps

    what = "the simulator's compiled loop over setpoint schedules"
    return announce_compiles(run_scheduled, what, 10.0)  # 8 s after fused_loop's callees


run_closed_loop = fused_loop(sources_sha256(ph, flight_control))
run_scheduled = scheduled_loop(sources_sha256(ph, flight_control))


class BuiltinPlant:
    """The built-in rigid-body quadrotor (see :mod:`vehicle_sim.physics`)."""

    def __init__(self, config: SimConfig) -> None:
        v = config.vehicle
        self.pp = np.zeros(ph.N_PLANT)
        self.pp[ph.P_MASS] = v.mass_kg
        self.pp[ph.P_JX : ph.P_JZ + 1] = v.inertia_kgm2
        self.pp[ph.P_TMAX] = v.max_rotor_thrust_n
        self.pp[ph.P_KM] = v.torque_coeff_nm_per_radps2 / v.thrust_coeff_n_per_radps2
        self.pp[ph.P_TAU] = v.motor_time_constant_s
        self.pp[ph.P_G] = GRAVITY_MPS2
        self.rp = np.ascontiguousarray(v.rotor_positions_frd_m, dtype=np.float64)
        self.spin = np.asarray(v.rotor_spin, dtype=np.float64)
        self.ep = pack_effects(config.effects)
        self.x = np.zeros(ph.N_STATE)
        self.x[ph.QUAT] = 1.0
        self.aux = np.zeros(ph.N_AUX)
        self.aux[ph.AUX_CONTACT] = 1.0

    def advance(
        self,
        n_steps: int,
        dt_s: float,
        sp: np.ndarray,
        cs: np.ndarray,
        cp: np.ndarray,
        mix: np.ndarray,
        noise: np.ndarray,
    ) -> int:
        return run_closed_loop(
            n_steps,
            dt_s,
            self.x,
            cs,
            sp,
            cp,
            mix,
            self.pp,
            self.rp,
            self.spin,
            self.ep,
            noise,
            self.aux,
        )

    def advance_scheduled(
        self,
        dt_s: float,
        sp: np.ndarray,
        sp_rows: np.ndarray,
        change_at: np.ndarray,
        anchor_rows: np.ndarray,
        anchor_at: np.ndarray,
        record_at: np.ndarray,
        out: np.ndarray,
        cs: np.ndarray,
        cp: np.ndarray,
        mix: np.ndarray,
    ) -> int:
        """:func:`run_scheduled` on this plant (gusts off); returns the steps done."""
        return run_scheduled(
            dt_s, self.x, cs, sp, sp_rows, change_at, anchor_rows, anchor_at, record_at, out,
            cp, mix, self.pp, self.rp, self.spin, self.ep, self.aux,
        )  # fmt: skip
