"""A rover regime and the section 3.4 example write their files whole or not at all: an
interrupt while the figure is drawn leaves no temporary file (nor an open figure) behind, and
a folder that cannot be written is an OutputError (one line), not an OSError traceback."""

from pathlib import Path

import matplotlib.pyplot as plt
import pytest
from matplotlib.figure import Figure

from experiments.rover.illustrative import write_figure
from experiments.rover.report import run_regime
from flightlog.atomic_output import OutputError


def _interrupted(*_args, **_kwargs) -> None:
    raise KeyboardInterrupt


def test_a_regime_interrupted_while_drawing_leaves_nothing(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(Figure, "savefig", _interrupted)  # Ctrl-C inside matplotlib
    with pytest.raises(KeyboardInterrupt):
        run_regime("rover_exp1", str(tmp_path), trials=1)
    assert list(tmp_path.iterdir()) == []
    assert plt.get_fignums() == []


@pytest.mark.slow
def test_the_example_interrupted_while_drawing_leaves_nothing(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setattr(Figure, "savefig", _interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_figure(str(tmp_path / "fig4_illustrative.png"))
    assert list(tmp_path.iterdir()) == []
    assert plt.get_fignums() == []


def test_a_folder_that_cannot_be_written_is_an_output_error(tmp_path: Path) -> None:
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(OutputError):
        run_regime("rover_exp1", str(blocker / "out"), trials=1)
