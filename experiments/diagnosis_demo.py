"""The diagnosis half of `make demo`: what does the plain preset get wrong about the demo vehicle?

Flies the excitation mission (missions/excite_full.toml) on the demo vehicle (the study preset
``iris_study``: rotor and body drag, wind, gusts, motor lag, command delay), puts realistic
sensor noise on what is logged (:mod:`vehicle_sim.sensor_noise`, seeded), diagnoses that log
against the plain ``iris`` preset and writes the report (report.json, report.md with plots,
extended_config.toml) into ``out_dir``. The flight is in-process (the simulator the MAVLink
endpoint runs, stepped directly), which keeps the demo's time for the learning loop.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from diagnosis.diagnosis import diagnose
from diagnosis.excitation import load_schedule
from diagnosis.extend_config import write_extended_config
from diagnosis.fly_schedule import fly_schedule
from diagnosis.report import write_report
from flightlog.schema import write_flight_log
from vehicle_sim import load_sim_config
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise

MISSION = Path(__file__).resolve().parents[1] / "missions" / "excite_full.toml"
DEMO_VEHICLE = "iris_study"
PLAIN_PRESET = "iris"


@dataclass(frozen=True)
class DiagnosisDemoResult:
    """What the demo prints: ``verdict`` (cause names), ``params`` (cause -> fitted
    parameters), replay and closed-loop gains, the noise floor [m/s] and the report file."""

    verdict: tuple[str, ...]
    params: dict[str, dict[str, float]]
    replay_gain: float
    closed_loop_gain: float
    noise_floor_mps: float
    report_md: Path

    def summary(self) -> str:
        """A few lines for the terminal."""
        lines = [f"diagnosis of the plain preset: verdict {', '.join(self.verdict) or 'none'}"]
        for name, params in self.params.items():
            values = ", ".join(f"{k} = {v:.3g}" for k, v in params.items())
            lines.append(f"  {name}: {values}")
        lines.append(
            f"  held-out replay gain {self.replay_gain:.2f}x, closed-loop gain "
            f"{self.closed_loop_gain:.2f}x (noise floor {self.noise_floor_mps:.3f} m/s)"
        )
        lines.append(f"  report: {self.report_md}")
        return "\n".join(lines)


def run_diagnosis_demo(
    out_dir: Path, seed: int = 0, progress: Callable[[str], None] = lambda msg: None
) -> DiagnosisDemoResult:
    """Fly, add sensor noise, diagnose against the plain preset, write the report to ``out_dir``."""
    progress(f"diagnosis: flying {MISSION.name} on {DEMO_VEHICLE} (in-process)")
    log = fly_schedule(load_sim_config(DEMO_VEHICLE), load_schedule(MISSION), seed=seed)
    noise = draw_sensor_noise(np.random.default_rng(seed))
    log = add_sensor_noise(log, noise, seed)
    out_dir.mkdir(parents=True, exist_ok=True)
    log_path = write_flight_log(out_dir / "excite_noisy.csv", log)
    progress(f"diagnosis: diagnosing the noisy log against {PLAIN_PRESET}")
    result = diagnose([log], load_sim_config(PLAIN_PRESET))
    extended = write_extended_config(
        PLAIN_PRESET, result.added_effects, out_dir / "extended_config.toml"
    )
    files = write_report(result, out_dir, [log_path.name], PLAIN_PRESET, extended)
    named = set(result.verdict)
    params = {c.name: dict(c.params) for c in result.causes if c.name in named}
    cl = result.closed_loop
    return DiagnosisDemoResult(
        verdict=result.verdict,
        params=params,
        replay_gain=result.gain,
        closed_loop_gain=cl.gain() if result.added_effects else 1.0,
        noise_floor_mps=float(result.noise_floor["replay_rmse_mps"]),
        report_md=files[1],
    )
