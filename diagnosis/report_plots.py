"""PNG plots of a diagnosis: measured vs simulated velocity (replay and closed-loop tracking), and
per cause the residual against the variable that explains it, before (config) and after
(extended config)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from diagnosis.diagnosis import Diagnosis  # noqa: E402
from diagnosis.force_model import predicted_residual  # noqa: E402
from diagnosis.forces import GRAVITY_MPS2, ForceData  # noqa: E402
from diagnosis.replay import ReplayResult  # noqa: E402

# cause -> (x label, x of the rows, y label, y of a residual (n, 3) for the rows)
Axis = Callable[[ForceData], np.ndarray]
Component = Callable[[ForceData, np.ndarray], np.ndarray]


def _body(data: ForceData, v: np.ndarray) -> np.ndarray:
    return np.einsum("nji,nj->ni", data.rot, v)


def _thrust_axis(data: ForceData, r: np.ndarray) -> np.ndarray:
    return -np.sum(data.thrust_axis_ned() * r, axis=1)


RESIDUAL_AXES: dict[str, tuple[str, Axis, str, Component]] = {
    "rotor_drag": (
        "body x velocity [m/s]", lambda d: _body(d, d.vel_ned_mps)[:, 0],
        "body x force residual [N]", lambda d, r: _body(d, r)[:, 0],
    ),
    "body_drag": (
        "body x velocity [m/s]", lambda d: _body(d, d.vel_ned_mps)[:, 0],
        "body x force residual [N]", lambda d, r: _body(d, r)[:, 0],
    ),
    "isotropic_drag": (
        "body x velocity [m/s]", lambda d: _body(d, d.vel_ned_mps)[:, 0],
        "body x force residual [N]", lambda d, r: _body(d, r)[:, 0],
    ),
    "wind": (
        "north velocity [m/s]", lambda d: d.vel_ned_mps[:, 0],
        "north force residual [N]", lambda d, r: r[:, 0],
    ),
    "payload": (
        "m_nom (a - g) along thrust axis [N]",
        lambda d: _thrust_axis(d, d.mass_kg * (d.acc_ned_mps2 - [0.0, 0.0, GRAVITY_MPS2])),
        "force residual along thrust axis, down [N]", _thrust_axis,
    ),
    "battery_sag": (
        "time [s]", lambda d: d.t_s,
        "force residual along thrust axis, down [N]", _thrust_axis,
    ),
    "ground_effect": (
        "altitude [m]", lambda d: d.alt_m,
        "force residual along thrust axis, down [N]", _thrust_axis,
    ),
    "unexplained": (
        "time [s]", lambda d: d.t_s,
        "north force residual [N]", lambda d, r: r[:, 0],
    ),
}  # fmt: skip
LOG_X = {"ground_effect"}  # causes whose explaining variable is best seen on a log axis


def plot_replay(d: Diagnosis, path: Path) -> Path:
    """Measured vs simulated (config and extended config) velocity on the held-out windows."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
    for k, (ax, name) in enumerate(zip(axes, ("north", "east", "down"), strict=True)):
        _lines(ax, d.baseline, d.baseline.meas_vel_ned_mps[:, k], "measured", "k", 1.5)
        _lines(ax, d.baseline, d.baseline.sim_vel_ned_mps[:, k], "simulated, config", "C3", 1.0)
        if d.added_effects:
            sim = d.extended.sim_vel_ned_mps[:, k]
            _lines(ax, d.extended, sim, "simulated, extended", "C0", 1.0)
        ax.set_ylabel(f"{name} vel [m/s]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title("Replay of the logged setpoints on held-out windows")
    axes[-1].set_xlabel("log time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def plot_closed_loop(d: Diagnosis, path: Path) -> Path:
    """Measured vs closed-loop velocity (config and extended config) on the held-out rows;
    segments a config was re-anchored in, which no figure counts, dotted and labelled so."""
    cl = d.closed_loop
    dt_s = np.diff(cl.t_s)
    row_dt_s = float(np.median(dt_s)) if len(dt_s) else 0.0
    gaps = np.flatnonzero((dt_s > 1.5 * row_dt_s) | (np.diff(cl.run) != 0)) + 1
    flown = [("config", cl.baseline_vel_ned_mps, "C3")]
    if d.added_effects:
        flown.append(("extended", cl.extended_vel_ned_mps, "C0"))
    fig, axes = plt.subplots(3, 1, figsize=(10, 7), sharex=True)
    for k, (ax, name) in enumerate(zip(axes, ("north", "east", "down"), strict=True)):
        ax.plot(*_broken(cl.t_s, cl.meas_vel_ned_mps[:, k], gaps), "k", lw=1.5, label="measured")
        for config, vel, color in flown:
            scored = np.where(cl.whole, vel[:, k], np.nan)
            ax.plot(*_broken(cl.t_s, scored, gaps), color, lw=1.0, label=f"closed loop, {config}")
            if not cl.whole.all():
                ax.plot(
                    *_broken(cl.t_s, np.where(cl.whole, np.nan, vel[:, k]), gaps),
                    color,
                    lw=1.0,
                    ls=":",
                    label=f"closed loop, {config}, re-anchored (not scored)",
                )
        ax.set_ylabel(f"{name} vel [m/s]")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title("Closed-loop tracking of the logged setpoints, held-out rows")
    axes[-1].set_xlabel("log time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def plot_residuals(d: Diagnosis, out_dir: Path) -> list[Path]:
    """One plot per named airframe cause (and ``unexplained``): the force residual against
    the variable that cause acts on, under the config and under the whole extended config
    (every added effect at once, not the plot's cause alone, which the report's table
    apportions)."""
    if d.force is None:
        return []
    data = d.force
    before = data.resid_ned_n - predicted_residual(d.base_effects, data, d.battery)
    after = data.resid_ned_n - predicted_residual(d.final_effects, data, d.battery)
    paths = []
    for name in d.verdict:
        if name not in RESIDUAL_AXES:
            continue
        xlabel, x_of, ylabel, y_of = RESIDUAL_AXES[name]
        fig, ax = plt.subplots(figsize=(7, 4.5))
        x = x_of(data)
        ax.plot(x, y_of(data, before), ".", ms=2, color="C3", label="config")
        added = ", ".join(d.added_effects) or "nothing added"
        ax.plot(x, y_of(data, after), ".", ms=2, color="C0", label=f"extended config ({added})")
        if name in LOG_X:
            ax.set_xscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(f"{name}: force residual, config and extended config (all added causes)")
        ax.legend(loc="best", fontsize=8)
        fig.tight_layout()
        path = out_dir / f"residual_{name}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def _lines(ax, result: ReplayResult, y: np.ndarray, label: str, color: str, lw: float) -> None:
    """Plot ``y`` against time with a break between windows."""
    breaks = np.flatnonzero(np.diff(result.window) != 0) + 1
    ax.plot(*_broken(result.t_s, np.asarray(y), breaks), color=color, lw=lw, label=label)


def _broken(t: np.ndarray, y: np.ndarray, breaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) with NaN inserted before the indices ``breaks``, so lines do not join there."""
    return np.insert(t.astype(float), breaks, np.nan), np.insert(y.astype(float), breaks, np.nan)
