"""The diagnosis half of `make demo`: what does the plain preset get wrong about the demo vehicle?

Starts a `vehicle-sim` MAVLink endpoint with the demo vehicle (the study preset ``iris_study``:
rotor and body drag, wind, gusts, motor lag, command delay) and flies the demo's excitation
mission (missions/excite_demo.toml, 46 s: excite_full.toml without the ground holds and the
long hover, which excite effects the demo vehicle does not have) over MAVLink (pymavlink) in real
time, as a companion would. The log diagnosed is the vehicle's own onboard log (`vehicle-sim
--log`, as PX4 writes one to its SD card: MAVLink carries no acceleration or thrust), with
realistic sensor noise put on what it measured (:mod:`vehicle_sim.sensor_noise`, seeded). It is
diagnosed against the plain ``iris`` preset and the report (report.json, report.md with plots,
extended_config.toml) is written into ``out_dir``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from companion.link import LinkError
from companion.pymavlink_link import PymavlinkLink
from diagnosis.diagnosis import diagnose
from diagnosis.excitation import load_schedule
from diagnosis.extend_config import write_extended_config
from diagnosis.report import write_report
from experiments.mavlink_excitation import fly_schedule_over_link
from experiments.sim_endpoint import EndpointError, SimEndpoint
from flightlog.schema import FlightLogError, read_flight_log, sidecar_path, write_flight_log
from vehicle_sim import load_sim_config
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise

MISSION = Path(__file__).resolve().parents[1] / "missions" / "excite_demo.toml"
DEMO_VEHICLE = "iris_study"
PLAIN_PRESET = "iris"
CONNECT_TIMEOUT_S = 120.0  # a fresh endpoint on a busy computer may need most of a minute


@dataclass(frozen=True)
class DiagnosisDemoResult:
    """What the demo prints: ``verdict`` (cause names), ``params`` (cause -> fitted
    parameters), replay and closed-loop gains, the noise floor [m/s], the report file and the
    OFFBOARD time of the onboard log [s]."""

    verdict: tuple[str, ...]
    params: dict[str, dict[str, float]]
    replay_gain: float
    closed_loop_gain: float
    noise_floor_mps: float
    report_md: Path
    flight_s: float

    def summary(self) -> str:
        """A few lines for the terminal."""
        lines = [
            f"diagnosis of the plain preset ({MISSION.name} flown over MAVLink, "
            f"{self.flight_s:.0f} s of onboard log with sensor noise): verdict "
            f"{', '.join(self.verdict) or 'none'}"
        ]
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
    """Fly over MAVLink, add sensor noise to the onboard log, diagnose it against the plain
    preset, write the report to ``out_dir``.

    Raises:
        EndpointError: the endpoint did not start, or the flight or its log failed (one line).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    onboard = out_dir / "onboard.csv"
    for earlier in (onboard, sidecar_path(onboard)):  # the demo writes its folder anew
        earlier.unlink(missing_ok=True)
    progress(f"diagnosis: starting vehicle-sim ({DEMO_VEHICLE}) with its onboard log")
    with SimEndpoint(DEMO_VEHICLE, seed, out_dir / "vehicle_sim.log", onboard) as sim:
        link = PymavlinkLink(sim.mavsdk_url)
        try:
            link.connect(CONNECT_TIMEOUT_S)
            progress(f"diagnosis: flying {MISSION.name} over MAVLink")
            fly_schedule_over_link(link, load_schedule(MISSION), progress=progress)
        except LinkError as exc:
            raise EndpointError(f"the diagnosis flight failed: {exc}") from None
        finally:
            link.close()
    try:
        log = read_flight_log(onboard)
    except (FlightLogError, OSError) as exc:
        raise EndpointError(f"the onboard log cannot be read: {exc}") from None
    noise = draw_sensor_noise(np.random.default_rng(seed))
    log = add_sensor_noise(log, noise, seed)
    log_path = write_flight_log(out_dir / "onboard_noisy.csv", log)
    offboard = log["mode"] == "OFFBOARD"
    flight_s = float(np.ptp(log["t_s"][offboard])) if offboard.any() else 0.0
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
        flight_s=flight_s,
    )
