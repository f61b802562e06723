"""Presets and config validation: good files load, bad ones give one line naming key and fix."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from vehicle_sim import EFFECT_NAMES, SimConfigError, load_sim_config
from vehicle_sim.config import BACKEND_NAMES, PRESET_DIR
from vehicle_sim.effects import GroundEffect, RotorDrag, Wind

IRIS_TOML = (PRESET_DIR / "iris.toml").read_text()


def variant(tmp_path: Path, old: str, new: str, extra: str = "") -> Path:
    assert old in IRIS_TOML
    path = tmp_path / "vehicle.toml"
    path.write_text(IRIS_TOML.replace(old, new, 1) + extra)
    return path


def test_presets_have_the_documented_vehicles():
    iris, m100 = load_sim_config("iris"), load_sim_config("m100")
    assert iris.mass_kg == 1.5 and iris.vehicle.inertia_kgm2 == (0.029125, 0.029125, 0.055225)
    assert 0.012 <= iris.vehicle.motor_time_constant_s <= 0.025
    assert m100.mass_kg == 2.4 and m100.preset_name == "m100"
    for cfg in (iris, m100):
        assert cfg.physics_dt_s == 0.002 and cfg.effects == ()
        assert 0.3 < cfg.vehicle.hover_thrust_norm < 0.6  # thrust-to-weight about 2


def test_effects_from_toml_from_mappings_and_from_objects(tmp_path):
    path = variant(
        tmp_path,
        "# No effects by default",
        "# none",
        extra=(
            "\n[effects.rotor_drag]\nk_n_per_mps = [0.3, 0.3, 0.1]\n"
            "[effects.wind]\nvel_ned_mps = [0.0, 2.0, 0.0]\n"
            "[effects.payload]\nenabled = false\nmass_ratio = 1.4\n"
        ),
    )
    cfg = load_sim_config(path)
    assert cfg.effect_names == ("rotor_drag", "wind") and cfg.preset_name == "vehicle"
    assert cfg.effect("wind").vel_ned_mps == (0.0, 2.0, 0.0)
    cfg = load_sim_config(path, effects={"wind": {"vel_ned_mps": [1, 1, 0]}, "ground_effect": {}})
    assert cfg.effect("wind").vel_ned_mps == (1.0, 1.0, 0.0)
    assert cfg.effect("ground_effect") == GroundEffect()
    cfg = load_sim_config("iris", effects=[RotorDrag(k_n_per_mps=(0.5, 0.5, 0.2)), Wind()])
    assert cfg.without_effects("wind").effect_names == ("rotor_drag",)
    assert set(EFFECT_NAMES) == {
        "rotor_drag",
        "body_drag",
        "isotropic_drag",
        "wind",
        "gusts",
        "payload",
        "battery_sag",
        "ground_effect",
        "motor_lag",
        "command_delay",
        "thrust_curve",
        "wind_field",
    }


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("mass_kg = 1.5", "mass_kg = -1.5", r"vehicle\.mass_kg = -1\.5 is out of range; use a"),
        ("mass_kg = 1.5", "mass = 1.5", r"vehicle\.mass: unknown key; did you mean mass_kg\?"),
        ("mass_kg = 1.5", "", r"vehicle\.mass_kg is missing; add mass_kg = <value in kg>"),
        ("mass_kg = 1.5", 'mass_kg = "heavy"', r"vehicle\.mass_kg: expected a number in kg"),
        ("mass_kg = 1.5", "mass_kg = true", r"vehicle\.mass_kg: expected a number in kg"),
        ("spin = [1, 1, -1, -1]", "spin = [1, 1, 2, -1]", r"rotors\.spin: each spin must be 1"),
        ("full_v = 16.8", "full_v = 12.0", r"battery\.empty_v = 14\.0 must be below full_v"),
        ("[sim]", "[simulation]", r"simulation: unknown section"),
        ("= 1100.0", "= 300.0", r"vehicle\.thrust_coeff_n_per_radps2: the rotors give only"),
        (
            "[sim]",
            '[sim]\nbackend = "xplane"',
            r"sim\.backend = 'xplane' is unknown; choose one of builtin, jsbsim$",
        ),
        ("[sim]", "[sim]\nbackend = 1", r"sim\.backend = 1 is unknown; choose one of builtin"),
        ("[sim]", '[sim]\nbackends = "jsbsim"', r"sim\.backends: unknown key; did you mean"),
    ],
)
def test_bad_vehicle_files(tmp_path, old, new, match):
    path = variant(tmp_path, old, new)
    with pytest.raises(SimConfigError, match=match) as info:
        load_sim_config(path)
    assert "\n" not in str(info.value)
    assert str(info.value).startswith(f"{path}: ")  # which file, when several are in play


@pytest.mark.parametrize(
    ("mission", "kind"),
    [
        ("demo_bspline.toml", "a companion mission ([reference])"),
        ("excite_demo.toml", "an excitation schedule ([segment])"),
        ("forest_short_world.toml", "an obstacle world ([cylinder])"),
    ],
)
def test_another_kind_of_toml_is_named_not_taken_for_a_config_with_an_unknown_section(
    mission, kind
):
    """`diagnose --sim-config missions/demo_bspline.toml` said only 'name: unknown section'."""
    path = PRESET_DIR.parents[1] / "missions" / mission
    with pytest.raises(SimConfigError) as info:
        load_sim_config(path)
    assert str(info.value).startswith(f"{path}: {kind}, not a simulation config; pass a preset")


@pytest.mark.parametrize(
    ("effects", "match"),
    [
        ({"dust_devil": {}}, r"effects\.dust_devil: unknown effect; choose from rotor_drag"),
        ({"payload": {"mass_ratio": -1.0}}, r"effects\.payload\.mass_ratio = -1\.0 is out of"),
        ({"payload": {"mass_ratio": "1.2"}}, r"effects\.payload\.mass_ratio: expected a number"),
        ({"rotor_drag": {"k_n_per_mps": 0.3}}, r"rotor_drag\.k_n_per_mps: expected a list of 3"),
        (
            {"rotor_drag": {"k": [0.3, 0.3, 0.1]}},
            r"rotor_drag\.k: unknown parameter; rotor_drag "
            r"takes k_n_per_mps \[N/\(m/s\)\]",
        ),
        ({"motor_lag": {"tau_s": 0.0}}, r"effects\.motor_lag\.tau_s = 0\.0 is out of range"),
        ({"wind": {}}, r"effects\.wind: acts only through drag; also enable rotor_drag"),
        (
            {"gusts": {}, "body_drag": {}, "command_delay": {"enabled": "yes"}},
            r"effects\.command_delay\.enabled: expected true or false",
        ),
        ({"ground_effect": 3}, r"effects\.ground_effect: expected a table of parameters"),
    ],
)
def test_bad_effects(effects, match):
    with pytest.raises(SimConfigError, match=match) as info:
        load_sim_config("iris", effects)
    assert "\n" not in str(info.value)


def test_effect_objects_validate_on_construction_and_bad_sources():
    with pytest.raises(SimConfigError, match=r"effects\.wind\.vel_ned_mps: expected a list of 3"):
        Wind(vel_ned_mps=(1.0, 2.0))
    with pytest.raises(SimConfigError, match=r"no such config file or preset; use one of .*iris"):
        load_sim_config("iris2")
    with pytest.raises(SimConfigError, match="is not an effect"):
        load_sim_config("iris", effects=["rotor_drag"])
    assert issubclass(SimConfigError, ValueError)


def test_the_sim_backend_key_names_the_physics_backend(tmp_path):
    assert load_sim_config("iris").backend == "builtin" == load_sim_config("f450").backend
    config = load_sim_config(variant(tmp_path, "[sim]", '[sim]\nbackend = "jsbsim"'))
    assert config.backend == "jsbsim" and BACKEND_NAMES == ("builtin", "jsbsim")
    with pytest.raises(SimConfigError, match=r"sim\.backend = 'JSBSim' is unknown; choose one of"):
        replace(config, backend="JSBSim")


def test_a_flight_log_or_a_binary_file_given_as_the_config_is_one_line_with_the_fix(tmp_path):
    """diagnose LOG --sim-config LOG (the arguments swapped) raised a UnicodeDecodeError
    traceback for a .ulg and called a CSV log 'not valid TOML; fix the syntax'."""
    ulog = Path(__file__).resolve().parents[1] / "fixtures" / "ulog" / "quad_posctl_v1_15.ulg"
    csv = tmp_path / "flight.csv"
    csv.write_text("t_s,pos_n_m\n0.0,1.0\n")
    for log in (ulog, csv):
        with pytest.raises(SimConfigError) as exc:
            load_sim_config(log)
        assert str(exc.value) == (
            f"{log}: a flight log, not a sim config; make a config from it with "
            f"vehicle-sim config-from-log {log} --out my_vehicle.toml"
        )
    binary = tmp_path / "vehicle.toml"
    binary.write_bytes(ulog.read_bytes()[:4096])
    with pytest.raises(SimConfigError, match=r"a binary file, not a config TOML; use one of "):
        load_sim_config(binary)
