"""`make demo`: the learning loop end to end over MAVLink.

Starts `vehicle-sim` (the study vehicle, vehicle_sim/presets/iris_study.toml) as a MAVLink
endpoint on loopback, flies missions/demo_bspline.toml with the nominal NMPC over MAVSDK, fits
the residual GP from that flight's log, flies the mission again with the augmented NMPC, prints
the comparison and writes out/demo/report.md with plots. Then the diagnosis: a third endpoint
with the same vehicle, the demo's excitation mission flown over MAVLink, the vehicle's onboard
log with realistic sensor noise diagnosed against the plain iris preset; the verdict is printed
below the learning result (experiments/diagnosis_demo.py; report with plots in
out/demo/diagnosis). Every process it starts is stopped, also on errors and Ctrl-C. Exit code 0
on success, 1 if a flight failed, 130 on Ctrl-C.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from companion.app import CompanionInputError
from experiments.diagnosis_demo import run_diagnosis_demo
from experiments.sim_endpoint import EndpointError
from experiments.study.mavlink_demo import DemoConfig, DemoError, comparison_table, run_demo

MISSION = Path(__file__).resolve().parent.parent / "missions" / "demo_bspline.toml"


def parse_args(argv: Sequence[str] | None) -> DemoConfig:
    parser = argparse.ArgumentParser(prog="demo", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DemoConfig.out_dir, help="output folder")
    parser.add_argument("--mission", type=Path, default=MISSION, help="mission file")
    parser.add_argument("--seed", type=int, default=DemoConfig.seed, help="simulator seed")
    args = parser.parse_args(argv)
    return DemoConfig(mission_path=args.mission, out_dir=args.out, seed=args.seed)


def main(argv: Sequence[str] | None = None) -> int:
    config = parse_args(argv)
    start = time.monotonic()

    def progress(message: str) -> None:
        print(f"demo [{time.monotonic() - start:6.1f} s] {message}", file=sys.stderr, flush=True)

    try:
        figures = run_demo(config, progress)
        print(comparison_table(figures))
        nominal, augmented = figures
        print(
            f"\nresidual RMSE {nominal.residual_rmse_mps / augmented.residual_rmse_mps:.2f}x "
            f"lower, tracking RMSE {nominal.tracking_rmse_m / augmented.tracking_rmse_m:.2f}x "
            f"lower augmented; {time.monotonic() - start:.0f} s in all"
        )
        print(f"report: {config.out_dir / 'report.md'}\n", flush=True)
        diagnosis = run_diagnosis_demo(config.out_dir / "diagnosis", config.seed, progress)
    except KeyboardInterrupt:
        print("demo: interrupted; the simulator was stopped", file=sys.stderr)
        return 130
    except (CompanionInputError, DemoError, EndpointError) as exc:
        print(f"demo: error: {exc}", file=sys.stderr)
        return 1
    print(diagnosis.summary())
    print(f"demo: {time.monotonic() - start:.0f} s in all (learning and diagnosis)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
