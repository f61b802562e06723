"""The extended config: the input config file plus [effects.<name>] tables with fitted values."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import tomli_w

from vehicle_sim.config import PRESET_DIR, PRESET_NAMES


def config_source(path_or_preset: str | Path) -> Path:
    """The TOML file behind a config path or preset name (as ``load_sim_config`` resolves it)."""
    src = str(path_or_preset)
    return PRESET_DIR / f"{src}.toml" if src in PRESET_NAMES else Path(src)


def extended_document(
    doc: Mapping[str, Any], added: Mapping[str, Mapping[str, Any]]
) -> dict[str, Any]:
    """``doc`` (a parsed config) with the effects ``added`` written into its [effects] tables,
    replacing any of the same name, and fitted ``flight_control`` gains into [px4_params];
    vectors become lists."""
    out = {k: v for k, v in doc.items() if k != "effects"}
    effects = {k: dict(v) for k, v in doc.get("effects", {}).items()}
    if "flight_control" in added:
        gains = {k: float(v) for k, v in added["flight_control"].items()}
        out["px4_params"] = {**dict(doc.get("px4_params", {})), **gains}
    for name, params in added.items():
        if name == "flight_control":
            continue
        effects[name] = {
            key: [float(v) for v in value] if isinstance(value, (list, tuple)) else float(value)
            for key, value in params.items()
        }
    if effects:
        out["effects"] = effects
    return out


def write_extended_config(
    path_or_preset: str | Path, added: Mapping[str, Mapping[str, Any]], out_path: Path
) -> Path:
    """Write the extended config of ``path_or_preset`` to ``out_path``; returns ``out_path``."""
    src = config_source(path_or_preset)
    doc = tomllib.loads(src.read_text())
    names = ", ".join(added) if added else "none"
    header = (
        f"# {src.name} extended by the diagnosis; effects added or refitted: {names}.\n"
        "# Units as in the effect parameter names (vehicle_sim/effects).\n"
    )
    out_path.write_text(header + tomli_w.dumps(extended_document(doc, added)))
    return out_path
