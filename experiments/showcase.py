"""`make showcase`: fly the square mission with two planners, in calm air and in wind, and plot.

The companion flies ``missions/square.toml`` (a 10 m square at 2 m/s, twice around) over the
in-process link (lockstep, deterministic), once with [Kulathunga23]'s PD regulator and once with the
NMPC (CasADi, kinematic model, reference feed-forward); each on the nominal iris and on an
iris in a 4 m/s wind acting through rotor drag, an effect neither planner's model knows.
The table and ``out/showcase/square.png`` show what the planner buys and what the wind costs.
(The learning loop over MAVLink, the project's main job, is ``make demo``.)
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import tomli_w

from companion.app import CompanionConfig, run_companion
from flightlog.atomic_output import write_figure_atomic
from flightlog.reader import read_log
from flightlog.schema import FlightLog
from vehicle_sim.config import PRESET_DIR

MISSION = Path(__file__).resolve().parent.parent / "missions" / "square.toml"
PLANNERS = ("pd", "nmpc")
WINDY_EFFECTS = {
    "wind": {"vel_ned_mps": [0.0, 4.0, 0.0]},
    "rotor_drag": {"k_n_per_mps": [0.35, 0.35, 0.1]},
}


@dataclass(frozen=True)
class DemoConfig:
    """Where the demo writes (``out_dir``) and the simulator seed."""

    out_dir: Path = Path("out/showcase")
    seed: int = 0


def tracking_errors_m(log: FlightLog) -> np.ndarray:
    """Distance [m] from the reference at each row where the planner was following, (n,)."""
    following = log["planner_ok"] > 0.5
    pos = log.stack("pos_n_m", "pos_e_m", "pos_d_m")[following]
    ref = log.stack("ref_pos_n_m", "ref_pos_e_m", "ref_pos_d_m")[following]
    return np.linalg.norm(pos - ref, axis=1)


def write_windy_config(out_dir: Path) -> Path:
    """The iris preset plus wind and rotor drag, as a config file the user can inspect."""
    text = (PRESET_DIR / "iris.toml").read_text()
    path = out_dir / "iris_windy.toml"
    path.write_text(text + "\n" + tomli_w.dumps({"effects": WINDY_EFFECTS}))
    return path


def plot(logs: dict[str, FlightLog], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_path, ax_err) = plt.subplots(1, 2, figsize=(12, 5))
    first = next(iter(logs.values()))
    ok = first["planner_ok"] > 0.5
    ax_path.plot(first["ref_pos_e_m"][ok], first["ref_pos_n_m"][ok], "k--", lw=1, label="reference")
    for name, log in logs.items():
        ax_path.plot(log["pos_e_m"], log["pos_n_m"], label=name)
        following = log["planner_ok"] > 0.5
        ax_err.plot(log["t_s"][following], tracking_errors_m(log), label=name)
    ax_path.set(xlabel="east [m]", ylabel="north [m]", title="flown path (top view)")
    ax_path.set_aspect("equal")
    ax_err.set(
        xlabel="time [s]",
        ylabel="distance to the reference's point at that time [m]",
        title="tracking error (lagging along the path counts)",
    )
    for ax in (ax_path, ax_err):
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.tight_layout()
    write_figure_atomic(fig, path, dpi=120)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="showcase", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=DemoConfig.out_dir, help="output folder")
    parser.add_argument("--seed", type=int, default=DemoConfig.seed, help="simulator seed")
    args = parser.parse_args(argv)
    config = DemoConfig(out_dir=args.out, seed=args.seed)
    config.out_dir.mkdir(parents=True, exist_ok=True)

    def progress(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    vehicles = {"calm": "iris", "wind": str(write_windy_config(config.out_dir))}
    logs: dict[str, FlightLog] = {}
    for planner in PLANNERS:
        for air, vehicle in vehicles.items():
            name = f"{planner}, {air}"
            progress(f"== flying the square: {name}")
            result = run_companion(
                CompanionConfig(
                    mission_path=MISSION,
                    link="inprocess",
                    planner=planner,
                    log_path=config.out_dir / f"square_{planner}_{air}.csv",
                    replace_log=True,
                    seed=config.seed,
                    vehicle=vehicle,
                ),
                progress,
            )
            if result.log_path is None or result.outcome.status != "completed":
                print(f"demo: the {name} flight did not complete: {result.outcome.detail}")
                return 1
            logs[name] = read_log(result.log_path)
    figure = config.out_dir / "square.png"
    plot(logs, figure)
    print("| flight | tracking RMSE [m] | max error [m] |")
    print("|---|---|---|")
    for name, log in logs.items():
        err = tracking_errors_m(log)
        print(f"| {name} | {np.sqrt(np.mean(err**2)):.3f} | {err.max():.3f} |")
    print(f"\nplot: {figure}\nlogs and the windy vehicle config: {config.out_dir}/")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
