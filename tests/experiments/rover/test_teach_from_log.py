"""teach_from_track: the taught path of a recorded drive, on the real PX4 logs of
tests/fixtures/ulog (multirotors: their local xy track is still a recorded track) and on drives
built to hold one stop, corner or reversal each."""

import dataclasses
import re

import numpy as np
import pytest

from experiments.rover.path_start import is_loop
from experiments.rover.teach import TeachError
from experiments.rover.teach_from_log import teach_from_track
from flightlog.ulog_track import ULogTrack, read_ulog_track
from planners.rover.path import TaughtPath
from tests.flightlog.ulog_damage import FIXTURES, POSCTL

RATE_HZ = 10.0


def _track(
    legs: list[tuple[float, float, float]],
    armed: list[tuple[float, float]] | None = None,
    noise_m: float = 0.0,
) -> ULogTrack:
    """A drive at RATE_HZ from the origin: legs of (north_mps, east_mps, duration_s), with
    seeded position noise of ``noise_m``; armed throughout unless ``armed`` says otherwise."""
    v = np.concatenate([np.tile([vn, ve], (int(d * RATE_HZ), 1)) for vn, ve, d in legs])
    ne = np.vstack([[0.0, 0.0], np.cumsum(v / RATE_HZ, axis=0)])
    ne += np.random.default_rng(3).normal(0.0, noise_m, ne.shape)
    t = np.arange(len(ne)) / RATE_HZ
    spans = [(0.0, float(t[-1]))] if armed is None else armed
    return ULogTrack("drive.ulg", t, ne, np.ones(len(t), bool), float(t[-1]), spans, None,
                     "ground rover", None)  # fmt: skip


def test_a_real_log_gives_the_path_in_the_live_teach_frame() -> None:
    track = read_ulog_track(POSCTL)
    taught = teach_from_track(track)
    path = taught.path
    assert (len(path), round(path.length_m, 1), is_loop(path)) == (53, 12.9, False)
    assert taught.span_from == "armed" and taught.span_s == pytest.approx((0.0, 75.1), abs=0.05)
    north_west = np.column_stack([track.pos_ne_m[:, 0], -track.pos_ne_m[:, 1]])
    np.testing.assert_allclose(path.xy_m[0], north_west[0], atol=1e-9)
    gap = np.min(np.linalg.norm(path.xy_m[:, None] - north_west[None], axis=2), axis=1)
    assert gap.max() < 0.1  # every vertex on the flown track (x north, y west), not mirrored


def test_a_stop_with_the_estimate_wandering_adds_nothing() -> None:
    straight = teach_from_track(_track([(0.5, 0.0, 10.0), (0.5, 0.0, 10.0)]))
    stopped = teach_from_track(
        _track([(0.5, 0.0, 10.0), (0.0, 0.0, 60.0), (0.5, 0.0, 10.0)], noise_m=0.02)
    )
    north, west = stopped.path.xy_m.T
    assert np.all(np.diff(north) > 0.2) and np.abs(west).max() < 0.1  # no tangle at the stop
    assert stopped.path.length_m == pytest.approx(straight.path.length_m, abs=0.25)


def test_a_corner_turned_after_a_stop_is_a_path() -> None:
    corner = teach_from_track(_track([(0.5, 0.0, 6.0), (0.0, 0.0, 5.0), (0.0, 0.5, 6.0)]))
    assert corner.path.length_m == pytest.approx(6.0, abs=0.3)


def test_backing_up_is_refused_naming_the_one_way_stretch_that_teaches() -> None:
    track = _track([(0.5, 0.0, 10.0), (0.0, 0.0, 2.0), (-0.5, 0.0, 6.0)])
    with pytest.raises(TeachError, match=r"turns back on itself at t=(9|10)\.\d s \(by 180 deg"):
        teach_from_track(track)
    try:
        teach_from_track(track)
    except TeachError as exc:
        start, end = map(float, re.search(r"--start-s (\S+) --end-s (\S+),", str(exc)).groups())
    assert teach_from_track(track, 0.25, start, end).path.length_m == pytest.approx(5.0, abs=0.3)
    shuttle = _track([(0.5, 0.0, 1.6), (-0.5, 0.0, 1.2), (0.5, 0.0, 1.6)])
    too_short = r"no stretch between its turns gives a path \(the longest: 0\.8 m\)"
    with pytest.raises(TeachError, match=too_short):
        teach_from_track(shuttle)


def test_a_real_flight_out_and_back_is_refused() -> None:
    track = read_ulog_track(FIXTURES / "quad_offboard_v1_16.ulg")
    said = r"0\.0-61\.3 s: the drive turns back on itself at t=19.*no stretch between its turns"
    with pytest.raises(TeachError, match=said):
        teach_from_track(track)  # 1.4 m out, a hover, 1.4 m back: no stretch gives a path


def test_the_longest_one_way_stretch_of_a_real_flight_teaches() -> None:
    track = read_ulog_track(FIXTURES / "quad_mission_rtl_v1_9_esc.ulg")
    with pytest.raises(TeachError, match=r"at t=21\.5 s .* --start-s 1\.2 --end-s 21\.4, its"):
        teach_from_track(track)  # the mission, then a sharp turn into the return
    path = teach_from_track(track, 0.25, 1.2, 21.4).path
    assert (len(path), round(path.length_m, 1)) == (301, 75.0)


def test_a_span_without_motion_is_refused_as_a_live_teach_is() -> None:
    hover = read_ulog_track(FIXTURES / "quad_offboard_v1_16.ulg")
    with pytest.raises(TeachError, match=r"moved 0\.00 m .* at least 1 m: pass --start-s"):
        teach_from_track(hover, 0.25, 0.0, 15.0)


@pytest.mark.parametrize(
    ("start_s", "end_s", "message"),
    [
        (100.0, None, r"--start-s 100 is outside quad_posctl_v1_15.ulg \(76.1 s of data\)"),
        (None, 80.0, r"--end-s 80 is past the end of .*leave --end-s out"),
        (30.0, 20.0, r"--end-s 20 is not after --start-s 30"),
        (None, 0.0, r"^--end-s 0 is the log's start; pass one after 0$"),
        (10.0, 10.05, r"no position sample in the span \(the log's 762 lie from 0\.0 to 76\.1 s\); "
         r"pass --start-s/--end-s around the drive \(armed: 0\.0-75\.1 s\)"),
    ],
)  # fmt: skip
def test_a_span_outside_the_log_is_refused(start_s, end_s, message: str) -> None:
    with pytest.raises(TeachError, match=message):
        teach_from_track(read_ulog_track(POSCTL), 0.25, start_s, end_s)


def test_which_span_without_start_and_end() -> None:
    legs = [(0.0, 0.0, 5.0), (0.5, 0.0, 4.0), (0.0, 0.0, 5.0), (0.0, 0.5, 10.0)]
    twice = teach_from_track(_track(legs, armed=[(1.0, 12.0), (14.0, 24.0)]))
    assert twice.span_s == (14.0, 24.0)  # the second: 5 m driven, against 2 m
    assert (
        "armed 2 times (1.0-12.0 s, 14.0-24.0 s); taught the one driven farthest" in twice.notes[0]
    )
    unlogged = teach_from_track(_unarmed(legs))
    assert unlogged.span_from == "whole log" and "does not log arming" in unlogged.notes[0]
    with pytest.raises(TeachError, match="never armed; pass --start-s and --end-s"):
        teach_from_track(_track(legs, armed=[]))


def _unarmed(legs: list[tuple[float, float, float]]) -> ULogTrack:
    """:func:`_track` of a log without vehicle_status (arming not logged)."""
    track = _track(legs)
    return ULogTrack(**{**track.__dict__, "armed_spans_s": None})


def test_invalid_positions_are_left_out_and_a_nan_one_is_refused() -> None:
    track = _track([(0.5, 0.0, 10.0)])
    valid = track.xy_valid.copy()
    valid[40:50] = False
    gap = teach_from_track(ULogTrack(**{**track.__dict__, "xy_valid": valid}))
    assert "10 of 101 position samples" in gap.notes[0]
    assert gap.path.length_m == pytest.approx(5.0, abs=0.25)  # ends within a spacing
    ne = track.pos_ne_m.copy()
    ne[[40, 47]] = np.nan
    with pytest.raises(
        TeachError, match=r"not finite \(NaN\) in 2 of 101 samples, from t=4\.0 to 4\.7 s"
    ):
        teach_from_track(ULogTrack(**{**track.__dict__, "pos_ne_m": ne}))
    with pytest.raises(TeachError, match=r"in 101 of 101 samples, .*; teach another span \("):
        teach_from_track(ULogTrack(**{**track.__dict__, "pos_ne_m": ne * np.nan}))


def test_a_log_without_a_position_estimate_is_refused() -> None:
    with pytest.raises(TeachError, match="invalid throughout the log .*no GPS fix"):
        teach_from_track(read_ulog_track(FIXTURES / "quad_stab_nogps_v1_16_1.ulg"))


def test_the_path_is_resampled_as_a_live_teach_resamples() -> None:
    arc = TaughtPath.from_segments([(2.0, 0.0), (np.pi, 0.5), (2.0, 0.0)], spacing_m=0.01)
    north_east = arc.xy_m * [1.0, -1.0]
    t = np.arange(len(arc)) / 50.0  # 0.5 m/s at 50 Hz
    track = ULogTrack("arc.ulg", t, north_east, np.ones(len(t), bool), float(t[-1]),
                      [(0.0, float(t[-1]))], None, None, None)  # fmt: skip
    taught = teach_from_track(track, 0.25).path
    live = TaughtPath.from_drive(arc.xy_m, 0.25)
    assert len(live) - len(taught) in (0, 1)  # it ends within a spacing of the drive's end
    assert taught.spacing_m == pytest.approx(0.25, abs=0.01)
    gap = np.min(np.linalg.norm(taught.xy_m[:, None] - arc.xy_m[None], axis=2), axis=1)
    assert gap.max() < 0.01  # on the driven arc: x north, y west


def test_a_failing_estimators_accuracy_is_said_beside_the_path() -> None:
    failing = teach_from_track(read_ulog_track(FIXTURES / "quad_posctl_ekf_fail_v1_15.ulg"), 0.25,
                               0.1, 71.9)  # fmt: skip
    eph = [n for n in failing.notes if "horizontal accuracy (eph)" in n]
    assert len(eph) == 1 and float(re.search(r"reached ([\d.]+) m", eph[0])[1]) > 1.0
    assert not teach_from_track(read_ulog_track(POSCTL)).notes  # eph 3 cm: nothing to say


def test_a_reset_of_the_position_in_the_span_is_said_a_tiny_or_outside_one_is_not() -> None:
    rng = np.random.default_rng(7)
    t_reset, shift_m = float(rng.uniform(4.0, 14.0)), float(rng.uniform(0.3, 2.0))
    drive = _track([(0.5, 0.0, 20.0)])
    resets = ((t_reset, shift_m), (t_reset + 0.5, 0.01), (40.0, 3.0))  # big, tiny, after
    taught = teach_from_track(dataclasses.replace(drive, xy_resets=resets))
    (note,) = [n for n in taught.notes if "reset" in n]
    assert f"1 time in the span (the largest by {shift_m:.2f} m at t={t_reset:.1f} s)" in note
    assert not teach_from_track(drive).notes
