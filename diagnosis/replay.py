"""Replay logged setpoints through the simulation from measured states, in short windows.

A simulated vehicle of the config (a copy of a hovering template) follows each log: at every
row it is put into the measured state (``Simulator.anchor``) while its flight control runs on the
logged setpoint, so its controller state (velocity and rate integrals, delayed setpoints in
flight, rotor speeds, yaw setpoint) builds up as the measured vehicle's did, from the velocity
integral the vehicle had at the start of each airborne run, fitted to the run's first
``LEAD_IN_S`` (the warm-up, :mod:`.warm_up`); windows start after that. At each window's anchor
row a copy of it flies free for ``window_s`` on the logged setpoints; the error is simulated
minus measured velocity, after the part that an error in the run's start integral and in each
anchor's measured velocity explain (:mod:`.window_nuisance`: neither is the config's to
answer for).
"""

from __future__ import annotations

import copy
import math
import weakref
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from diagnosis import sim_anchor
from diagnosis.warm_up import LEAD_IN_S, start_integral
from diagnosis.window_nuisance import RunNuisance
from flightlog.schema import FlightLog
from vehicle_sim import AnchorState, CheckedSetpoint, SimConfig, Simulator, VelocitySetpoint

STATE_COLUMNS = (
    "pos_n_m", "pos_e_m", "pos_d_m", "vel_n_mps", "vel_e_mps", "vel_d_mps",
    "q_w", "q_x", "q_y", "q_z",
)  # fmt: skip
RATE_COLUMNS = ("rate_x_radps", "rate_y_radps", "rate_z_radps")
CMD_COLUMNS = ("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")
ACC_COLUMNS = ("acc_n_mps2", "acc_e_mps2", "acc_d_mps2")
MIN_REPLAY_ALT_M = 0.02
MAX_ROW_GAP_S = 0.5  # rows further apart than this (dropped rows between) end a replay run


@dataclass(frozen=True)
class Window:
    """Free flight over rows [anchor, stop) of log ``log_index``; ``t_anchor_s`` since its start."""

    log_index: int
    anchor: int
    stop: int
    t_anchor_s: float


@dataclass(frozen=True)
class ReplayResult:
    """Replay of some windows.

    Attributes:
        t_s: (m,) log time of each compared row [s].
        sim_vel_ned_mps, meas_vel_ned_mps: (m, 3) simulated and measured velocity NED
            [m/s]; the simulated one with its run's nuisance added (what an error in the run's
            start integral and in each anchor's measured velocity explain,
            :mod:`.window_nuisance`), so their difference is what the config leaves.
        window: (m,) index of the window each row belongs to.
    """

    t_s: np.ndarray
    sim_vel_ned_mps: np.ndarray
    meas_vel_ned_mps: np.ndarray
    window: np.ndarray

    def rmse_mps(self) -> float:
        """RMS over rows of the 3-D velocity error [m/s]."""
        if len(self.t_s) == 0:
            return float("nan")
        err = self.sim_vel_ned_mps - self.meas_vel_ned_mps
        return float(np.sqrt(np.mean(np.sum(err * err, axis=1))))


def airborne_runs(log: FlightLog) -> list[tuple[int, int]]:
    """[start, stop) row ranges in which the vehicle is airborne throughout, the logged command
    drives it, and no two rows are more than ``MAX_ROW_GAP_S`` apart.

    The command drives the vehicle in OFFBOARD for the project's own logs (a ``mode`` column
    other than OFFBOARD means the autopilot flew itself). A PX4 ULog's mapping keeps only rows
    in position-controlled modes, where the command is the setpoint PX4's velocity controller
    was given (POSCTL, AUTO.*, OFFBOARD), so every kept row counts; rows it dropped (estimator
    invalid, other modes) leave gaps, which end a run.
    """
    air = -log["pos_d_m"] > MIN_REPLAY_ALT_M
    if log.has("mode") and log.metadata.get("source") != "px4_ulog":
        air &= np.char.upper(log["mode"].astype(str)) == "OFFBOARD"
    gap_before = np.r_[False, np.diff(log["t_s"]) > MAX_ROW_GAP_S]
    runs = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], air.astype(int), [0]])))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        cuts = [a, *(a + 1 + np.flatnonzero(gap_before[a + 1 : b])).tolist(), b]
        runs += [(int(c), int(d)) for c, d in zip(cuts[:-1], cuts[1:], strict=True) if d > c]
    return runs


def windows(logs: Sequence[FlightLog], window_s: float = 2.0) -> list[Window]:
    """Consecutive windows of ``window_s`` [s] over the airborne runs of every log (ValueError
    unless ``window_s`` is a finite number > 0)."""
    if not (math.isfinite(window_s) and window_s > 0.0):
        raise ValueError(f"replay window {window_s!r} s: must be a finite number of seconds > 0")
    out = []
    for i, log in enumerate(logs):
        t = log["t_s"]
        for run_start, run_stop in airborne_runs(log):
            anchor = int(np.searchsorted(t, t[run_start] + LEAD_IN_S))
            while anchor < run_stop:  # a run within LEAD_IN_S of the log's end has no anchor
                stop = int(np.searchsorted(t, t[anchor] + window_s))
                if stop >= run_stop:
                    break
                out.append(Window(i, anchor, stop, float(t[anchor] - t[0])))
                anchor = stop
    return out


def replay(
    sim_config: SimConfig, logs: Sequence[FlightLog], wins: Sequence[Window]
) -> ReplayResult:
    """Replay ``wins`` of ``logs`` through a vehicle of ``sim_config``."""
    flown = list(_flown_windows(sim_config, logs, wins))
    if not flown:
        return ReplayResult(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, int))
    runs: dict[int, RunNuisance] = {}
    for f in flown:
        runs.setdefault(f.run, RunNuisance(sim_config)).add(f.tau_s, f.sim_vel_ned_mps, f.meas)
    fitted = {run: iter(nuisance.fitted()) for run, nuisance in runs.items()}
    return ReplayResult(
        np.concatenate([f.t_s for f in flown]),
        np.vstack([next(fitted[f.run]) for f in flown]),
        np.vstack([f.meas for f in flown]),
        np.concatenate([np.full(len(f.t_s), f.window) for f in flown]),
    )


def replay_sse(
    sim_config: SimConfig, logs: Sequence[FlightLog], wins: Sequence[Window], above: float
) -> float:
    """Sum over rows of the squared 3-D velocity error [m^2/s^2] that :func:`replay` gives, or
    ``inf`` as soon as the windows flown so far exceed ``above``: a search that only needs the
    best of several configs stops replaying one that can no longer be it (the sum only grows
    with each window, its run's nuisance refitted included, :class:`.RunNuisance`; every
    config is replayed on the same rows)."""
    done, run, nuisance = 0.0, None, None
    for flown in _flown_windows(sim_config, logs, wins):
        if flown.run != run:
            done += nuisance.sse() if nuisance is not None else 0.0
            run, nuisance = flown.run, RunNuisance(sim_config)
        nuisance.add(flown.tau_s, flown.sim_vel_ned_mps, flown.meas)
        if done + nuisance.sse() > above:
            return math.inf
    return done + (nuisance.sse() if nuisance is not None else 0.0)


@dataclass(frozen=True)
class _Flown:
    """One window flown free: ``window`` (index into the windows given), ``run`` (its airborne
    run's number among those flown), and per compared row (m,) its log time [s] and time since
    the anchor ``tau_s`` [s], (m, 3) simulated and measured velocity NED [m/s] (before the
    run's nuisance is taken out)."""

    window: int
    run: int
    t_s: np.ndarray
    tau_s: np.ndarray
    sim_vel_ned_mps: np.ndarray
    meas: np.ndarray


def _flown_windows(
    sim_config: SimConfig, logs: Sequence[FlightLog], wins: Sequence[Window]
) -> Iterator[_Flown]:
    """Each of ``wins`` flown free from its anchor row, log by log and in row order (the
    anchored follower running along each airborne run, as the module docstring says)."""
    template = sim_anchor.hovering_template(sim_config)
    run = -1
    for i, log in enumerate(logs):
        a = LogArrays.of(log)
        mine = {w.anchor: (k, w) for k, w in enumerate(wins) if w.log_index == i}
        for run_start, run_stop in airborne_runs(log):
            if not any(run_start <= anchor < run_stop for anchor in mine):
                continue
            follower = sim_anchor.fresh_copy(template)
            first = a.anchor(run_start, lead=True)
            follower.anchor(first, integral="reset")
            follower.set_velocity_setpoint(a.setpoint[run_start])
            lead_stop = int(np.searchsorted(a.t, a.t[run_start] + LEAD_IN_S))
            warm_up = slice(run_start, lead_stop)
            follower.set_velocity_integral(
                start_integral(
                    follower, first, a.t[run_start : lead_stop + 1], a.setpoint[warm_up],
                    a.state[run_start + 1 : lead_stop + 1, 3:6],
                )
            )  # fmt: skip
            last = max(w.stop for w in wins if w.log_index == i and w.anchor < run_stop)
            run += 1
            forks = sorted(j for j in mine if run_start <= j < last)
            # the lead-in's rows (anchored with thrust and acceleration) apart from the rest
            start, resumed = min(lead_stop, forks[0]), False
            _follow(follower, a, run_start, start, lead_stop, resumed)
            for fork in forks:
                _follow(follower, a, start, fork, lead_stop, resumed)
                follower.set_velocity_setpoint(a.setpoint[fork])
                follower.anchor(a.anchor(fork, lead=fork < lead_stop), integral="keep")
                k, w = mine[fork]
                sim = (
                    sim_anchor.fresh_copy(follower)
                    .stream_setpoints(
                        [None, *a.setpoint[w.anchor + 1 : w.stop]],
                        np.diff(a.t[w.anchor : w.stop + 1]),
                    )
                    .vel_ned_mps
                )
                rows = slice(w.anchor + 1, w.stop + 1)
                tau = a.t[rows] - a.t[w.anchor]
                yield _Flown(k, run, a.t[rows], tau, sim, a.state[rows, 3:6])
                start, resumed = fork, True
            _follow(follower, a, start, last, lead_stop, resumed)


def _follow(
    follower: Simulator, a: LogArrays, start: int, stop: int, lead_stop: int, resumed: bool
) -> None:
    """The anchored follower along rows [start, stop): each row's logged setpoint, then its
    measured state (with thrust and acceleration before ``lead_stop``), then the row's
    interval; ``resumed``: row ``start``'s setpoint and state are already given."""
    rows = range(start, stop)
    skip = start if resumed else -1
    follower.stream_setpoints(
        [None if r == skip else a.setpoint[r] for r in rows],
        np.diff(a.t[start : stop + 1]),
        [None if r == skip else a.anchor(r, lead=r < lead_stop) for r in rows],
    )


class LogArrays:
    """The columns a replay reads, as plain arrays (n rows), and the anchor states of its rows.

    Every replay, thrust tracking and closed-loop run of a diagnosis reads the same logs: get
    them with :meth:`of`, which builds them once per log (logs are never changed in place), and
    the :class:`AnchorState` of each row once (it is immutable).
    """

    _by_log: dict[int, LogArrays] = {}

    def __init__(self, log: FlightLog) -> None:
        n = log.n_rows
        rates = log.stack(*RATE_COLUMNS) if log.has(*RATE_COLUMNS) else np.zeros((n, 3))
        self.t = log["t_s"]
        self.state = np.hstack([log.stack(*STATE_COLUMNS), rates])
        self.setpoint = [
            _setpoint(tuple(float(v) for v in row), float(yaw_rate))
            for row, yaw_rate in zip(
                log.stack(*CMD_COLUMNS), log["cmd_yaw_rate_radps"], strict=True
            )
        ]
        self.thrust = log["thrust_n"] if log.has("thrust_n") else np.zeros(n)
        self.acc = log.stack(*ACC_COLUMNS) if log.has(*ACC_COLUMNS) else np.zeros((n, 3))
        self._anchors: dict[tuple[int, bool], AnchorState] = {}
        self._noisy: dict[tuple[float, ...], LogArrays] = {}

    @classmethod
    def of(cls, log: FlightLog) -> LogArrays:
        """The arrays of ``log``, built at its first use and kept while ``log`` lives."""
        arrays = cls._by_log.get(id(log))
        if arrays is None:
            arrays = cls._by_log[id(log)] = cls(log)
            weakref.finalize(log, cls._by_log.pop, id(log), None)
        return arrays

    def with_velocity_noise(self, std_mps: np.ndarray, seed: int) -> LogArrays:
        """A copy whose measured velocity has white Gaussian noise of std ``std_mps`` (3,)
        [m/s] added, drawn with ``seed`` (the same draw for the same seed; kept for reuse)."""
        key = (seed, *(float(v) for v in std_mps))
        noisy = self._noisy.get(key)
        if noisy is None:
            noisy = self._noisy[key] = copy.copy(self)
            rng = np.random.default_rng(seed)
            noisy.state = self.state.copy()
            noisy.state[:, 3:6] += rng.normal(size=(len(self.t), 3)) * np.asarray(std_mps)
            noisy._anchors, noisy._noisy = {}, {}
        return noisy

    def anchor(self, j: int, lead: bool) -> AnchorState:
        """The measured state of row ``j``; during the lead-in with its thrust and acceleration
        (thrust 0 = not logged: rotor speeds are kept)."""
        key = (j, lead)
        state = self._anchors.get(key)
        if state is None:
            s = self.state[j]
            state = self._anchors[key] = AnchorState(
                pos_ned_m=s[0:3],
                vel_ned_mps=s[3:6],
                q_wxyz=s[6:10],
                rates_frd_radps=s[10:13],
                thrust_n=float(self.thrust[j]) if lead else None,
                acc_ned_mps2=self.acc[j] if lead else None,
            )
        return state


def _setpoint(vel_ned_mps: tuple[float, ...], yaw_rate_radps: float) -> VelocitySetpoint:
    """A logged command as the setpoint replays set, checked once here (a replay sets each
    one thousands of times); one the vehicle refuses stays unchecked, to be refused when set."""
    try:
        return CheckedSetpoint(vel_ned_mps, yaw_rate_radps)
    except ValueError:
        return VelocitySetpoint(vel_ned_mps, yaw_rate_radps)
