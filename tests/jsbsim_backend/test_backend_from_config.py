"""The backend comes from the config's ``[sim] backend`` unless the caller (or `vehicle-sim
--backend`) says otherwise; it is recorded in the log sidecar and reaches the companion."""

from dataclasses import replace

import pytest

from companion.inprocess_link import InProcessLink
from flightlog.schema import FlightLogRecorder, read_flight_log, write_flight_log
from scripts.vehicle_sim_cli import build_endpoint, main, parse_args
from tests.jsbsim_backend.jsbsim_helpers import f450_config
from vehicle_sim import SimConfigError, Simulator
from vehicle_sim.backends import make_backend
from vehicle_sim.config import PRESET_DIR
from vehicle_sim.jsbsim_backend import JsbsimBackend

FREE_PORTS = ["--offboard-bind-port", "0", "--gcs-bind-port", "0"]


def f450_file(tmp_path, backend: str, extra: str = ""):
    """The f450 preset as a config file whose ``[sim]`` names ``backend``."""
    text = (PRESET_DIR / "f450.toml").read_text()
    path = tmp_path / f"f450_{backend}.toml"
    path.write_text(text.replace("[sim]", f'[sim]\nbackend = "{backend}"', 1) + extra)
    return path


def test_the_config_backend_is_used_unless_an_argument_overrides_it():
    config = replace(f450_config(), backend="jsbsim")
    assert type(make_backend(None, config)) is JsbsimBackend
    assert Simulator(config).backend_name == "jsbsim"
    assert Simulator(config, backend="builtin").backend_name == "builtin"
    assert Simulator(f450_config(), backend="jsbsim").backend_name == "jsbsim"


def test_the_sidecar_records_the_backend(tmp_path):
    for backend in ("builtin", "jsbsim"):
        sim = Simulator(f450_config(), backend=backend)
        assert sim.log_metadata()["backend"] == backend
        recorder = FlightLogRecorder(sim.log_metadata())
        for _ in range(3):
            recorder.append(sim.log_row())
            sim.step(0.05)
        path = write_flight_log(tmp_path / f"{backend}.csv", recorder.to_log())
        assert read_flight_log(path).metadata["backend"] == backend


def test_vehicle_sim_backend_flag_overrides_the_config(tmp_path):
    jsbsim_file = str(f450_file(tmp_path, "jsbsim"))
    cases = [
        (["--vehicle", "f450", "--backend", "jsbsim"], "jsbsim"),
        (["--vehicle", jsbsim_file], "jsbsim"),
        (["--vehicle", jsbsim_file, "--backend", "builtin"], "builtin"),
        (["--vehicle", "f450"], "builtin"),
    ]
    for argv, expected in cases:
        endpoint = build_endpoint(parse_args([*argv, *FREE_PORTS]))
        assert endpoint.sim.backend_name == expected, argv


def test_vehicle_sim_refuses_an_unknown_backend_in_one_line(capsys):
    assert main(["--backend", "xplane"]) == 2
    err = capsys.readouterr().err
    assert "--backend: invalid choice: 'xplane'" in err and "builtin" in err and "jsbsim" in err
    assert err.count("\n") == 1 and err.startswith("vehicle-sim: error:")


def test_vehicle_sim_backend_jsbsim_on_the_default_vehicle_names_the_preset_to_fly(capsys):
    """README's `--backend jsbsim` alone flies the default iris, which JSBSim's F450 is not."""
    assert main(["--backend", "jsbsim", *FREE_PORTS]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not describe JSBSim's F450" in err
    assert "preset f450 (or f450_jsbsim, whose [sim] backend is jsbsim)" in err


def test_a_config_file_flies_the_companion_in_process_link_on_jsbsim(tmp_path):
    with pytest.raises(SimConfigError, match="effects belong to the built-in physics"):
        InProcessLink.from_vehicle(
            str(f450_file(tmp_path, "jsbsim", "\n[effects.payload]\nmass_ratio = 1.2\n")), seed=0
        )
    link = InProcessLink.from_vehicle(str(f450_file(tmp_path, "jsbsim")), seed=0)
    link.connect(1.0)
    assert link.arm().accepted and link.takeoff(2.0).accepted
    link.clock.sleep_until(8.0)
    state = link.read_state()
    assert state.armed and state.pos_ned_m[2] == pytest.approx(-2.0, abs=0.15)
