"""`python -m vehicle_sim.prebuild` builds the compiled loops a replay and a flight use: after it,
neither compiles another specialisation (which every pytest worker would then compile again)."""

from __future__ import annotations

import subprocess
import sys

FLY_AND_REPLAY = """
from diagnosis.fly_schedule import fly_schedule
from diagnosis.replay import replay, windows
from experiments.bench.diagnose import bench_schedule
from vehicle_sim import builtin_plant, load_sim_config
from vehicle_sim.prebuild import prebuild

loops = (builtin_plant.run_closed_loop, builtin_plant.run_scheduled)
prebuild()
built = [list(loop.signatures) for loop in loops]
log = fly_schedule(load_sim_config("iris"), bench_schedule(21.0), seed=1)
delayed = load_sim_config("iris", {"command_delay": {"delay_s": 0.05}})
result = replay(delayed, [log], windows([log]))
assert result.rmse_mps() > 0.0
print(built == [list(loop.signatures) for loop in loops], [len(s) for s in built])
"""


def test_a_flight_and_a_replay_after_it_compile_nothing_more():
    done = subprocess.run(
        [sys.executable, "-c", FLY_AND_REPLAY], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["True", "[1,", "1]"], done.stdout
