"""JSBSim's F450 as a simulator backend: our flight control drives its four motors.

Implements ``vehicle_sim.builtin_plant.PlantBackend``: per step, the jitted PX4-like
``flight_control.control_step`` turns the state into normalised motor thrust commands u, the
ESCs get rotor-speed commands sqrt(u) (as the built-in physics does), JSBSim advances, and its
state is written back into the physics layout (``x``, ``aux``) that the simulator reads. The
thrust reported (both aux thrust entries) is JSBSim's propeller output, the acceleration the
measured d(vel)/dt. Gusts, battery discharge and the built-in effects do not exist on this plant;
JSBSim models its own drag, propeller inflow and landing gear.
"""

from __future__ import annotations

import numpy as np

from vehicle_sim import physics as ph
from vehicle_sim.config import SimConfig
from vehicle_sim.effects import SimConfigError
from vehicle_sim.flight_control import control_step
from vehicle_sim.jsbsim_backend.plant import JsbsimF450Plant, PlantConfig, PlantState

MASS_TOLERANCE = 0.05
"""Largest relative difference between the preset's mass and JSBSim's F450 we accept."""


class JsbsimBackend:
    """The simulator's plant backend "jsbsim" (see ``PlantBackend`` for the contract).

    Args:
        config: the simulator config; its vehicle preset must describe the F450 (preset
            "f450": the flight control takes hover thrust and mixer from it, and the rotor speeds
            are normalised by its maximum); effects are refused (they are built-in physics).
        plant_config: where JSBSim starts (default: on the ground at the default origin).
    """

    def __init__(self, config: SimConfig, plant_config: PlantConfig | None = None) -> None:
        if config.effects:
            raise SimConfigError(
                f"effects.{config.effect_names[0]}: effects belong to the built-in physics; "
                "remove them to fly the jsbsim backend"
            )
        self._rotor_max_speed_radps = config.vehicle.rotor_max_speed_radps
        self.plant = JsbsimF450Plant(plant_config)
        plant_mass_kg = self.plant.state().mass_kg
        if abs(config.mass_kg - plant_mass_kg) > MASS_TOLERANCE * plant_mass_kg:
            raise SimConfigError(
                f"vehicle.mass_kg = {config.mass_kg} does not describe JSBSim's F450 "
                f"({plant_mass_kg:.2f} kg); fly the jsbsim backend with preset f450 (or "
                "f450_jsbsim, whose [sim] backend is jsbsim)"
            )
        self.x = np.zeros(ph.N_STATE)
        self.aux = np.zeros(ph.N_AUX)
        self._u = np.zeros(4)
        self._write_state(self.plant.state())

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
        """Up to ``n_steps`` steps of control + JSBSim; stops right after a step in which ground
        contact changed. ``noise`` is unused (no gusts here). Returns the steps done."""
        contact0 = self.aux[ph.AUX_CONTACT]
        acc_ned_mps2 = self.aux[ph.AUX_ACC : ph.AUX_ACC + 3]
        with self.plant.messages_kept():
            for k in range(n_steps):
                control_step(self.x, acc_ned_mps2, sp, cs, cp, mix, dt_s, self._u)
                self.plant.set_motor_commands(np.sqrt(self._u))
                self.plant.step(dt_s)
                self._write_state(self.plant.state())
                if self.aux[ph.AUX_CONTACT] != contact0:
                    return k + 1
        return n_steps

    def _write_state(self, s: PlantState) -> None:
        x, aux = self.x, self.aux
        x[ph.POS : ph.POS + 3] = s.pos_ned_m
        x[ph.VEL : ph.VEL + 3] = s.vel_ned_mps
        x[ph.QUAT : ph.QUAT + 4] = s.q_wxyz
        x[ph.RATES : ph.RATES + 3] = s.rates_frd_radps
        x[ph.MOTORS : ph.MOTORS + 4] = np.clip(
            s.rotor_speeds_radps / self._rotor_max_speed_radps, 0.0, 1.0
        )
        aux[ph.AUX_ACC : ph.AUX_ACC + 3] = s.acc_ned_mps2
        aux[ph.AUX_CONTACT] = 1.0 if s.on_ground else 0.0
        aux[ph.AUX_THRUST_NOM] = s.thrust_n
        aux[ph.AUX_THRUST_TRUE] = s.thrust_n
        aux[ph.AUX_CMD : ph.AUX_CMD + 4] = self._u
