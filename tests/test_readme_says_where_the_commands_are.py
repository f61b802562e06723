"""A newcomer who ran `make setup` and types a command the README names finds it: the README
says where the project's console scripts are installed and names every one of them."""

import re
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def test_readme_names_every_command_and_how_to_reach_it() -> None:
    readme = (REPO / "README.md").read_text()
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    assert "`make setup`" in readme and "`. .venv/bin/activate`" in readme
    named = set(re.findall(r"`([a-z-]+)[ `]", readme))
    assert sorted(set(scripts) - named) == []
