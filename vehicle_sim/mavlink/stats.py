"""Counters of what an endpoint received, rejected and sent (read by tests and benchmarks)."""

from __future__ import annotations

import threading
from dataclasses import dataclass, fields


@dataclass(frozen=True)
class EndpointStats:
    """A snapshot of an endpoint's counters (all counts since start).

    Attributes:
        datagrams_received: UDP datagrams read from all links.
        messages_received: well-formed MAVLink messages decoded from them.
        garbage_datagrams: datagrams holding no well-formed message at all.
        bad_frames: bad prefixes, lengths, CRCs or unknown message ids.
        truncated_datagrams: datagrams that ended inside a frame.
        signing_rejected: messages refused on a signed link (unsigned or bad signature).
        wrong_target: messages addressed to another system or component, ignored.
        commands_received: COMMAND_LONG/COMMAND_INT for us (each answered with an ACK).
        commands_unsupported: of those, answered UNSUPPORTED.
        setpoints_accepted: SET_POSITION_TARGET_LOCAL_NED passed to the simulator.
        setpoints_rejected: setpoints refused (frame, type_mask, NaN, absurd values).
        manual_control_accepted: MANUAL_CONTROL sticks passed to the simulator.
        manual_control_rejected: MANUAL_CONTROL dropped (an axis marked invalid, or stick
            input disabled by COM_RC_IN_MODE).
        params_unknown: parameter requests for unknown names or indices.
        handler_errors: messages whose handling raised (the loop kept running).
        messages_sent: MAVLink messages sent (one per peer).
        send_errors: sends that failed at the socket.
        notices_sent: STATUSTEXT messages queued for broadcast.
        notices_suppressed: repeated STATUSTEXTs dropped by the rate limit.
        loop_overruns: times the sim fell more than ``max_lag_s`` behind wall time and the
            excess was dropped.
        caught_up_ms: simulated time stepped to catch up after the loop was stalled (more
            than one pass behind wall time, or a datagram read late) [ms].
    """

    datagrams_received: int = 0
    messages_received: int = 0
    garbage_datagrams: int = 0
    bad_frames: int = 0
    truncated_datagrams: int = 0
    signing_rejected: int = 0
    wrong_target: int = 0
    commands_received: int = 0
    commands_unsupported: int = 0
    setpoints_accepted: int = 0
    setpoints_rejected: int = 0
    manual_control_accepted: int = 0
    manual_control_rejected: int = 0
    params_unknown: int = 0
    handler_errors: int = 0
    messages_sent: int = 0
    send_errors: int = 0
    notices_sent: int = 0
    notices_suppressed: int = 0
    loop_overruns: int = 0
    caught_up_ms: int = 0


STAT_NAMES: tuple[str, ...] = tuple(f.name for f in fields(EndpointStats))


class StatsCounter:
    """Thread-safe mutable counters behind ``EndpointStats`` snapshots."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._counts = dict.fromkeys(STAT_NAMES, 0)

    def add(self, name: str, count: int = 1) -> None:
        """Increase one counter; an unknown name raises KeyError listing the valid ones."""
        if name not in self._counts:
            raise KeyError(f"unknown counter {name!r}; valid: {', '.join(STAT_NAMES)}")
        with self._lock:
            self._counts[name] += count

    def snapshot(self) -> EndpointStats:
        with self._lock:
            return EndpointStats(**self._counts)
