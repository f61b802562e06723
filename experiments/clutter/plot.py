"""The forest with every flown path (PNG), written atomically."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from experiments.clutter.table3 import Table3Result  # noqa: E402
from flightlog.atomic_output import write_figure_atomic  # noqa: E402
from planners.obstacles import Cylinder  # noqa: E402

_COLOUR = {
    "proposed": "tab:green",
    "nominal": "tab:purple",
    "gp_no_regeneration": "tab:cyan",
    "no_regeneration": "tab:blue",
    "rrtstar_online": "tab:orange",
    "rrtstar": "tab:brown",
    "pd": "tab:red",
}


def legend_labels(learned_flown: bool, gp_flown: bool) -> dict[str, str]:
    """Each planner's legend entry, naming what the learned rows flew: the NMPC with the GP,
    the identified lag alone (its GP did not beat the lag), or the kinematic model (the model
    failed its own check)."""
    learned = "GP" if gp_flown else "identified lag" if learned_flown else "kinematic model"
    return {
        "proposed": f"proposed (NMPC+{learned}+replanner+regeneration)",
        "nominal": "proposed without a learned model (PX4's default lag)",
        "gp_no_regeneration": f"proposed without regeneration (NMPC+{learned})",
        "no_regeneration": "NMPC replanner, no regeneration",
        "rrtstar_online": f"RRT* (OMPL) re-planned in the sensed map + NMPC+{learned}",
        "rrtstar": f"RRT* (OMPL) in the known forest + NMPC+{learned}",
        "pd": "PD on the initial reference",
    }


def plot_forest(result: Table3Result, path: Path) -> Path:
    """Trunks, starts, goals and every flight's path (x east, y north) to ``path``."""
    fig, ax = plt.subplots(figsize=(8, 8))
    for o in result.scenario.world.obstacles:
        if isinstance(o, Cylinder):
            ax.add_patch(plt.Circle((o.center_ne_m[1], o.center_ne_m[0]), o.radius_m, color="0.3"))
    labels = legend_labels(result.learned_flown, result.gp_flown)
    for kind, flights in result.flights.items():
        colour, label = _COLOUR.get(kind, "k"), labels.get(kind, kind)
        for i, f in enumerate(flights):
            ax.plot(f.path_ne_m[:, 1], f.path_ne_m[:, 0], color=colour, lw=1.0,
                    label=label if i == 0 else None, alpha=0.8)  # fmt: skip
            if f.contacts:
                ax.plot(f.path_ne_m[-1, 1], f.path_ne_m[-1, 0], "x", color=colour, ms=8)
    s, g = result.scenario.starts_ne_m, result.scenario.goals_ne_m
    n = len(next(iter(result.flights.values()), []))
    ax.plot(s[:n, 1], s[:n, 0], "k^", label="starts")
    ax.plot(g[:n, 1], g[:n, 0], "k*", ms=10, label="goals")
    ax.set_aspect("equal")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_title("Forest (Table 3 of [Kulathunga23]); x = contact")
    ax.legend(loc="upper left", fontsize=8)
    return write_figure_atomic(fig, path, dpi=110, bbox_inches="tight")
