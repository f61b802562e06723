"""Write the diagnosis out: report.json (schema diagnosis/2), report.md with plots, extended config.

The JSON keeps every key of diagnosis/1 (docs/design.md section 8) and adds: ``closed_loop``
(held-out closed-loop tracking velocity RMSE of the config and of the extended config, and their
ratio), ``noise_floor`` (the log's own noise), ``explained_of_explainable``, ``not_examined``,
``at_bound``, ``warnings`` and per cause ``statistic`` (its significance test), ``at_bound`` and
``unpinned`` (parameters the log does not pin, with their 95 % interval).
Causes that the data cannot identify appear in the ranking with confidence 0 and say in their
evidence what flight would make them so.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from diagnosis.cause import Cause
from diagnosis.closed_loop import NEAR_GROUND_ALT_M
from diagnosis.diagnosis import Diagnosis
from diagnosis.report_plots import plot_closed_loop, plot_replay, plot_residuals

SCHEMA = "diagnosis/2"
EXPLAINED_LEGEND = (
    "*explained*: the share of the held-out error above the noise floor (the force residual's "
    "for a force cause, the replay's for a command-path cause) that the cause removes, fitted "
    "on top of the causes named before it (0 % when it removes none); *confidence*: the share "
    "of the error then left that it removes (for `unexplained`: the share of the config's "
    "held-out error left). A cause is named only when that removal is large, significant (p) "
    "and its fit is not on its search bound."
)


def report_document(diagnosis: Diagnosis) -> dict[str, Any]:
    """The report.json content (schema diagnosis/2)."""
    cl = diagnosis.closed_loop
    return {
        "schema": SCHEMA,
        "baseline": {"replay_vel_rmse_mps": _num(diagnosis.baseline.rmse_mps())},
        "causes": [
            {
                "name": c.name,
                "params": {k: _num(v) for k, v in c.params.items()},
                "explained_fraction": _num(c.explained_fraction),
                "confidence": _num(c.confidence),
                "evidence": c.evidence,
                "statistic": c.statistic,
                "at_bound": c.at_bound,
                "unpinned": {k: [_num(lo), _num(hi)] for k, (lo, hi) in c.unpinned.items()},
            }
            for c in diagnosis.causes
        ],
        "noise_floor": diagnosis.noise_floor,
        "explained_of_explainable": (
            None
            if diagnosis.explained_of_explainable is None
            else _num(diagnosis.explained_of_explainable)
        ),
        "not_examined": list(diagnosis.not_examined),
        "at_bound": list(diagnosis.at_bound),
        "warnings": list(diagnosis.warnings),
        "thrust_sources": list(diagnosis.thrust_sources),
        "verdict": list(diagnosis.verdict),
        "extended": {
            "replay_vel_rmse_mps": _num(diagnosis.extended.rmse_mps()),
            "gain": _num(diagnosis.gain),
        },
        "closed_loop": {
            "baseline_vel_rmse_mps": _num(cl.baseline_rmse_mps()),
            "extended_vel_rmse_mps": _num(cl.extended_rmse_mps()),
            "gain": _num(cl.gain() if diagnosis.added_effects or not cl.scored.any() else 1.0),
            "ground_hold_gain": _num(
                cl.ground_hold_gain()
                if diagnosis.added_effects or not (cl.whole & cl.near_ground).any()
                else 1.0
            ),
            "segments": cl.segments,
            "segments_reanchored": cl.reanchored,
            "segments_reanchored_baseline": cl.reanchored_baseline,
            "segments_reanchored_extended": cl.reanchored_extended,
            "scored_rows": int(cl.scored.sum()),
        },
    }


def headline(diagnosis: Diagnosis) -> str:
    """One line for the terminal: the verdict and the held-out replay gain, or that the replay
    was not examined (then no gain was measured), and the causes the logs could not examine
    (a verdict of none says nothing about them)."""
    verdict = ", ".join(diagnosis.verdict) or "none"
    if math.isfinite(diagnosis.gain):
        line = f"{verdict}; gain {diagnosis.gain:.1f}x"
    else:
        line = f"{verdict}; held-out replay not examined (no gain measured)"
    if diagnosis.not_examined:
        line += f"; not examined: {', '.join(diagnosis.not_examined)}"
    return line


def write_report(
    diagnosis: Diagnosis,
    out_dir: Path,
    log_names: Sequence[str],
    config_name: str,
    extended_config: Path,
) -> list[Path]:
    """Write report.json, report.md and its plots into ``out_dir``; returns the files."""
    out_dir.mkdir(parents=True, exist_ok=True)
    json_path = out_dir / "report.json"
    json_path.write_text(json.dumps(report_document(diagnosis), indent=2) + "\n")
    plots = [plot_replay(diagnosis, out_dir / "replay_velocity.png")]
    plots += plot_residuals(diagnosis, out_dir)
    tracking_plot = plot_closed_loop(diagnosis, out_dir / "closed_loop_velocity.png")
    md_path = out_dir / "report.md"
    md = _markdown(diagnosis, log_names, config_name, extended_config, plots)
    md_path.write_text(md + _closed_loop_markdown(report_document(diagnosis), tracking_plot))
    return [json_path, md_path, *plots, tracking_plot]


def _markdown(
    d: Diagnosis, log_names: Sequence[str], config_name: str, extended: Path, plots: list[Path]
) -> str:
    verdict = ", ".join(f"`{v}`" for v in d.verdict) or (
        "none: no cause stands out of the log's noise floor"
    )
    if d.not_examined:
        verdict += f" (not examined: {', '.join(d.not_examined)})"
    floor = d.noise_floor.get("replay_rmse_mps")
    lines = [
        "# Diagnosis: what the simulation gets wrong",
        "",
        f"- Logs: {', '.join(f'`{n}`' for n in log_names)}",
        f"- Simulation config: `{config_name}`",
        f"- **Verdict: {verdict}**",
        (
            f"- Held-out replay velocity RMSE: baseline {d.baseline.rmse_mps():.4f} m/s, "
            f"extended {d.extended.rmse_mps():.4f} m/s (gain {d.gain:.1f}x)"
            if math.isfinite(d.baseline.rmse_mps())
            else "- Held-out replay: not examined (see the warning below)"
        ),
        "- Noise floor of the logs (replay RMSE white velocity noise alone leaves): "
        + (f"{floor:.4f} m/s" if isinstance(floor, float) else "n/a"),
        f"- Extended config: `{extended.name}`",
        *(f"- Thrust of log {i + 1}: {s}" for i, s in enumerate(d.thrust_sources)),
        *(f"- **Warning:** {w}" for w in d.warnings),
        "",
        "## Causes, strongest first",
        "",
        "| cause | parameters | explained | confidence | evidence |",
        "|---|---|---|---|---|",
    ]
    lines += [_cause_row(c) for c in d.causes]
    lines += ["", EXPLAINED_LEGEND]
    if d.not_identifiable:
        lines += ["", "## Not identifiable from these logs", ""]
        lines += [
            f"- `{n.name}`: {n.reason}. To identify it: {n.flight}." for n in d.not_identifiable
        ]
    if "ground_effect" in d.added_effects:
        lines += [
            "",
            "Ground effect assumes the rotor height above ground when landed given "
            "in the extended config (`rotor_height_m`); measure it and refit if it differs.",
        ]
    lines += ["", "## Plots", ""]
    lines += [f"![{p.stem}]({p.name})" for p in plots]
    return "\n".join(lines) + "\n"


def _closed_loop_markdown(doc: dict[str, Any], plot: Path) -> str:
    cl = doc["closed_loop"]
    figures = ", ".join(
        f"{label} {value:.4f} m/s" if value is not None else f"{label} n/a"
        for label, value in (
            ("config", cl["baseline_vel_rmse_mps"]),
            ("extended", cl["extended_vel_rmse_mps"]),
        )
    )
    gain = "n/a" if cl["gain"] is None else f"{cl['gain']:.1f}x"
    ground = "n/a" if cl["ground_hold_gain"] is None else f"{cl['ground_hold_gain']:.1f}x"
    return "\n".join(
        [
            "",
            "## Closed-loop tracking",
            "",
            "Each configuration, anchored once at the start of every airborne segment (flights "
            f"and ground holds below {NEAR_GROUND_ALT_M} m apart), flies the logged setpoints "
            "under its own flight control; its velocity is compared with the measured one (the "
            "real vehicle) on the held-out rows. A simulated vehicle that touches down where "
            "the real one flew is re-anchored, and its segment is left out of the figures "
            "(dotted in the plot).",
            "",
            f"- Velocity RMSE over whole flight segments: {figures} (gain {gain}; "
            f"{cl['scored_rows']} rows)",
            f"- Ground holds, scored apart: gain {ground}",
            f"- Segments re-anchored: {cl['segments_reanchored']} of {cl['segments']} (config "
            f"{cl['segments_reanchored_baseline']}, extended {cl['segments_reanchored_extended']})",
            "",
            f"![{plot.stem}]({plot.name})",
            "",
        ]
    )


def _num(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _cause_row(cause: Cause) -> str:
    """The cause table's row of ``cause``."""
    params = ", ".join(f"{k} = {v:.4g}" for k, v in cause.params.items()) or "-"
    explained = _percent(cause.explained_fraction)
    return (
        f"| `{cause.name}` | {params} | {explained} | {cause.confidence:.2f} | {cause.evidence} |"
    )


def _percent(fraction: float) -> str:
    """A fraction as a whole percentage ("37 %"), "n/a" when it is not a number."""
    return f"{round(100 * fraction):d} %" if math.isfinite(fraction) else "n/a"
