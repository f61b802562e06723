"""Who took the vehicle out of OFFBOARD, in words: the companion's hand-over detail.

A PX4 offboard application yields whenever the vehicle leaves OFFBOARD (companion.runner). What
it then says should be right about who chose the new mode: a pilot (a manual mode), PX4's own
failsafe (announced in a STATUSTEXT the Link heard, companion.link.StatusText), or, for an
automatic mode that nothing explained, no one in particular.
"""

from __future__ import annotations

from companion.link import Link
from companion.waiting import POLL_PERIOD_S

_MANUAL_MODES = ("MANUAL", "STABILIZED", "ACRO", "ALTCTL", "POSCTL")
"""Modes a pilot's sticks fly. PX4's failsafes choose them only as the offboard-loss fallback
with sticks present (COM_OBL_RC_ACT, Position mode by default), and then say so ("Failsafe
activated"), which failsafe_said hears first."""


FAILSAFE_TEXT_RECENT_S = 3.0
"""A vehicle text naming a failsafe this recent [s] explains a mode change."""

FAILSAFE_TEXT_WAIT_S = 1.0
"""How long [s] a real-time link is given, after a change to an automatic mode was seen, to
deliver a failsafe's text (for such a mode the text is the only way to tell who chose it).
PX4 announces the failsafe in the cycle that switches the mode, but a link may hand the two
over in either order: MAVSDK reports the flight mode and the texts on separate streams, and on
a loaded computer the text came second (seen once in a suite run beside other work)."""


def handover_detail(link: Link, mode: str, t_s: float) -> str:
    """handed_over_detail for a vehicle that left OFFBOARD for ``mode`` ``t_s`` seconds in, with
    what ``link`` heard of a failsafe (failsafe_heard)."""
    return handed_over_detail(mode, t_s, failsafe_heard(link, mode))


def failsafe_heard(link: Link, mode: str) -> str:
    """failsafe_said once the vehicle left OFFBOARD for ``mode``: for an automatic mode it waits
    up to FAILSAFE_TEXT_WAIT_S for the text; a manual mode is a pilot's unless a text already
    said otherwise, so the report is not held back."""
    return failsafe_said(link, 0.0 if mode in _MANUAL_MODES else FAILSAFE_TEXT_WAIT_S)


def failsafe_said(link: Link, wait_s: float = 0.0) -> str:
    """The vehicle's newest text naming a failsafe in the last FAILSAFE_TEXT_RECENT_S, or ""
    when it said none, waiting up to ``wait_s`` [s] for one on a real-time link (a lockstep
    link hands texts over in the order they were sent, so it does not wait). Nothing is sent
    while waiting. PX4 v1.14+ says "Failsafe activated" (or "..., entering Hold for 5
    seconds"), v1.13 "Failsafe enabled: no datalink", each ending in a tab (PX4's mark of a
    text its events protocol says too), which is left out here, as surrounding blanks are."""
    clock = link.clock
    deadline_s = clock.now_s() + (wait_s if clock.real_time else 0.0)
    while True:
        said = _recent_failsafe_text(link)
        if said or clock.now_s() >= deadline_s:
            return said
        clock.sleep_until(min(clock.now_s() + POLL_PERIOD_S, deadline_s))


def _recent_failsafe_text(link: Link) -> str:
    """The newest text naming a failsafe in the last FAILSAFE_TEXT_RECENT_S, or ""."""
    now_s = link.clock.now_s()
    for said in reversed(link.status_texts()):
        if now_s - said.t_s > FAILSAFE_TEXT_RECENT_S:
            break
        if "failsafe" in said.text.lower():
            return said.text.strip()
    return ""


def handed_over_detail(mode: str, t_s: float, failsafe_text: str = "") -> str:
    """The outcome's detail when the vehicle left OFFBOARD for ``mode`` ``t_s`` seconds in.

    With ``failsafe_text`` (what the vehicle just said of a failsafe, see failsafe_said), it
    was PX4's failsafe. Otherwise a manual mode is a pilot's, and an automatic one (RTL, LAND,
    HOLD, ...) may be a pilot's switch, a ground station's command or a failsafe that said
    nothing the link heard, which the mode alone cannot tell apart: the detail does not guess.
    """
    if failsafe_text:
        return (
            f"a PX4 failsafe took the vehicle out of OFFBOARD into {mode} at t={t_s:.1f} s "
            f'("{failsafe_text}"); mission abandoned'
        )
    if mode in _MANUAL_MODES:
        return f"pilot took control in {mode} at t={t_s:.1f} s; mission abandoned"
    return (
        f"the vehicle left OFFBOARD for {mode} at t={t_s:.1f} s (a pilot, a ground station "
        "or a PX4 failsafe chose it); mission abandoned"
    )
