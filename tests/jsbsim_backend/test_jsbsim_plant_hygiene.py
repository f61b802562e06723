"""The plant keeps JSBSim quiet and writes nothing: not into the package, not into the cwd."""

import gc
from pathlib import Path

import jsbsim
import numpy as np

from tests.jsbsim_backend.jsbsim_helpers import fly
from vehicle_sim.jsbsim_backend import JsbsimF450Plant, PlantConfig


def _fly_briefly(config: PlantConfig) -> JsbsimF450Plant:
    plant = JsbsimF450Plant(config)
    fly(plant, np.full(4, 0.5), 0.5)
    plant.state()
    return plant


def test_jsbsim_prints_nothing_by_default(capfd):
    plant = _fly_briefly(PlantConfig(height_m=2.0))
    del plant
    gc.collect()
    out, err = capfd.readouterr()
    assert out == ""
    assert err == ""


def test_jsbsim_messages_are_kept_for_inspection():
    plant = _fly_briefly(PlantConfig())
    assert any("INCOMPATIBLE CFG FILE" in m for m in plant.messages)


def test_verbose_lets_jsbsim_print(capfd):
    plant = _fly_briefly(PlantConfig(verbose=True))
    out, _ = capfd.readouterr()
    assert "Reading Aircraft Configuration File: F450" in out
    assert plant.messages == ()


def test_the_threads_logger_is_restored():
    before = jsbsim.get_logger()
    _fly_briefly(PlantConfig())
    assert jsbsim.get_logger() is before


def test_a_block_of_many_steps_keeps_the_messages_and_restores_the_logger():
    before = jsbsim.get_logger()
    plant = JsbsimF450Plant(PlantConfig(height_m=2.0))
    with plant.messages_kept():
        routed = jsbsim.get_logger()
        assert routed is not before
        fly(plant, np.full(4, 0.5), 0.1)
        assert jsbsim.get_logger() is routed  # each step left it as it found it
    assert jsbsim.get_logger() is before


def _tree(root: Path) -> dict[str, tuple[int, int]]:
    """Files under ``root`` (Python's own bytecode caches aside) with size and mtime."""
    return {
        str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns)
        for p in root.rglob("*")
        if p.is_file() and "__pycache__" not in p.parts
    }


def test_no_files_written_into_the_package_or_the_working_dir(tmp_path, monkeypatch):
    package_dir = Path(jsbsim.get_default_root_dir())
    before = _tree(package_dir)
    monkeypatch.chdir(tmp_path)
    plant = _fly_briefly(PlantConfig(height_m=1.0))
    del plant
    gc.collect()
    assert _tree(package_dir) == before
    assert list(tmp_path.iterdir()) == []
