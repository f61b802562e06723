"""When each setpoint of a stream takes effect: the command-delay queue, planned in steps.

A stream (:meth:`vehicle_sim.Simulator.stream_setpoints`) is a row of legs: leg i sets
``setpoints[i]`` (None: none) at its start and then lasts ``steps[i]`` physics steps. The
simulator takes a setpoint into force when it is set, or, with a command delay of D steps,
queues it and releases it at the first stretch of physics that starts at or after D steps later
(stretches are cut there, so exactly then). A release at the stream's very end waits for the
next stretch, after the stream. Planned here, a compiled loop switches its setpoint at those
steps as the stretch-by-stretch loop does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

T = TypeVar("T")


@dataclass(frozen=True)
class StreamPlan(Generic[T]):
    """A stream's legs and setpoint changes, in physics steps from its start.

    Attributes:
        leg_start, leg_end: (n,) int64, the step each leg starts and ends at.
        change_at: (m,) int64, ascending: the step from which ``changes[j]`` is in force (the
            last of equal steps wins); the first is 0, what is in force at the start.
        changes: (m,) the setpoint in force from ``change_at[j]`` on.
        k0: the absolute step the stream starts at; delay_steps: the command delay [steps];
        setpoints: (n,) each leg's setpoint as given (None: none); queued: the delay queue
            at the start [(absolute release step, setpoint)].
    """

    leg_start: np.ndarray
    leg_end: np.ndarray
    change_at: np.ndarray
    changes: tuple[T | None, ...]
    k0: int
    delay_steps: int
    setpoints: tuple[T | None, ...]
    queued: tuple[tuple[int, T], ...]

    def state_after(self, done: int, *, at_end: bool) -> StreamState[T]:
        """Where the stream stands once ``done`` steps have run. ``at_end``: it ran to its
        end, every leg's setpoint is set (also those of empty legs at the end); otherwise it
        stopped after step ``done``, and the legs starting there are not begun."""
        begun = len(self.leg_start) if at_end else int(np.searchsorted(self.leg_start, done))
        sets = [
            (int(self.leg_start[i]), sp)
            for i, sp in enumerate(self.setpoints[:begun])
            if sp is not None
        ]
        last_set = sets[-1][0] if sets else None
        if self.delay_steps == 0:
            return StreamState(sets[-1][1] if sets else self.changes[0], (), begun, last_set)
        queue = [*self.queued, *((self.k0 + s + self.delay_steps, sp) for s, sp in sets)]
        released = sum(1 for release, _ in queue if release - self.k0 < done)
        in_force = queue[released - 1][1] if released else self.changes[0]
        return StreamState(in_force, tuple(queue[released:]), begun, last_set)


@dataclass(frozen=True)
class StreamState(Generic[T]):
    """A stream after some steps: the setpoint in force (``changes[0]`` of its plan, or one of
    its setpoints or queued ones), the delay queue left [(absolute release step, setpoint)],
    how many legs have begun (their setpoints set), and the step (from the stream's start) of
    the last setpoint set (None: none)."""

    in_force: object
    queued: tuple[tuple[int, T], ...]
    legs_begun: int
    last_set_at: int | None


def plan_stream(
    k0: int,
    steps: Sequence[int],
    setpoints: Sequence[T | None],
    delay_steps: int,
    in_force: T | None,
    queued: Sequence[tuple[int, T]],
) -> StreamPlan[T]:
    """The plan of a stream that starts at absolute step ``k0`` with ``in_force`` in force and
    ``queued`` [(absolute release step, setpoint)] in the delay queue, legs of ``steps``
    (n,) physics steps setting ``setpoints`` (n,), the command delay ``delay_steps``."""
    ends = np.cumsum(np.asarray(steps, dtype=np.int64))
    starts = ends - np.asarray(steps, dtype=np.int64)
    total = int(ends[-1]) if len(ends) else 0
    at: list[int] = [0]
    changes: list[T | None] = [in_force]
    if delay_steps == 0:
        for start, sp in zip(starts.tolist(), setpoints, strict=True):
            if sp is not None and start < total:
                at.append(start)
                changes.append(sp)
    else:
        news = [
            (k0 + s + delay_steps, sp) for s, sp in zip(starts.tolist(), setpoints, strict=True)
        ]
        for release, sp in [*queued, *((r, sp) for r, sp in news if sp is not None)]:
            if release - k0 < total:
                at.append(max(release - k0, 0))
                changes.append(sp)
    return StreamPlan(
        starts,
        ends,
        np.asarray(at, dtype=np.int64),
        tuple(changes),
        k0,
        delay_steps,
        tuple(setpoints),
        tuple(queued),
    )
