"""The fixed-rate control loop: read telemetry, decide, send, record - on any Link.

The loop runs on the link's clock (wall time for MAVLink links, simulated time for the
in-process one), so the same code flies real and simulated vehicles. A tick whose work ends
after the next tick was due counts as a deadline miss; the schedule then restarts from now
instead of bursting to catch up.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

from companion.decision import Decision
from companion.link import Link, LinkState


class Policy(Protocol):
    """Turns a telemetry snapshot into a command. Must not raise (see PlannerPolicy)."""

    def decide(self, state: LinkState, t_s: float) -> Decision: ...


@dataclass(frozen=True)
class Tick:
    """One control step: when it ran, what was seen, what was sent.

    Attributes:
        t_s: loop clock time the state was read [s].
        state: telemetry snapshot used.
        decision: the command sent and the planner's account of it.
    """

    t_s: float
    state: LinkState
    decision: Decision


StopReason = Literal["done", "timeout"]


class LoopCounters:
    """Running totals over several loop runs, updated live (so an interrupted run counts)."""

    def __init__(self) -> None:
        self.ticks = 0
        self.deadline_misses = 0


@dataclass(frozen=True)
class LoopResult:
    """How a loop run ended: "done" (the stop condition held) or "timeout"; counts of ticks."""

    stop_reason: StopReason
    ticks: int
    deadline_misses: int
    last_state: LinkState


def run_fixed_rate(
    link: Link,
    policy: Policy,
    *,
    rate_hz: float,
    until: Callable[[LinkState, float], bool],
    timeout_s: float,
    on_tick: Callable[[Tick], None],
    counters: LoopCounters | None = None,
) -> LoopResult:
    """Run ``policy`` at ``rate_hz`` on ``link`` until ``until(state, t_s)`` or ``timeout_s``.

    Every tick reads the state, stops if ``until`` holds (sending nothing more), else sends
    exactly one velocity command and hands a :class:`Tick` to ``on_tick``.
    The first tick runs at once; no tick runs at or after ``timeout_s`` (so consecutive runs
    never put two ticks at the same time).
    Exceptions from the link or ``on_tick`` propagate (the runner then brings the vehicle to
    a safe state); the policy is expected to absorb its own failures. ``counters``, if given,
    is updated as the loop goes.
    """
    counters = counters if counters is not None else LoopCounters()
    if not rate_hz > 0.0:
        raise ValueError(f"rate_hz must be positive, got {rate_hz}")
    clock = link.clock
    period_s = 1.0 / rate_hz
    t_start_s = clock.now_s()
    t_due_s = t_start_s
    ticks = 0
    misses = 0
    while True:
        t_s = clock.now_s()
        state = link.read_state()
        if until(state, t_s):  # checked before sending: a handover gets no further setpoint
            return LoopResult("done", ticks, misses, state)
        decision = policy.decide(state, t_s)
        link.send_velocity(decision.command)
        on_tick(Tick(t_s, state, decision))
        ticks += 1
        counters.ticks += 1
        t_due_s += period_s
        now_s = clock.now_s()
        if now_s > t_due_s:
            misses += 1
            counters.deadline_misses += 1
            t_due_s = now_s
        clock.sleep_until(t_due_s)
        if t_due_s - t_start_s >= timeout_s - 1e-9:
            return LoopResult("timeout", ticks, misses, state)
