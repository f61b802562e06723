"""read_ulog_track on the real PX4 logs of tests/fixtures/ulog and on damaged copies: the
local xy track, arming and origin of any vehicle, as pyulog reads them."""

from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from flightlog.schema import FlightLogError
from flightlog.ulog import summarise_ulog
from flightlog.ulog_track import read_ulog_track
from tests.flightlog.ulog_damage import FIXTURES, POSCTL, corrupt_copy


def test_the_track_is_the_logged_local_position_from_the_log_start() -> None:
    track = read_ulog_track(POSCTL)
    pos = ULog(str(POSCTL), message_name_filter_list=["vehicle_local_position"]).get_dataset(
        "vehicle_local_position"
    )
    np.testing.assert_array_equal(track.pos_ne_m[:, 0], pos.data["x"])
    np.testing.assert_array_equal(track.pos_ne_m[:, 1], pos.data["y"])
    assert track.t_s[0] == pytest.approx(0.0, abs=0.1)
    assert track.duration_s == pytest.approx(76.1, abs=0.1)
    assert track.xy_valid.all() and track.vehicle == "quadrotor" and track.damage is None


@pytest.mark.parametrize(
    ("name", "spans"),
    [
        ("quad_posctl_v1_15.ulg", [(0.0, 75.1)]),  # armed before logging, disarmed at the end
        ("quad_sitl_v1_15_auto.ulg", [(14.9, 30.1)]),  # armed after the log starts
        ("quad_manual_v1_6.ulg", []),  # never armed
    ],
)
def test_armed_spans_from_vehicle_status(name: str, spans: list[tuple[float, float]]) -> None:
    got = read_ulog_track(FIXTURES / name).armed_spans_s
    assert got is not None and len(got) == len(spans)
    np.testing.assert_allclose(np.array(got).reshape(-1, 2), np.array(spans).reshape(-1, 2),
                               atol=0.05)  # fmt: skip


def test_times_count_from_the_start_flightlog_info_gives_the_log() -> None:
    """The mission log's first position comes 0.5 s after its first other data: the track
    counted from there, so --start-s read off `flightlog info`'s modes was 0.5 s off."""
    path = FIXTURES / "quad_mission_rtl_v1_9_esc.ulg"
    track, info = read_ulog_track(path), summarise_ulog(path)
    assert track.duration_s == pytest.approx(info["duration_s"], abs=1e-9)
    assert track.t_s[0] == pytest.approx(0.51, abs=0.01)


def test_origin_only_where_the_log_has_a_global_reference() -> None:
    lat, lon = read_ulog_track(FIXTURES / "quad_sitl_v1_15_auto.ulg").origin_deg
    assert (lat, lon) == pytest.approx((47.3977, 8.5456), abs=1e-3)  # PX4 SITL's Zurich home
    assert read_ulog_track(POSCTL).origin_deg is None


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda tmp: FIXTURES / "fixedwing_v1_17rc_status.ulg", "holds no vehicle_local_position"),
        (lambda tmp: tmp / "missing.ulg", "no such file"),
        (lambda tmp: tmp, "a folder, not a flight log; pass a PX4 .ulg in it"),
        (lambda tmp: Path(__file__), "not a ULog file"),
        (lambda tmp: _head(tmp, 3000), "truncated at byte 2853 and holds no local position"),
    ],
)
def test_refusals_are_one_line_with_the_fix(tmp_path: Path, make, message: str) -> None:
    with pytest.raises(FlightLogError, match=message) as err:
        read_ulog_track(make(tmp_path))
    assert "\n" not in str(err.value)


def test_a_log_without_read_access_is_not_called_no_ulog(tmp_path: Path, monkeypatch) -> None:
    """A .ulg copied off the SD card by root cannot be opened by its user: is_ulog reads no
    magic bytes there, and the refusal said 'not a ULog file ... copy the .ulg again'."""
    log = tmp_path / "root_only.ulg"
    log.write_bytes(POSCTL.read_bytes()[:100])
    real_open = Path.open

    def denied(self: Path, *args, **kwargs):
        if self == log:
            raise PermissionError(13, "Permission denied")
        return real_open(self, *args, **kwargs)

    monkeypatch.setattr(Path, "open", denied)
    with pytest.raises(
        FlightLogError,
        match=r"root_only.ulg: cannot read it \(Permission denied\); "
        r"make it readable to you \(chown or chmod",
    ) as err:
        read_ulog_track(log)
    assert "\n" not in str(err.value)


def test_a_damaged_log_is_read_as_far_as_it_goes_and_says_so(tmp_path: Path) -> None:
    damaged, offset = corrupt_copy(tmp_path, "type")
    track = read_ulog_track(damaged)
    assert f"corrupt at byte {offset}" in track.damage and len(track.t_s) > 100
    cut = read_ulog_track(_head(tmp_path, 550_000))
    assert "is truncated" in cut.damage and cut.duration_s < 45.0


def _head(tmp: Path, size: int) -> Path:
    """The first ``size`` bytes of the POSCTL fixture, as a log cut by a power loss."""
    path = tmp / f"cut_{size}.ulg"
    path.write_bytes(POSCTL.read_bytes()[:size])
    return path


def test_the_estimators_accuracy_and_position_resets_are_read_as_logged() -> None:
    path = FIXTURES / "quad_sitl_v1_15_auto.ulg"  # one reset of the horizontal position
    track = read_ulog_track(path)
    pos = ULog(str(path), message_name_filter_list=["vehicle_local_position"]).get_dataset(
        "vehicle_local_position"
    )
    np.testing.assert_array_equal(track.eph_m, pos.data["eph"])
    counter = pos.data["xy_reset_counter"].astype(int)
    at = [i for i in range(1, len(counter)) if counter[i] != counter[i - 1]]
    assert [t for t, _ in track.xy_resets] == pytest.approx(track.t_s[at].tolist())
    shifts = [np.hypot(pos.data["delta_xy[0]"][i], pos.data["delta_xy[1]"][i]) for i in at]
    assert [m for _, m in track.xy_resets] == pytest.approx(shifts)
    assert len(at) == 1 and read_ulog_track(POSCTL).xy_resets == ()


def test_a_board_with_no_airframe_set_is_not_called_a_generic_vehicle(tmp_path: Path) -> None:
    """SYS_AUTOSTART 0 and MAV_TYPE 0 are PX4's defaults on a board never given an airframe:
    MAV_TYPE 0 says nothing of the vehicle there, as flightlog info says."""
    ulog = ULog(str(POSCTL))
    ulog.initial_parameters.update({"SYS_AUTOSTART": 0, "MAV_TYPE": 0})
    ulog.write_ulog(str(tmp_path / "no_airframe.ulg"))
    assert read_ulog_track(tmp_path / "no_airframe.ulg").vehicle == "no airframe set"
    ulog.initial_parameters["SYS_AUTOSTART"] = 4001
    ulog.write_ulog(str(tmp_path / "generic.ulg"))
    assert read_ulog_track(tmp_path / "generic.ulg").vehicle == "generic vehicle"


def test_a_sample_of_garbage_gives_no_reset_and_no_origin(tmp_path: Path) -> None:
    """A damaged log's bytes read as one vehicle_local_position sample: rover-path printed a
    reset by 3.7e37 m (and one more as the counter came back) and an origin at -4.8e240 deg."""
    ulog = ULog(str(FIXTURES / "quad_sitl_v1_15_auto.ulg"))
    (pos,) = [d for d in ulog.data_list if d.name == "vehicle_local_position"]
    data = pos.data
    i = len(data["timestamp"]) // 2
    data["delta_xy[0]"][i], data["ref_lat"][i], data["ref_lon"][i] = 3.7e37, -4.8e240, 1e-299
    data["xy_reset_counter"][i] += 7
    data["xy_global"][-1] = 0  # the origin is known up to the sample before the last
    data["ref_lat"][-2] = np.inf
    ulog.write_ulog(str(tmp_path / "garbage.ulg"))
    track = read_ulog_track(tmp_path / "garbage.ulg")
    clean = read_ulog_track(FIXTURES / "quad_sitl_v1_15_auto.ulg")
    assert track.xy_resets == clean.xy_resets and len(clean.xy_resets) == 1
    assert track.origin_deg == (data["ref_lat"][-3], data["ref_lon"][-3])
