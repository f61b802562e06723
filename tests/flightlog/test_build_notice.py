"""The build notice starts with the running command's name, as that command's other lines do."""

from __future__ import annotations

import sys

import pytest

from flightlog.build_notice import say_building


@pytest.mark.parametrize(
    ("argv0", "command"),
    [
        ("/home/u/rc/.venv/bin/fit-gp", "fit-gp"),  # a console script
        ("/home/u/rc/scripts/diagnose.py", "diagnose"),  # python -m scripts.diagnose
        ("/usr/lib/python3/site-packages/pytest/__main__.py", "pytest"),  # python -m pytest
        ("-c", "python"),
    ],
)
def test_the_line_names_the_command_and_rounds_the_time(argv0, command, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [argv0])
    say_building("the thing", 12.6)
    say_building("a small thing", 0.2)
    assert capsys.readouterr() == (
        "",
        f"{command}: building the thing for this machine (once, about 13 s)...\n"
        f"{command}: building a small thing for this machine (once, about 1 s)...\n",
    )
