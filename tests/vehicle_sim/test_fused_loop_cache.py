"""The jitted closed loop is cached on disk, and an edit of its callees' files recompiles it."""

from __future__ import annotations

from pathlib import Path

import numba

import vehicle_sim
from vehicle_sim import Simulator, builtin_plant, flight_control, load_sim_config, physics
from vehicle_sim.builtin_plant import fused_loop, sources_sha256


def test_the_loop_is_loaded_from_the_cache_until_its_callees_sources_change(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))

    def fly(loop):
        monkeypatch.setattr(builtin_plant, "run_closed_loop", loop)
        sim = Simulator(load_sim_config("iris"))
        assert sim.arm().accepted and sim.takeoff(2.0).accepted
        sim.step(0.5)
        said = capsys.readouterr().err
        return sum(loop.stats.cache_hits.values()), sum(loop.stats.cache_misses.values()), said

    building = "building the simulator's compiled flight loop for this machine (once, about"
    hits, misses, said = fly(fused_loop("a" * 64))
    assert (hits, misses) == (0, 1) and building in said  # compiled and written, said first
    assert fly(fused_loop("a" * 64)) == (1, 0, "")  # a new process would load it like this
    hits, misses, said = fly(fused_loop("b" * 64))
    assert (hits, misses) == (0, 1) and building in said  # the callees were edited


def test_the_shipped_loop_is_keyed_on_every_file_with_jitted_code():
    for loop in (builtin_plant.run_closed_loop, builtin_plant.run_scheduled):
        (cell,) = loop.py_func.__closure__
        assert cell.cell_contents == sources_sha256(physics, flight_control)
    # A new file of jitted code must join the key above (builtin_plant's own is numba's key).
    jitted = {
        path.name
        for path in Path(vehicle_sim.__file__).parent.rglob("*.py")
        if "@njit" in path.read_text()
    }
    assert jitted == {"physics.py", "flight_control.py", "builtin_plant.py"}
