"""The companion runs on a companion computer without the simulator (docs/design.md section 2).

Importing every companion module that flies a real vehicle must not load ``vehicle_sim``,
``numba`` or ``jsbsim`` (the ``[sim]`` extra), nor the experiments or the diagnosis above it,
nor scikit-learn: a model file flies as its posterior (gp.model_io), and scikit-learn with the
scipy.stats it imports costs every companion process about 2 s of CPU at start.
"""

import subprocess
import sys

FLIGHT_MODULES = (
    "companion.app",
    "companion.runner",
    "companion.planner_registry",
    "companion.nmpc_planner",
    "companion.mavsdk_link",
    "companion.pymavlink_link",
    "companion.flight_recorder",
    "scripts.companion_cli",
)
FORBIDDEN = ("vehicle_sim", "numba", "jsbsim", "experiments", "diagnosis", "sklearn")


def test_companion_imports_no_simulator_module() -> None:
    code = (
        "import importlib, sys\n"
        f"for m in {FLIGHT_MODULES!r}: importlib.import_module(m)\n"
        f"print(sorted({{n.split('.')[0] for n in sys.modules}} & set({FORBIDDEN!r})))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "[]", out.stdout
