"""Outputs appear whole or not at all, and output-side errors are one line."""

from __future__ import annotations

import os
import stat

import pytest

from flightlog.atomic_output import (
    OutputError,
    atomic_output_dir,
    check_not_an_input,
    check_writable_dir,
    check_writable_file,
    describe_os_error,
    write_bytes_atomic,
    write_text_atomic,
)


def test_a_new_folder_set_appears_whole_and_an_existing_folder_loses_nothing(tmp_path) -> None:
    out = tmp_path / "report"
    with atomic_output_dir(out) as tmp:
        (tmp / "a.md").write_text("first")
        assert not out.exists()  # nothing visible until the set is complete
    (out / "users_notes.txt").write_text("mine")
    with atomic_output_dir(out) as tmp:
        (tmp / "a.md").write_text("second")
        (tmp / "plots").mkdir()
        (tmp / "plots" / "p.png").write_text("png")
    assert sorted(p.name for p in out.iterdir()) == ["a.md", "plots", "users_notes.txt"]
    assert (out / "a.md").read_text() == "second" and (out / "plots" / "p.png").is_file()
    assert (out / "users_notes.txt").read_text() == "mine"
    assert [p.name for p in tmp_path.iterdir()] == ["report"]  # no temporary left behind


def test_a_failure_inside_leaves_the_old_set_untouched(tmp_path) -> None:
    out = tmp_path / "report"
    with atomic_output_dir(out) as tmp:
        (tmp / "a.md").write_text("good")
    with pytest.raises(RuntimeError), atomic_output_dir(out) as tmp:
        (tmp / "a.md").write_text("half")
        raise RuntimeError("plotting failed")
    assert (out / "a.md").read_text() == "good"
    assert [p.name for p in tmp_path.iterdir()] == ["report"]


@pytest.mark.parametrize("check", [check_writable_dir, check_writable_file])
def test_a_file_in_the_way_is_one_line_naming_the_path(tmp_path, check) -> None:
    blocker = tmp_path / "blocker"
    blocker.write_text("x")
    with pytest.raises(OutputError, match="blocker") as info:
        check(blocker / "out")
    assert "\n" not in str(info.value) and "folder" in str(info.value)


@pytest.mark.parametrize("write", [check_writable_file, lambda p: write_text_atomic(p, "x")])
def test_a_pipe_is_refused_not_replaced_by_a_regular_file(tmp_path, write) -> None:
    """The rename that puts a file in place replaced a device or a pipe given as the output
    (--out /dev/null, run as root, left /dev/null a regular file): a named pipe stands in."""
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="pipe: not a regular file .*give a file name") as info:
        write(fifo)
    assert "\n" not in str(info.value) and stat.S_ISFIFO(fifo.stat().st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["pipe"]


def test_a_file_is_replaced_atomically(tmp_path) -> None:
    path = write_text_atomic(tmp_path / "sub" / "f.txt", "one")
    write_text_atomic(path, "two")
    assert path.read_text() == "two" and [p.name for p in path.parent.iterdir()] == ["f.txt"]


def test_outputs_get_the_permissions_of_any_new_file_or_folder(tmp_path) -> None:
    """Written through a temporary sibling, an output still gets the mode the user's umask gives
    a new file (not the temporary's private 0600 / 0700): a log or model another user of the
    companion computer must read."""
    umask = os.umask(0o022)
    try:
        file = write_text_atomic(tmp_path / "flight.csv", "t_s\n")
        with atomic_output_dir(tmp_path / "report") as tmp:
            (tmp / "report.md").write_text("done")
    finally:
        os.umask(umask)
    assert stat.S_IMODE(file.stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "report").stat().st_mode) == 0o755


def test_a_figure_is_written_whole_and_closed_even_when_saving_fails(tmp_path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from flightlog.atomic_output import write_figure_atomic

    fig, ax = plt.subplots()
    ax.plot([0.0, 1.0])
    path = write_figure_atomic(fig, tmp_path / "a.png", dpi=40)
    assert path.read_bytes().startswith(b"\x89PNG") and not plt.fignum_exists(fig.number)
    fig, _ = plt.subplots()

    def fails(*args, **kwargs):
        raise KeyboardInterrupt  # Ctrl-C while Matplotlib renders

    fig.savefig = fails
    with pytest.raises(KeyboardInterrupt):
        write_figure_atomic(fig, tmp_path / "b.png", dpi=40)
    assert not plt.fignum_exists(fig.number)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]  # no temporary left


def test_a_written_file_is_synced_to_disk_before_it_is_renamed_into_place(
    tmp_path, monkeypatch
) -> None:
    """An experience or path file written on the vehicle must survive a power cut: its bytes
    reach the disk (fsync) before the rename makes it the file, never an empty file renamed."""
    calls: list[str] = []
    fsync, replace = os.fsync, os.replace
    monkeypatch.setattr(os, "fsync", lambda fd: (calls.append("fsync"), fsync(fd))[1])
    monkeypatch.setattr(os, "replace", lambda a, b: (calls.append("replace"), replace(a, b))[1])
    path = write_text_atomic(tmp_path / "path.csv", "x_m,y_m\n")
    assert calls == ["fsync", "replace"]
    assert path.read_text() == "x_m,y_m\n"


def test_a_file_that_cannot_be_put_in_place_leaves_no_temporary_behind(tmp_path) -> None:
    """A folder standing where the file should go: the write fails in one line and the
    temporary sibling it was filled in is gone, so the folder holds only what it held."""
    target = tmp_path / "report.json"
    target.mkdir()
    with pytest.raises(OutputError, match="report.json"):
        write_bytes_atomic(target, b"{}")
    assert list(tmp_path.iterdir()) == [target]


def test_an_output_spelled_another_way_is_still_recognised_as_the_input(tmp_path) -> None:
    """The same file named through another folder (sub/../flight.ulg) or a symbolic link is
    the input all the same: writing there would replace it."""
    flight = tmp_path / "flight.ulg"
    flight.write_bytes(b"ULog")
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.ulg").symlink_to(flight)
    for out in (tmp_path / "sub" / ".." / "flight.ulg", tmp_path / "link.ulg"):
        with pytest.raises(OutputError, match="is an input being read"):
            check_not_an_input(out, [flight])
    check_not_an_input(tmp_path / "other.ulg", [flight])


def test_any_other_os_error_says_what_to_do(tmp_path):
    """--out /proc/x said "cannot write (No such file or directory)" and nothing more."""
    said = describe_os_error(tmp_path / "x", FileNotFoundError(2, "No such file or directory"))
    assert said == (
        f"{tmp_path / 'x'}: cannot write (No such file or directory); choose a path in a folder "
        "you can write to"
    )
