"""Detection rate, parameter error and false positives of the diagnosis by IMU noise level.

For each hidden effect of the vocabulary and each trial, a simulated Iris flies the excitation
mission (missions/excite_full.toml) with the effect on (parameters drawn at random, seeded);
the log gets realistic sensor noise (:func:`vehicle_sim.sensor_noise.draw_sensor_noise`, the
IMU level fixed per column: 0, 0.1, 0.3, 0.5 m/s^2; at 0 no noise at all) and is diagnosed
against the plain preset. "Named" means the effect is the first cause of the verdict; the
parameter error is the largest relative error of its main parameter(s). False positives: clean
flights (no effect) with noise drawn per seed; any named cause counts.

    python -m experiments.bench.diagnose_detection [--levels 0.3 ...] [--part hidden|clean]
        [--effects rotor_drag ...] [--clean-seeds 0 10]

runs one part at chosen levels (``bench --only diagnose`` runs all of them) and prints the
figures and the table; the parts (and subsets of the effects or of the clean seeds) can run in
parallel, the same flights as one run.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from diagnosis.diagnosis import diagnose
from experiments.hidden_effects import HIDDEN_EFFECTS, draw, fly_hidden, main_parameter_errors
from vehicle_sim import load_sim_config
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise

NOISE_LEVELS_MPS2 = (0.0, 0.1, 0.3, 0.5)


def _noisy(logs, level: float, seed: int):
    if level <= 0.0:
        return logs
    noise = draw_sensor_noise(np.random.default_rng(seed), acc_mps2=level)
    return [add_sensor_noise(log, noise, seed) for log in logs]


def run(
    progress: Callable[[str], None] = print,
    trials: int = 2,
    clean_seeds: range = range(20),
    levels: tuple[float, ...] = NOISE_LEVELS_MPS2,
    hidden: bool = True,
    clean: bool = True,
    effects: tuple[str, ...] = HIDDEN_EFFECTS,
) -> dict[str, float]:
    """Figures ``diagnose_named_rate_acc<level>``, ``diagnose_max_param_err_acc<level>``,
    ``diagnose_median_param_err_acc<level>`` and ``diagnose_false_positive_rate_acc<level>``
    (``hidden``: the hidden-effect flights of ``effects``, ``clean``: the false-positive flights
    with noise seeds ``clean_seeds``; at level 0 one clean flight)."""
    named = {lv: [] for lv in levels}
    errors = {lv: [] for lv in levels}
    false_pos = {lv: [] for lv in levels}
    with tempfile.TemporaryDirectory() as tmp:
        for name in effects if hidden else ():
            for trial in range(trials):
                seed = 1000 + 17 * HIDDEN_EFFECTS.index(name) + trial
                truth, base = draw(name, np.random.default_rng(seed))
                logs = fly_hidden(truth, Path(tmp), seed)
                for lv in levels:
                    d = diagnose(_noisy(logs, lv, seed), load_sim_config("iris", base))
                    ok = bool(d.verdict) and d.verdict[0] == name
                    named[lv].append(ok)
                    err = "-"
                    if ok:
                        errs = main_parameter_errors(name, truth, d.causes[0].params)
                        errors[lv].append(max(errs.values()))
                        err = f"{100 * errors[lv][-1]:.1f} %"
                    progress(f"detection: {name} trial {trial} acc {lv}: {d.verdict}, error {err}")
        clean_logs = fly_hidden({}, Path(tmp), 77) if clean else []
        for lv in levels if clean else ():
            for s in clean_seeds if lv > 0.0 else clean_seeds[:1]:
                d = diagnose(_noisy(clean_logs, lv, 5000 + s), load_sim_config("iris"))
                false_pos[lv].append(bool(d.verdict))
                progress(f"detection: clean seed {s} acc {lv}: {d.verdict}")
    out: dict[str, float] = {}
    for lv in levels:
        if hidden:
            out[f"diagnose_named_rate_acc{lv}"] = float(np.mean(named[lv]))
            errs = errors[lv] or [float("nan")]
            out[f"diagnose_max_param_err_acc{lv}"] = float(np.max(errs))
            out[f"diagnose_median_param_err_acc{lv}"] = float(np.median(errs))
        if clean:
            out[f"diagnose_false_positive_rate_acc{lv}"] = float(np.mean(false_pos[lv]))
    return out


def markdown_table(figures: dict[str, float], levels=NOISE_LEVELS_MPS2) -> str:
    """The BENCHMARKS.md table of :func:`run`'s figures."""
    rows = [
        "| IMU noise [m/s^2] | named | median param err | max param err | false positives |",
        "|---|---|---|---|---|",
    ]
    for lv in levels:
        f = {
            k: figures.get(f"diagnose_{k}_acc{lv}", float("nan"))
            for k in ("named_rate", "median_param_err", "max_param_err", "false_positive_rate")
        }
        rows.append(
            f"| {lv} | {100 * f['named_rate']:.0f} % | {100 * f['median_param_err']:.1f} % | "
            f"{100 * f['max_param_err']:.1f} % | {100 * f['false_positive_rate']:.0f} % |"
        )
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=float, nargs="+", default=list(NOISE_LEVELS_MPS2))
    parser.add_argument("--part", choices=("all", "hidden", "clean"), default="all")
    parser.add_argument("--effects", nargs="+", choices=HIDDEN_EFFECTS, default=HIDDEN_EFFECTS)
    parser.add_argument("--clean-seeds", type=int, nargs=2, default=(0, 20), metavar=("FROM", "TO"))
    args = parser.parse_args(argv)
    levels = tuple(args.levels)
    figures = run(
        levels=levels,
        hidden=args.part != "clean",
        clean=args.part != "hidden",
        effects=tuple(args.effects),
        clean_seeds=range(*args.clean_seeds),
    )
    print(json.dumps(figures, indent=2))
    print(markdown_table(figures, levels))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
