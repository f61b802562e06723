"""vehicle-sim's first lines say how to reach it from the companion and whether obstacles are
solid: the banner gave MAVSDK's URL and pymavlink's own 'udpin:HOST:PORT' form (the GCS port,
which companion --link pymavlink refuses as an unsupported URL), and nothing of --world."""

from __future__ import annotations

from pathlib import Path

from scripts.vehicle_sim_cli import main

WORLD = Path(__file__).resolve().parents[2] / "missions" / "forest_short_world.toml"


def test_the_banner_gives_the_companion_url_and_the_world(capsys):
    argv = ["--offboard-port", "16340", "--offboard-bind-port", "0", "--gcs-bind-port", "0"]
    assert main([*argv, "--world", str(WORLD), "--duration-s", "0.2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].endswith(f", world {WORLD} (OBSTACLE_DISTANCE)"), lines[0]
    assert "companion: --url udpin://127.0.0.1:16340 (--link mavsdk or pymavlink)" in lines
