"""PNG plots of residuals against velocity with the model and its inducing points (Fig. 5).

One figure per axis: measured residual y vs measured velocity (grey), the model's mean at the
same points (blue), and the inducing points (red triangles, at the model mean) where the
feature vector holds that velocity component.
"""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure

from flightlog.atomic_output import write_figure_atomic
from gp.datasets import ResidualDataset
from gp.model_io import ResidualModel

_AXES = ("n", "e", "d")


def plot_residuals(model: ResidualModel, data: ResidualDataset, prefix: Path) -> list[Path]:
    """Write ``<prefix>_residual_<axis>.png`` for each axis; returns the paths."""
    mean, _ = model.predict(data.X)
    inputs = model.features.inputs
    paths = []
    for j, axis in enumerate(_AXES[: len(model.features.outputs)]):
        fig = Figure(figsize=(6.4, 4.0))  # no pyplot: no global backend state
        ax = fig.add_subplot()
        ax.plot(data.vel_ned_mps[:, j], data.Y[:, j], ".", ms=2, color="0.6", label="measured")
        ax.plot(data.vel_ned_mps[:, j], mean[:, j], ".", ms=2, color="tab:blue", label="GP mean")
        col = [i for i, (c, lag) in enumerate(inputs) if c == f"vel_{axis}_mps" and lag == 0]
        if col:
            Z = model.posterior.support[j]
            z_mean, _ = model.predict(Z)
            ax.plot(Z[:, col[0]], z_mean[:, j], "^", color="tab:red", label="inducing points")
        ax.set_xlabel(f"vel_{axis} [m/s]")
        ax.set_ylabel(f"residual {axis} [m/s^2]")
        ax.set_title(f"{model.features.name}: residual vs velocity ({axis})")
        ax.legend(loc="best", fontsize="small")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        path = prefix.with_name(f"{prefix.name}_residual_{axis}.png")
        paths.append(write_figure_atomic(fig, path, dpi=100))
    return paths
