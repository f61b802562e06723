"""Deadline-bounded waits and commands on a Link (every wait has a deadline)."""

from __future__ import annotations

from collections.abc import Callable

from companion.link import CommandOutcome, Link, LinkError, LinkState

POLL_PERIOD_S = 0.05


def wait_for(
    link: Link, condition: Callable[[LinkState], bool], timeout_s: float, what: str
) -> LinkState:
    """Poll telemetry on the link's clock until ``condition`` holds; returns that state.

    Raises:
        LinkError: after ``timeout_s`` [s], naming ``what`` and the last state seen.
    """
    clock = link.clock
    deadline_s = clock.now_s() + timeout_s
    while True:
        state = link.read_state()
        if condition(state):
            return state
        if clock.now_s() >= deadline_s:
            raise LinkError(
                f"timed out after {timeout_s:g} s waiting for {what}; {describe(state)}"
            )
        clock.sleep_until(min(clock.now_s() + POLL_PERIOD_S, deadline_s))


def command_until_accepted(
    link: Link, send: Callable[[], CommandOutcome], timeout_s: float, what: str
) -> CommandOutcome:
    """Repeat a command (every 0.5 s of link time) until accepted or ``timeout_s`` passes.

    Raises:
        LinkError: naming ``what`` and the autopilot's last answer.
    """
    clock = link.clock
    deadline_s = clock.now_s() + timeout_s
    while True:
        outcome = send()
        if outcome.accepted:
            return outcome
        if clock.now_s() >= deadline_s:
            raise LinkError(
                f"{what} refused for {timeout_s:g} s: {outcome.detail or 'no reason given'}"
            )
        clock.sleep_until(min(clock.now_s() + 0.5, deadline_s))


def describe(state: LinkState) -> str:
    """One-line summary of a state for messages."""
    n, e, d = (float(x) for x in state.pos_ned_m)
    return (
        f"mode {state.mode}, {'armed' if state.armed else 'disarmed'}, "
        f"{state.landed.name.lower()}, pos NED ({n:.2f}, {e:.2f}, {d:.2f}) m"
    )
