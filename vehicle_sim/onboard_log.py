"""The vehicle's own flight log, as PX4 writes one to its SD card while a companion flies it.

A MAVLink link carries position, velocity and attitude, but not the measured acceleration or
the rotor thrust a diagnosis needs; PX4 logs those on board (ULog) and the user copies the log
off afterwards. :class:`OnboardLogger` does the same for a simulator behind the MAVLink endpoint:
it stands in for the :class:`~vehicle_sim.Simulator` (every attribute is the simulator's), and
records schema-v1 rows (:func:`vehicle_sim.truth_log.truth_row`) as the endpoint steps it.
The command in a row is the last velocity setpoint the vehicle received (what PX4 logs as it
arrives), not the one it acts on after a command delay, and a row's command is the one the
vehicle flew on from that row's time to the next row's, as a replay of the log assumes
(diagnosis.replay). So a row is written just before a step, with the state the step starts
from: when a new setpoint was received (the step is the first to fly it; PX4's velocity
controller likewise acts on a setpoint at a vehicle_local_position update, which is a ULog
row), and otherwise once per logging period, also within a long step of the endpoint's (one
catching up after a stall is flown in parts). Rows fall on physics steps, so their spacing
jitters by up to one, and a setpoint stream faster than the logging rate is
logged at up to twice the rate: a setpoint that arrives sooner than half a period after the
last one logged gets its row at the first step half a period after that one (it has flown
since it arrived; a newer one arriving meanwhile takes the row). Given a
``stream_path``, every row is also appended to the file at once (flightlog.live_log), as PX4
writes its log while it flies: a killed simulator leaves every row logged up to then.
"""

from __future__ import annotations

import math
from pathlib import Path

from flightlog.live_log import LiveFlightLog
from flightlog.schema import FlightLog, FlightLogRecorder, write_flight_log
from vehicle_sim.simulator import Simulator
from vehicle_sim.vehicle_types import VehicleState, VelocitySetpoint

DEFAULT_LOG_RATE_HZ = 50.0


class OnboardLogger:
    """``sim`` with an onboard log at ``rate_hz`` [Hz] of simulated time.

    Owned by whoever steps ``sim`` (the endpoint's thread); :meth:`write` after it stopped.
    """

    def __init__(
        self,
        sim: Simulator,
        rate_hz: float = DEFAULT_LOG_RATE_HZ,
        stream_path: str | Path | None = None,
    ) -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0.0):
            raise ValueError(f"onboard log rate {rate_hz!r} Hz: must be a positive number")
        self._sim = sim
        self._period_s = 1.0 / rate_hz
        self._next_s = -math.inf
        self._last_setpoint_row_s = -math.inf
        self._received: VelocitySetpoint | None = None
        self._fresh = False
        metadata = {**sim.log_metadata(), "rate_hz": rate_hz}
        self._recorder = FlightLogRecorder(metadata)
        self._live = (
            None
            if stream_path is None
            else LiveFlightLog(stream_path, metadata, columns=tuple(sim.log_row(None)))
        )

    def __getattr__(self, name: str) -> object:
        return getattr(self._sim, name)

    def set_velocity_setpoint(self, sp: VelocitySetpoint) -> None:
        """The simulator's; an accepted setpoint becomes the logged command."""
        self._sim.set_velocity_setpoint(sp)
        self._received = sp
        self._fresh = True

    def step(self, duration_s: float) -> VehicleState:
        """The simulator's step, a row before it if one is due (above), and one at each row
        due during it: a long step (the endpoint catching up after a stall) is flown in parts
        that end where the next row is due, as PX4 logs on at its rate whatever its link does.
        """
        dt_s = self._sim.physics_dt_s
        remaining = round(duration_s / dt_s) if math.isfinite(duration_s) else 0
        while True:
            self._row_if_due()
            steps_to_row = max(1, math.ceil((self._next_s - self._sim.t_s) / dt_s - 1e-6))
            if remaining <= steps_to_row:
                return self._sim.step(duration_s if remaining <= 0 else remaining * dt_s)
            self._sim.advance(steps_to_row * dt_s)
            remaining -= steps_to_row

    def _row_if_due(self) -> None:
        t_s = self._sim.t_s
        if self._fresh and t_s - self._last_setpoint_row_s >= 0.5 * self._period_s:
            self._log_row()
            self._last_setpoint_row_s = t_s
            self._next_s = t_s + self._period_s
        elif t_s >= self._next_s:
            self._log_row()
            due_s = self._next_s + self._period_s
            self._next_s = due_s if due_s > t_s else t_s + self._period_s

    def _log_row(self) -> None:
        row = self._sim.log_row(self._received)
        self._recorder.append(row)
        if self._live is not None:
            self._live.append(row)
        self._fresh = False

    def to_log(self) -> FlightLog:
        """The rows so far as a flight log."""
        return self._recorder.to_log()

    def write(self, path: Path) -> Path:
        """Write the log (CSV and metadata sidecar, atomically; over the streamed rows when
        ``path`` is the stream's); returns the CSV path."""
        if self._live is not None and Path(path) == self._live.path:
            return self._live.finish(self.to_log())
        return write_flight_log(path, self.to_log())
