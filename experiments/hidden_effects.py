"""Hidden-effect flights for the diagnosis' tests and its detection bench: draw an effect's
parameters, fly the excitation mission with it on, write the log under a neutral name, and score
a fitted parameter against the truth. The truth stays with the caller, never in the log."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from diagnosis.excitation import ExcitationSchedule, load_schedule
from diagnosis.fly_schedule import fly_schedule
from flightlog.schema import FlightLog, read_flight_log, write_flight_log
from vehicle_sim import load_sim_config
from vehicle_sim.effects import EFFECT_CLASSES
from vehicle_sim.effects.base import effect_as_mapping

MISSION = Path(__file__).resolve().parents[1] / "missions" / "excite_full.toml"


def schedule(ground_staircase: bool = True) -> ExcitationSchedule:
    """The excitation mission; with ``ground_staircase`` False without the ground-effect
    staircase that closes it (the altitude holds after its last hover), so the rows before are
    flown and logged as they are with it."""
    full = load_schedule(MISSION)
    if ground_staircase:
        return full
    last_hover = max(i for i, s in enumerate(full.segments) if s.kind == "hover")
    return replace(full, segments=full.segments[: last_hover + 1])


def draw(name: str, rng: np.random.Generator) -> tuple[dict, dict]:
    """(truth effects, effects of the config given to the diagnosis) for hidden effect ``name``,
    parameters drawn from the effect's typical ranges (``Effect.draw_typical``). An effect that
    acts only through drag comes with the drag it is fitted with (at its defaults) in both."""
    cls = EFFECT_CLASSES[name]
    base = {}
    if cls.ACTS_THROUGH:
        through = cls.FIT_WITH or cls.ACTS_THROUGH[0]
        base = {through: effect_as_mapping(EFFECT_CLASSES[through]())}
    return {**base, name: cls.draw_typical(rng)}, base


def fly_hidden(truth: dict, tmp_path: Path, seed: int) -> list[FlightLog]:
    """Fly the excitation mission with ``truth`` on; the log as the diagnosis would read it."""
    log = fly_schedule(load_sim_config("iris", truth), schedule(), seed=seed)
    path = write_flight_log(tmp_path / "flight_0.csv", log)
    return [read_flight_log(path)]


HIDDEN_EFFECTS = (
    "rotor_drag", "body_drag", "wind", "payload", "battery_sag", "ground_effect", "motor_lag",
    "command_delay", "isotropic_drag", "thrust_curve",
)  # fmt: skip


def main_parameter_errors(name: str, truth: dict, params: dict) -> dict[str, float]:
    """Relative error of the main parameter(s) of ``name``: estimate vs truth."""
    p = truth[name]
    if name == "isotropic_drag":
        return {"k": abs(params["k_n_per_mps2"] / p["k_n_per_mps2"] - 1.0)}
    if name in ("rotor_drag", "body_drag"):
        key = "k_n_per_mps" if name == "rotor_drag" else "c_n_per_mps2"
        return {
            f"{key}_{a}": abs(params[f"{key}_{a}"] / p[key][i] - 1.0) for i, a in enumerate("xy")
        }
    if name == "wind":
        est = np.array([params["vel_ned_mps_n"], params["vel_ned_mps_e"]])
        true = np.array(p["vel_ned_mps"][:2])
        return {"vel_ned_mps": float(np.linalg.norm(est - true) / np.linalg.norm(true))}
    if name == "payload":
        return {"mass_ratio - 1": abs((params["mass_ratio"] - 1.0) / (p["mass_ratio"] - 1.0) - 1.0)}
    if name == "battery_sag":
        return {k: abs(params[k] / p[k] - 1.0) for k in ("max_thrust_loss", "full_flight_time_s")}
    if name == "ground_effect":
        return {"max_gain": abs(params["max_gain"] / p["max_gain"] - 1.0)}
    if name == "thrust_curve":
        return {"gain": abs(params["gain"] / p["gain"] - 1.0)}
    key = "tau_s" if name == "motor_lag" else "delay_s"
    return {key: abs(params[key] / p[key] - 1.0)}
