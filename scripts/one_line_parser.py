"""The commands' argument parser: a bad option is one line and exit 2, no usage block."""

from __future__ import annotations

import argparse
from pathlib import Path

EXIT_BAD_INPUT = 2


class OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line, ``PROG: error: MESSAGE; see --help``, and exit
    code 2 (argparse prints its usage block first, which buries the reason)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}; see --help\n")


def output_path(text: str) -> Path:
    """An output file or folder from the command line (argparse ``type``). An empty one, as
    ``--out "$OUT"`` gives with OUT unset, is refused: it would mean the current folder."""
    if not text.strip():
        raise argparse.ArgumentTypeError("empty path; give a file or folder name")
    return Path(text)
