"""Teach and repeat over the companion's Links: the teach pass, the path and experience files,
repeating a loop with learning, and the refusals (too little motion, NaN position, another
path's experience, damaged files)."""

import math
import threading
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from companion.inprocess_rover_link import InProcessRoverLink
from companion.link import CommandOutcome, LinkError, VelocityCommand
from companion.pymavlink_link import PymavlinkLink
from companion.runner import Terminated
from experiments.rover import learner
from experiments.rover.drive_back import STALL_S, DriveBack, drive_back, reverse_along
from experiments.rover.experience_file import (
    ExperienceFileError,
    load_experience,
    save_experience,
)
from experiments.rover.link_commands import pose_of
from experiments.rover.link_drive import drive_path
from experiments.rover.path_start import is_loop, start_offset
from experiments.rover.repeat import repeat_path
from experiments.rover.teach import HandedOver, TeachError, record_teach
from planners.rover.path import TaughtPath
from planners.rover.path_file import PathFileError, path_csv_text, read_path_file
from planners.rover.speed_scheduler import TABLE_I, initial_schedule
from tests.free_port import free_udp_port
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint

LOOP = [(2.0, 0.0), (math.pi * 1.5, 1 / 1.5), (2.0, 0.0), (math.pi * 1.5, 1 / 1.5)]


class PilotAfterTwenty(InProcessRoverLink):
    """The in-process rover whose pilot switches it to Hold after 20 commands; counts what is
    sent after that (setpoints and holds)."""

    sent = 0
    after = 0

    def send_velocity(self, command) -> None:
        if self.sent >= 20:
            self.after += 1
        self.sent += 1
        super().send_velocity(command)
        if self.sent == 20:
            InProcessRoverLink.hold(self)  # the pilot's switch, not the program's

    def hold(self):
        self.after += 1
        return super().hold()


def _pilot_link() -> PilotAfterTwenty:
    return PilotAfterTwenty(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})


def _taught_loop() -> TaughtPath:
    return record_teach(InProcessRoverLink.from_preset("husky_50kg"), drive=LOOP).path


def test_a_scripted_teach_drive_records_the_pattern_resampled_to_the_spacing() -> None:
    taught = record_teach(InProcessRoverLink.from_preset("husky_50kg"), drive=LOOP, spacing_m=0.5)
    length = 4.0 + 3.0 * math.pi
    assert taught.ended_for == "the teach pattern ended"
    assert taught.path.length_m == pytest.approx(length, rel=0.05)
    assert taught.path.spacing_m == pytest.approx(0.5, rel=0.05)
    assert is_loop(taught.path)
    # LOOP's arcs turn left (curvature > 0) with a 1.5 m radius: in the path frame (x north,
    # y west) the loop lies left of its first leg along +x, up to 2 x 1.5 m = 3 m to the left
    y = taught.path.xy_m[:, 1]
    assert y.min() > -0.05 and y.max() == pytest.approx(3.0, abs=0.1)


def test_a_pilot_who_takes_the_rover_out_of_offboard_ends_a_scripted_teach() -> None:
    """The pilot switches the rover to Hold 20 commands into the scripted teach drive: the
    teach ends at once saying so, writes no path and sends nothing more."""

    link = _pilot_link()
    with pytest.raises(HandedOver, match="left OFFBOARD for HOLD during the teach drive"):
        record_teach(link, drive=LOOP, timeout_s=60.0)
    assert link.after == 0


class TerminatedLink(InProcessRoverLink):
    """The in-process rover, on which SIGTERM arrives (as companion.runner.Terminated, what
    rover-path's handler raises) after ``after`` telemetry reads."""

    def __init__(self, after: int) -> None:
        super().__init__(RoverSim(rover_preset("husky_50kg")))
        self.reads_left = after

    def read_state(self):  # noqa: ANN201
        self.reads_left -= 1
        if self.reads_left < 0:
            raise Terminated
        return super().read_state()


def test_sigterm_ends_a_teach_pass_and_is_said_as_sigterm_not_ctrl_c() -> None:
    taught = record_teach(TerminatedLink(after=120), drive=LOOP)
    assert taught.ended_for == "SIGTERM"
    assert taught.path.length_m > 2.0


def test_a_teach_pass_with_too_little_motion_is_refused() -> None:
    with pytest.raises(TeachError, match=r"drove 0\.\d\d m while recording.*at least 1 m"):
        record_teach(InProcessRoverLink.from_preset("husky_50kg"), drive=[(0.4, 0.0)])


def test_a_rover_without_a_position_is_refused_on_connecting() -> None:
    sim = RoverSim(rover_preset("husky_50kg"), pose=(math.nan, 0.0, 0.0))
    with pytest.raises(Exception, match="non-finite state"):
        record_teach(InProcessRoverLink(sim), drive=LOOP)


def test_the_path_file_round_trips_and_bad_files_are_one_line(tmp_path: Path) -> None:
    path = _taught_loop()
    good = tmp_path / "loop.csv"
    good.write_text(path_csv_text(path))
    again = read_path_file(good)
    assert np.allclose(again.xy_m, path.xy_m, atol=0.01)  # resampled again
    cases = {
        "missing.csv": (None, "no such path file"),
        "binary.csv": (b"\x89PNG\x00\xff\xfe", "cannot read it as a CSV text file"),
        "header.csv": ("lat,lon\n1,2\n", "expected the header 'x_m,y_m'"),
        "columns.csv": ("x_m,y_m\n0,0\n1,0,5\n2,0\n", "line 3 has 3 columns"),
        "nan.csv": ("x_m,y_m\n0,0\n1,nan\n2,0\n3,0\n", "path line 3"),
        "word.csv": ("x_m,y_m\n0,0\n1,zero\n2,0\n", "path line 3"),
        "short.csv": ("x_m,y_m\n0,0\n1,0\n", "2 rows under its header; a path needs at least 3"),
        "empty.csv": ("", "the file is empty"),
    }
    for name, (content, message) in cases.items():
        f = tmp_path / name
        if isinstance(content, bytes):
            f.write_bytes(content)
        elif content is not None:
            f.write_text(content)
        with pytest.raises(PathFileError) as err:
            read_path_file(f)
        text = str(err.value)
        assert message in text and str(f) in text and "\n" not in text, (name, text)


def test_a_path_file_keeps_vertices_to_the_millimetre_and_refuses_swapped_columns(
    tmp_path: Path,
) -> None:
    """The rows are the vertices in metres to better than a millimetre (a resampled path read
    back lies where it was taught); a header naming the columns in another order (y_m,x_m,
    which would mirror the path about x = y) or in other units (feet) is refused."""
    path = TaughtPath.from_csv_text("0,0\n1.23456,0.654321\n2.5,1.0\n")
    rows = np.array(
        [[float(v) for v in line.split(",")] for line in path_csv_text(path).splitlines()[1:]]
    )
    assert np.abs(rows - path.xy_m).max() < 1e-3
    for header in ("y_m,x_m", "x_ft,y_ft"):
        other = tmp_path / "other.csv"
        other.write_text(f"{header}\n0,0\n1,0\n2,0\n")
        with pytest.raises(PathFileError, match="expected the header 'x_m,y_m'"):
            read_path_file(other)


def test_repeating_a_loop_learns_and_the_experience_file_carries_it_on(tmp_path: Path) -> None:
    """Two trials on the in-process Link: each stores one experience per vertex and speed bin;
    saved and loaded into a fresh GP the bins are the same, and a third trial (a later run)
    adds to them."""
    path = _taught_loop()
    link = InProcessRoverLink.from_preset("husky_50kg", seed=1)
    link.connect(1.0)
    gp = learner.make_history_gp()
    sizes: list[int] = []
    out = repeat_path(link, path, 2, gp, np.full(len(path), 0.5),
                      on_trial=lambda t, _s: sizes.append(t.experiences))  # fmt: skip
    assert out.status == "completed", out.detail
    assert [t.number for t in out.trials] == [1, 2]
    assert 0 < sizes[0] < sizes[1]
    f = tmp_path / "exp.npz"
    save_experience(f, gp, path, 2)
    gp2 = learner.make_history_gp()
    memory = load_experience(f, gp2, path)
    assert memory.trials_done == 2 and memory.schedule_mps is None
    for (v1, b1, a1, g1), (v2, b2, a2, g2) in zip(gp.stored(), gp2.stored(), strict=True):
        assert (v1, b1) == (v2, b2) and np.array_equal(a1, a2) and np.array_equal(g1, g2)
    out = repeat_path(link, path, 1, gp2, np.full(len(path), 0.5), first_number=3)
    assert out.status == "completed" and out.trials[0].number == 3
    assert len(gp2) > len(gp)


def test_the_speed_scheduler_sets_the_next_trial_from_the_drive() -> None:
    path = _taught_loop()
    link = InProcessRoverLink.from_preset("husky_50kg", seed=2)
    link.connect(1.0)
    config = TABLE_I["experiment_2"]
    start = initial_schedule(len(path), config)
    out = repeat_path(link, path, 2, learner.make_history_gp(), start, config)
    assert out.status == "completed", out.detail
    assert np.array_equal(out.trials[0].schedule_mps, start)
    assert np.mean(out.trials[1].schedule_mps) > np.mean(start)  # small errors: faster


def test_an_experience_file_refuses_another_path_and_damage(tmp_path: Path) -> None:
    path = _taught_loop()
    gp = learner.make_history_gp()
    gp.add(3, 0.5, np.zeros(8), np.zeros(3))
    f = tmp_path / "exp.npz"
    save_experience(f, gp, path, 1)
    other = TaughtPath.from_segments([(5.0, 0.0)])
    with pytest.raises(ExperienceFileError, match="learned on another path"):
        load_experience(f, learner.make_history_gp(), other)
    coarser = TaughtPath(path.xy_m, spacing_m=0.5)  # the same file read with --spacing 0.5
    with pytest.raises(ExperienceFileError, match=r"at a vertex spacing of 0\.2\d m.*--spacing 0"):
        load_experience(f, learner.make_history_gp(), coarser)
    # as many vertices, but the path moved 0.5 m: its vertex indices mean other places
    shifted = TaughtPath(path.xy_m + [0.5, 0.0], spacing_m=path.spacing_m)
    assert len(shifted) == len(path)
    with pytest.raises(ExperienceFileError, match="learned on another path"):
        load_experience(f, learner.make_history_gp(), shifted)
    damaged = tmp_path / "damaged.npz"
    damaged.write_bytes(f.read_bytes()[:200])
    not_npz = tmp_path / "notes.npz"
    not_npz.write_text("hello")
    for bad in (damaged, not_npz):
        with pytest.raises(ExperienceFileError, match="not a readable experience file"):
            load_experience(bad, learner.make_history_gp(), path)
    np.savez(tmp_path / "foreign.npz", weights=np.zeros(3))
    with pytest.raises(ExperienceFileError, match="lacks"):
        load_experience(tmp_path / "foreign.npz", learner.make_history_gp(), path)
    with np.load(f) as npz:
        arrays = {k: npz[k] for k in npz.files}
    arrays["disturbance"] = np.full_like(arrays["disturbance"], np.nan)
    np.savez(tmp_path / "nan.npz", **arrays)
    with pytest.raises(ExperienceFileError, match="damaged"):
        load_experience(tmp_path / "nan.npz", learner.make_history_gp(), path)
    finer = learner.make_history_gp(replace(learner.PAPER_BINS, speed_bin_mps=0.1))
    with pytest.raises(ExperienceFileError, match="kept with other experience bins"):
        load_experience(f, finer, path)
    assert load_experience(tmp_path / "none.npz", learner.make_history_gp(), path).trials_done == 0


def test_an_experience_file_gives_every_experience_back_in_its_own_bin(tmp_path: Path) -> None:
    """Saved and loaded, each experience is in the vertex and speed bin it was kept in, for
    bins of 0.05 m/s too, where bin 43 (2.15-2.20 m/s) read back at its lower edge 43 x 0.05
    would land in bin 42 by rounding; the trials driven and the schedule come back too, a
    schedule only when it gives one speed per vertex."""
    path = TaughtPath.from_segments([(5.0, 0.0)])
    bins = replace(learner.PAPER_BINS, speed_bin_mps=0.05)
    gp = learner.make_history_gp(bins)
    for vertex, speed in ((3, 2.16), (4, 0.52), (5, 1.01)):
        gp.add(vertex, speed, np.full(8, float(vertex)), np.full(3, speed))
    f = tmp_path / "exp.npz"
    schedule = np.linspace(0.4, 0.8, len(path))
    save_experience(f, gp, path, 7, schedule)
    again = learner.make_history_gp(bins)
    memory = load_experience(f, again, path)
    assert [(v, b) for v, b, _, _ in again.stored()] == [(3, 43), (4, 10), (5, 20)]
    assert memory.trials_done == 7 and np.array_equal(memory.schedule_mps, schedule)
    # a schedule that does not give one speed per vertex is not flown
    save_experience(f, gp, path, 7, schedule[:3])
    assert load_experience(f, learner.make_history_gp(bins), path).schedule_mps is None


def test_a_loop_ends_where_it_starts_facing_the_way_it_started() -> None:
    """A loop's end is the next trial's start, within 1 m and 0.5 rad: a full circle of 1.5 m
    radius is one; a U-turn (2 m out, a half circle of 0.4 m radius, 2 m back) ends about 0.8 m
    from its start but facing back, so it is not."""
    assert is_loop(TaughtPath.from_segments([(math.pi * 3.0, 1 / 1.5)]))
    u_turn = TaughtPath.from_segments([(2.0, 0.0), (math.pi * 0.4, 1 / 0.4), (2.0, 0.0)])
    assert np.hypot(*(u_turn.xy_m[-1] - u_turn.xy_m[0])) == pytest.approx(0.8, abs=0.05)
    assert not is_loop(u_turn)


def test_a_rover_at_the_start_facing_away_is_not_at_the_start() -> None:
    """The rover (at the origin, facing along x) on the first vertex of a path that starts
    facing -x is pi rad off its heading, past the 0.5 rad start tolerance: without a drive
    back the run stops before the first trial, saying so."""
    path = TaughtPath.from_segments([(5.0, 0.0)], start=(0.0, 0.0, math.pi))
    link = InProcessRoverLink.from_preset("husky_50kg")
    link.connect(1.0)
    out = repeat_path(link, path, 1, learner.make_history_gp(), np.full(len(path), 0.5))
    assert out.status == "not_at_start" and out.trials == []
    assert "0.0 m from the path's start" in out.detail and "3.14 rad off" in out.detail


def test_the_start_heading_error_is_the_short_way_round() -> None:
    """A rover facing 3.0 rad on a path that starts facing -3.0 rad is 2 pi - 6 = 0.283 rad
    off, within the start tolerance, not 6 rad."""
    sim = RoverSim(rover_preset("husky_50kg"), pose=(0.0, 0.0, 3.0))
    link = InProcessRoverLink(sim, {"rover_preset": "husky_50kg", "seed": 0})
    link.connect(1.0)
    path = TaughtPath.from_segments([(5.0, 0.0)], start=(0.0, 0.0, -3.0))
    dist, dhead = start_offset(link, path)
    assert dist == pytest.approx(0.0, abs=1e-9)
    assert dhead == pytest.approx(2 * math.pi - 6.0)


def test_drive_back_gets_to_the_pose_and_holds() -> None:
    """From the origin facing x, back to (3, 1) m facing +y (pi/2 rad): the rover turns,
    drives, turns and holds there, within a few centimetres and hundredths of a radian
    (ARRIVED_M 0.05 m, ALIGNED_RAD 0.05 rad, plus what it coasts once stopped), never
    commanding a turn faster than max_turn_radps (0.4 rad/s here)."""
    turns: list[float] = []

    class Recording(InProcessRoverLink):
        def send_velocity(self, command) -> None:
            turns.append(command.yaw_rate_radps)
            super().send_velocity(command)

    link = Recording(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})
    link.connect(1.0)
    assert drive_back(link, (3.0, 1.0, math.pi / 2), 0.5, 0.4, timeout_s=60.0) == ("", "")
    assert max(abs(w) for w in turns) == pytest.approx(0.4)  # max_turn_radps, reached
    x, y, heading = pose_of(link)
    assert math.hypot(x - 3.0, y - 1.0) < 0.08
    assert abs(heading - math.pi / 2) < 0.08
    assert link.read_state().mode == "HOLD"


def test_drive_back_yields_to_a_pilot_who_takes_the_rover_out_of_offboard() -> None:
    """A pilot switches the rover to Hold after 20 commands of the drive back: the drive ends
    at once, naming the mode, and sends nothing more (no stop, no further setpoint)."""

    link = _pilot_link()
    link.connect(1.0)
    assert drive_back(link, (3.0, 1.0, math.pi / 2), 0.5, timeout_s=60.0) == ("HOLD", "")
    assert link.after == 0


def test_a_pilot_who_takes_over_during_the_drive_back_ends_the_run_as_handed_over() -> None:
    """Repeating a path that starts 3 m ahead of the rover, with a drive back: the pilot's
    switch to Hold during the drive back ends the run as "handed_over", naming the mode, with
    no trial driven and nothing sent after it."""
    path = TaughtPath.from_segments([(5.0, 0.0)], start=(3.0, 0.0, 0.0))
    link = _pilot_link()
    link.connect(1.0)
    out = repeat_path(
        link,
        path,
        1,
        learner.make_history_gp(),
        np.full(len(path), 0.5),
        drive_back=DriveBack("turn", 0.5),
    )
    assert out.status == "handed_over" and out.trials == []
    assert "left OFFBOARD for HOLD while driving back" in out.detail
    assert link.after == 0


def _pilot(endpoint: RoverMavlinkEndpoint, legs: list[tuple[float, float, float]]) -> None:
    """A pilot in MANUAL: arm, drive (duration_s, speed, yaw rate) legs, disarm."""
    time.sleep(1.0)
    endpoint.sim.arm()
    for duration, v, w in legs:
        endpoint.sim.set_setpoint(v, w)
        time.sleep(duration)
    endpoint.sim.disarm()


@pytest.mark.slow
def test_a_pilot_driven_teach_is_recorded_until_the_rover_disarms() -> None:
    """Nobody commands the rover over the Link: a pilot drives it in MANUAL from arming to
    disarming, and the teach pass records that drive."""
    port = free_udp_port()
    endpoint = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port, mode="udpout")
    endpoint.start()
    pilot = threading.Thread(
        target=_pilot, args=(endpoint, [(4.0, 0.6, 0.0), (3.0, 0.6, 0.4)]), daemon=True
    )
    pilot.start()
    link = PymavlinkLink(f"udpin://127.0.0.1:{port}")
    try:
        taught = record_teach(link, timeout_s=60.0)
    finally:
        link.close()
        endpoint.close()
    assert taught.ended_for == "the rover disarmed"
    assert 2.5 < taught.path.length_m < 5.0
    assert taught.path.xy_m[-1, 1] > 0.2  # the arc turned left (y is west)


@pytest.mark.slow
def test_a_teach_pass_whose_position_turns_nan_is_refused() -> None:
    port = free_udp_port()
    sim = RoverSim(rover_preset("husky_50kg"))
    endpoint = RoverMavlinkEndpoint(sim, port, mode="udpout")
    endpoint.start()

    def estimator_fails() -> None:
        time.sleep(3.0)
        sim.state = replace(sim.state, x_m=math.nan)

    threading.Thread(target=estimator_fails, daemon=True).start()
    link = PymavlinkLink(f"udpin://127.0.0.1:{port}")
    try:
        with pytest.raises(TeachError, match=r"position is not finite \(NaN\)"):
            record_teach(link, drive=[(20.0, 0.0)], timeout_s=30.0)
    finally:
        link.close()
        endpoint.close()


def test_a_failed_solve_stops_the_rover_in_hold_instead_of_crashing() -> None:
    """A local GP whose kernel matrix cannot be factorised (negative noise variances, as a
    broken hyperparameter file would give) fails the step: the drive says so and the rover is
    sent a zero velocity and Hold."""
    gp = learner.make_history_gp()
    gp.noise_variances = np.full(3, -1.0)
    for vertex in range(4):
        gp.add(vertex, 0.5, np.full(8, 0.1), np.zeros(3))
    link = InProcessRoverLink.from_preset("husky_50kg")
    drive = drive_path(link, TaughtPath.from_segments([(4.0, 0.0)]), 0.5, gp=gp)
    assert drive.stopped_for.startswith("the NMPC solve failed at t=0.0 s")
    assert not drive.reached_end
    assert link.read_state().mode == "HOLD"


def _open_ackermann_path() -> TaughtPath:
    """12 m, open, turning left then right at up to 0.25 1/m: within the 600 kg Ackermann
    rover's tightest turn (tan(0.6) / 2.0 m = 0.34 1/m), its end 11 m from its start."""
    return TaughtPath.from_segments([(3.0, 0.0), (4.0, 0.25), (2.0, 0.0), (3.0, -0.2)])


def _at_the_end(path: TaughtPath, preset: str) -> InProcessRoverLink:
    return InProcessRoverLink(RoverSim(rover_preset(preset), seed=2, pose=path.pose(len(path) - 1)))


@pytest.mark.parametrize("preset", ["dmrv_600kg", "roc6_150kg"])
def test_reversing_along_the_path_brings_any_rover_to_its_start_facing_along_it(
    preset: str,
) -> None:
    path = _open_ackermann_path()
    link = _at_the_end(path, preset)
    assert start_offset(link, path)[0] > 10.0
    assert reverse_along(link, path, 0.5) == ("", "")
    dist, dhead = start_offset(link, path)
    assert dist < 0.08 and abs(dhead) < 0.05  # the start's heading line was the last goal
    assert link.read_state().mode == "HOLD"


class PosesSent(InProcessRoverLink):
    """The in-process rover that keeps its pose (path frame) at each command sent."""

    def __init__(self, sim: RoverSim) -> None:
        super().__init__(sim)
        self.poses: list[np.ndarray] = []

    def send_velocity(self, command) -> None:
        self.poses.append(pose_of(self))
        super().send_velocity(command)


def test_reversing_from_partway_along_the_path_stays_on_it() -> None:
    """A run stopped partway along an out-and-back path (Ctrl-C, a pilot, a lost link) leaves
    the rover 3 m from the start, beside the path's way back: it reverses the 3 m along the
    path. The nearest vertex was looked for only among the last 20, so it took the way back
    beside it for where it was, crossed 1.6 m of ground it had never driven to reach it, and
    reversed along all 18.7 m of the path."""
    path = TaughtPath.from_segments([(8.0, 0.0), (math.pi * 1.5, 1 / 1.5), (6.0, 0.0)])
    link = PosesSent(RoverSim(rover_preset("husky_50kg"), seed=2, pose=path.pose(12)))
    assert reverse_along(link, path, 0.5) == ("", "")
    dist, dhead = start_offset(link, path)
    assert dist < 0.08 and abs(dhead) < 0.05
    poses = np.array(link.poses)
    off_path_m = np.sqrt(np.sum((poses[:, None, :2] - path.xy_m[None]) ** 2, axis=2)).min(axis=1)
    assert off_path_m.max() < 0.2
    assert np.max(poses[:, 0]) < path.xy_m[12, 0] + 0.2  # never further out than it was


def test_the_turn_way_cannot_bring_an_ackermann_rover_back_and_says_to_reverse() -> None:
    """It stops after STALL_S of turning in place without turning, long before its deadline."""
    path = _open_ackermann_path()
    link = _at_the_end(path, "dmrv_600kg")
    t0 = link.clock.now_s()
    left_for, stopped_for = drive_back(link, path.pose(0), 0.5, timeout_s=120.0)
    assert left_for == "" and stopped_for.startswith("the rover does not turn in place")
    assert stopped_for.endswith("--drive-back reverse"), stopped_for
    assert link.clock.now_s() - t0 < STALL_S + 2.0
    assert link.read_state().mode == "HOLD"


def test_an_ackermann_rover_repeats_an_open_path_reversing_back_between_trials() -> None:
    path = _open_ackermann_path()
    sim = RoverSim(rover_preset("dmrv_600kg"), seed=3, pose=path.pose(0))
    link = InProcessRoverLink(sim)
    link.connect(1.0)
    lines: list[str] = []
    out = repeat_path(link, path, 2, learner.make_history_gp(), np.full(len(path), 0.5),
                      drive_back=DriveBack("reverse", 0.5), progress=lines.append)  # fmt: skip
    assert out.status == "completed", out.detail
    assert [t.drive.reached_end for t in out.trials] == [True, True]
    assert any(line.startswith("trial 2: driving back to the start") for line in lines)
    assert max(np.max(np.abs(t.drive.e_lat_m)) for t in out.trials) < 0.1


def test_a_drive_back_says_what_it_cannot_be() -> None:
    with pytest.raises(ValueError, match="by 'sideways'.*one of turn, reverse"):
        DriveBack("sideways", 0.5)
    with pytest.raises(ValueError, match="must be > 0"):
        DriveBack("reverse", 0.0)


class FailingAfter(InProcessRoverLink):
    """The in-process rover whose link fails with ``error`` at the 20th command of a drive."""

    error: BaseException = LinkError("link lost")
    sent = 0

    def send_velocity(self, command) -> None:
        self.sent += 1
        if self.sent == 20:
            raise self.error
        super().send_velocity(command)


def test_a_link_lost_during_the_drive_back_stops_the_rover_and_says_why() -> None:
    link = FailingAfter(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})
    link.connect(1.0)
    assert drive_back(link, (3.0, 1.0, math.pi / 2), 0.5, timeout_s=60.0) == ("", "link lost")
    assert link.read_state().mode == "HOLD"


def test_ctrl_c_during_the_drive_back_stops_the_rover_and_is_raised_on() -> None:
    link = FailingAfter(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})
    link.error = KeyboardInterrupt()
    link.connect(1.0)
    with pytest.raises(KeyboardInterrupt):
        drive_back(link, (3.0, 1.0, math.pi / 2), 0.5, timeout_s=60.0)
    assert link.read_state().mode == "HOLD"


def test_a_drive_back_the_rover_refuses_to_arm_for_is_a_link_error() -> None:
    class NoArming(InProcessRoverLink):
        def arm(self):
            return CommandOutcome(False, "safety switch")

    link = NoArming(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})
    link.connect(1.0)
    with pytest.raises(LinkError, match="rover refused arm: safety switch"):
        drive_back(link, (3.0, 1.0, math.pi / 2), 0.5, timeout_s=60.0)


def test_drive_back_turns_in_place_then_drives_the_straight_line() -> None:
    """To (3, 3) m, 45 degrees off its heading: it faces the target before moving, so its
    track stays on the line from the origin (within a few centimetres), not an arc."""
    track: list[np.ndarray] = []

    class Tracking(InProcessRoverLink):
        def send_velocity(self, command) -> None:
            track.append(pose_of(self)[:2])
            super().send_velocity(command)

    link = Tracking(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})
    link.connect(1.0)
    assert drive_back(link, (3.0, 3.0, 0.0), 0.5, timeout_s=60.0) == ("", "")
    xy = np.array(track)
    off_line = np.abs(xy[:, 0] - xy[:, 1]) / math.sqrt(2.0)  # distance from the line y = x
    assert np.max(off_line) < 0.05


def test_reversing_a_long_path_gets_a_deadline_to_match_its_length() -> None:
    """40 m straight back at 0.5 m/s takes 80 s: the default deadline (3 x 80 s + 30 s)
    lets it get there."""
    path = TaughtPath.from_segments([(40.0, 0.0)], start=(0.0, 0.0, 0.0))
    link = _at_the_end(path, "husky_50kg")
    link.connect(1.0)
    assert reverse_along(link, path, 0.5) == ("", "")
    assert start_offset(link, path)[0] < 0.08


def test_a_drive_back_whose_position_turns_nan_stops_the_rover_and_says_so() -> None:
    """The rover's position estimate fails (NaN) mid-drive: no command is computed from it;
    the rover is stopped in Hold and the reason names the non-finite pose."""

    class LostPosition(InProcessRoverLink):
        reads = 0

        def read_state(self):
            st = super().read_state()
            self.reads += 1
            if self.reads > 30:
                return replace(st, pos_ned_m=np.full(3, np.nan))
            return st

    link = LostPosition(RoverSim(rover_preset("husky_50kg")), {"rover_preset": "husky_50kg"})
    link.connect(1.0)
    left_for, stopped_for = drive_back(link, (3.0, 1.0, math.pi / 2), 0.5, timeout_s=60.0)
    assert left_for == "" and stopped_for.startswith("the rover's pose is not finite")
    assert link.read_state().mode == "HOLD"


def test_a_drive_back_that_ends_away_from_the_start_drives_no_trial() -> None:
    """Reversing along the path ends once the rover is back at the start's arc length; a rover
    beside the start (2 m to its left, half a metre behind it) is there along the path at once,
    yet 2.1 m from the start: the run stops before the trial, saying where the rover is, rather
    than drive the trial from 2 m off the path."""
    path = TaughtPath.from_segments([(5.0, 0.0)])
    link = InProcessRoverLink(RoverSim(rover_preset("husky_50kg"), pose=(-0.5, 2.0, 0.0)))
    link.connect(1.0)
    out = repeat_path(link, path, 1, learner.make_history_gp(), np.full(len(path), 0.5),
                      drive_back=DriveBack("reverse", 0.5))  # fmt: skip
    assert out.status == "not_at_start" and out.trials == [], out.detail
    assert "driving back ended 2.1 m from the path's start" in out.detail
    assert link.read_state().mode == "HOLD"


@pytest.mark.parametrize("glitch", [31, 32])
def test_a_drive_back_steers_by_the_very_state_it_checked(glitch: int) -> None:
    """One state read of the drive back is not finite (a position estimate that glitches for
    one message): whichever read it is, no command is computed from it. The pose was read a
    second time after the finiteness check, so a glitch on that read was steered by: a NaN
    command streamed, or reverse's nearest vertex stuck at the start for the whole drive."""

    class OneGlitch(InProcessRoverLink):
        reads = 0
        sent: list[VelocityCommand] = []

        def read_state(self):
            st = super().read_state()
            self.reads += 1
            return replace(st, pos_ned_m=np.full(3, np.nan)) if self.reads == glitch else st

        def send_velocity(self, command) -> None:
            self.sent.append(command)
            super().send_velocity(command)

    path = _open_ackermann_path()
    link = OneGlitch(RoverSim(rover_preset("husky_50kg"), pose=path.pose(len(path) - 1)))
    link.sent = []
    link.connect(1.0)
    left_for, stopped_for = reverse_along(link, path, 0.5, timeout_s=60.0)
    assert left_for == "" and stopped_for.startswith("the rover's pose is not finite")
    assert all(np.all(np.isfinite([*c.vel_ned_mps, c.yaw_rate_radps])) for c in link.sent)
    assert link.read_state().mode == "HOLD"
