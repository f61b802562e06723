"""Real-time scheduling for a thread that must keep a wall-clock rate on a busy computer.

A companion computer runs its control loop at a real-time priority (Linux SCHED_FIFO), above
everything else the computer does, so the loop's tick waits for no other program; a flight
controller has a processor of its own. Here a thread asks for SCHED_FIFO at a low priority
(1-99; 1 is above every normal process and below the kernel's own real-time threads). Only
threads that sleep between short ticks may ask: a SCHED_FIFO thread that keeps computing holds
its core until it sleeps (Linux still leaves other programs 5 % of each second,
/proc/sys/kernel/sched_rt_runtime_us). Threads and processes started from a raised thread start
at normal priority (SCHED_RESET_ON_FORK).

Where the system does not permit it (no root, no CAP_SYS_NICE, RLIMIT_RTPRIO 0, not Linux) the
thread keeps its normal priority and the outcome says so in one line: nothing fails.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager

MAX_RT_PRIORITY = 99
"""Highest SCHED_FIFO priority Linux offers."""


def raise_to_realtime(rt_priority: int, thread_id: int = 0) -> str:
    """Put thread ``thread_id`` (0: the calling thread; else a native thread id, as
    ``threading.get_native_id`` gives) under SCHED_FIFO at ``rt_priority``.

    Returns:
        one line saying what happened: raised, or why the thread stays at normal priority.

    Raises:
        ValueError: ``rt_priority`` outside 1..99.
    """
    if not 1 <= rt_priority <= MAX_RT_PRIORITY:
        raise ValueError(f"real-time priority must be 1..{MAX_RT_PRIORITY}, got {rt_priority}")
    if not hasattr(os, "sched_setscheduler"):
        return "real-time priority not available on this system; normal priority"
    policy = os.SCHED_FIFO | os.SCHED_RESET_ON_FORK
    try:
        os.sched_setscheduler(thread_id, policy, os.sched_param(rt_priority))
    except OSError as exc:  # EPERM without the privilege; EINVAL e.g. in some containers
        return f"real-time priority not permitted ({exc.strerror or exc}); normal priority"
    return f"real-time priority SCHED_FIFO {rt_priority}"


@contextmanager
def realtime_section(
    rt_priority: int, what: str, progress: Callable[[str], None]
) -> Iterator[None]:
    """Run the body with the calling thread at SCHED_FIFO ``rt_priority`` (0: unchanged) and
    give it back its previous policy afterwards; reports the outcome as "<what>: <outcome>"."""
    if rt_priority == 0:
        yield
        return
    previous = _current_policy()
    progress(f"{what}: {raise_to_realtime(rt_priority)}")
    try:
        yield
    finally:
        if previous is not None:
            policy, param = previous
            try:
                os.sched_setscheduler(0, policy, param)
            except OSError as exc:
                progress(f"{what}: could not restore the scheduling policy ({exc.strerror})")


def _current_policy() -> tuple[int, os.sched_param] | None:
    if not hasattr(os, "sched_getscheduler"):
        return None
    return os.sched_getscheduler(0), os.sched_getparam(0)
