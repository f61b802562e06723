"""An operator's stop reaches a vehicle-driving command whatever the process inherited: inside
stop_signals_answered, SIGINT is KeyboardInterrupt and SIGTERM is Terminated even when the
parent left them ignored or blocked, and what was there before is back on leaving."""

import os
import signal
from collections.abc import Iterator

import pytest

from companion.runner import Terminated
from scripts.stop_signals import stop_signals_answered

STOPS = {signal.SIGINT, signal.SIGTERM}


@pytest.fixture
def inherited_ignored_and_blocked() -> Iterator[None]:
    """SIGINT and SIGTERM ignored and blocked, as a background job or supervisor may leave
    them; the test process's own state is put back afterwards."""
    saved = {s: signal.getsignal(s) for s in STOPS}
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    saved_mask = signal.pthread_sigmask(signal.SIG_BLOCK, STOPS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, saved_mask)
        for s, handler in saved.items():
            signal.signal(s, handler)


def test_ctrl_c_inside_is_a_keyboard_interrupt_though_it_was_ignored_and_blocked(
    inherited_ignored_and_blocked: None,
) -> None:
    with pytest.raises(KeyboardInterrupt) as stopped, stop_signals_answered():
        os.kill(os.getpid(), signal.SIGINT)
    assert type(stopped.value) is KeyboardInterrupt


def test_sigterm_inside_is_terminated_though_it_was_ignored_and_blocked(
    inherited_ignored_and_blocked: None,
) -> None:
    with pytest.raises(Terminated), stop_signals_answered():
        os.kill(os.getpid(), signal.SIGTERM)


def test_leaving_puts_back_the_inherited_handlers_and_mask(
    inherited_ignored_and_blocked: None,
) -> None:
    with stop_signals_answered():
        assert not STOPS & signal.pthread_sigmask(signal.SIG_BLOCK, set())
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) >= STOPS
