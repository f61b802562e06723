"""Benchmark of the diagnosis: wall time of the whole `diagnose` on a 5-minute flight log.

The log is the excitation mission (missions/excite_full.toml) flown back to back until it
lasts 5 minutes (quick: its first segments up to 20 s, a 21 s log, the shortest on which the
diagnosis still names all three, exact and noisy) by a simulated Iris with three effects its
config does not know (rotor drag, a payload, a command delay). Timed, as the
`diagnose` command does it: reading the log, the diagnosis, the extended config and the
report with its plots. The baseline measured in the same run is the wall time of simulating
that flight in-process.
On a shared machine the wall time says more about the load than about the code, so the
process' CPU time of the diagnosis is measured too, on that log and on the same log with
realistic sensor noise (IMU 0.3 m/s^2, the other levels drawn as the detection bench does).

    python -m experiments.bench.diagnose [--quick]

runs the timing part alone (``bench --only diagnose`` adds the detection figures).
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from diagnosis.diagnosis import diagnose
from diagnosis.excitation import ExcitationSchedule, load_schedule
from diagnosis.extend_config import write_extended_config
from diagnosis.fly_schedule import fly_schedule
from diagnosis.report import write_report
from experiments.bench import diagnose_detection
from flightlog.schema import read_flight_log, write_flight_log
from vehicle_sim import load_sim_config
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise

MISSION = Path(__file__).resolve().parents[2] / "missions" / "excite_full.toml"
PRESET = "iris"
HIDDEN_EFFECTS = {
    "rotor_drag": {"k_n_per_mps": [0.4, 0.35, 0.1]},
    "payload": {"mass_ratio": 1.25},
    "command_delay": {"delay_s": 0.12},
}
LOG_S = 300.0
QUICK_LOG_S = 20.0
NOISY_ACC_MPS2 = 0.3  # IMU noise of the noisy copy of the log (issue 18's ordinary IMU)
NOISE_SEED = 0


def bench_schedule(log_s: float) -> ExcitationSchedule:
    """The excitation mission repeated until it lasts at least ``log_s`` [s], then cut there."""
    one = load_schedule(MISSION)
    repeated = one.segments * math.ceil(log_s / one.duration_s)
    segments, total_s = [], 0.0
    for s in repeated:
        if total_s >= log_s:
            break
        segments.append(s)
        total_s += s.duration_s
    return ExcitationSchedule(f"{one.name}_{log_s:.0f}s", one.takeoff_alt_m, tuple(segments))


def run(
    progress: Callable[[str], None] = print, quick: bool = False, detection: bool = True
) -> dict[str, float]:
    """Measure ``diagnose_5min_s`` (wall s of the whole diagnosis; quick: of a 21 s log),
    ``diagnose_5min_cpu_s`` (process CPU s of the diagnosis alone),
    ``diagnose_5min_noisy_cpu_s`` (the same on the log with sensor noise),
    ``diagnose_log_s`` (the log's duration [s]), ``diagnose_speedup_vs_realtime`` (log duration
    / diagnosis wall time), ``diagnose_log_sim_s`` (wall s to simulate the flight itself, the
    same-run baseline) and ``diagnose_vs_log_sim_ratio`` (diagnosis / simulation wall time);
    with ``detection`` (and not quick) also the detection figures by noise level."""
    schedule = bench_schedule(QUICK_LOG_S if quick else LOG_S)
    progress(f"diagnose: flying {schedule.duration_s:.0f} s with {', '.join(HIDDEN_EFFECTS)}")
    fly_schedule(load_sim_config(PRESET, HIDDEN_EFFECTS), bench_schedule(5.0), seed=1)  # warm up
    t0 = time.perf_counter()
    log = fly_schedule(load_sim_config(PRESET, HIDDEN_EFFECTS), schedule, seed=0)
    sim_s = time.perf_counter() - t0
    log_s = float(log["t_s"][-1] - log["t_s"][0])
    with tempfile.TemporaryDirectory() as tmp:
        out_dir = Path(tmp)
        log_path = write_flight_log(out_dir / "flight_0.csv", log)
        progress(f"diagnose: {log_s:.0f} s log written; diagnosing")
        t0 = time.perf_counter()
        cpu0 = time.process_time()
        result = diagnose(
            [read_flight_log(log_path)],
            load_sim_config(PRESET),
            progress=lambda msg: progress(f"diagnose: {msg}"),
        )
        cpu_s = time.process_time() - cpu0
        extended = write_extended_config(PRESET, result.added_effects, out_dir / "ext.toml")
        write_report(result, out_dir, [log_path.name], PRESET, extended)
        wall_s = time.perf_counter() - t0
    progress(f"diagnose: verdict {', '.join(result.verdict) or 'none'} in {wall_s:.1f} s")
    noise = draw_sensor_noise(np.random.default_rng(NOISE_SEED), acc_mps2=NOISY_ACC_MPS2)
    noisy_log = add_sensor_noise(log, noise, NOISE_SEED)
    cpu0 = time.process_time()
    noisy = diagnose([noisy_log], load_sim_config(PRESET))
    noisy_cpu_s = time.process_time() - cpu0
    progress(
        f"diagnose: noisy log: verdict {', '.join(noisy.verdict) or 'none'} in "
        f"{noisy_cpu_s:.1f} CPU s (exact log {cpu_s:.1f} CPU s)"
    )
    return {
        "diagnose_5min_s": wall_s,
        "diagnose_5min_cpu_s": cpu_s,
        "diagnose_5min_noisy_cpu_s": noisy_cpu_s,
        "diagnose_log_s": log_s,
        "diagnose_speedup_vs_realtime": log_s / wall_s,
        "diagnose_log_sim_s": sim_s,
        "diagnose_vs_log_sim_ratio": wall_s / sim_s,
        **(_detection(progress, quick) if detection else {}),
    }


def _detection(progress: Callable[[str], None], quick: bool) -> dict[str, float]:
    """Detection / false-positive figures by noise level (quick: none, they need many flights)."""
    if quick:
        return {}
    figures = diagnose_detection.run(progress)
    progress("diagnose: detection by noise level\n" + diagnose_detection.markdown_table(figures))
    return figures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 21 s log instead of 5 minutes")
    args = parser.parse_args(argv)
    print(json.dumps(run(quick=args.quick, detection=False), indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
