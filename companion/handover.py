"""Who took the vehicle out of OFFBOARD, in words: the companion's hand-over detail.

A PX4 offboard application yields whenever the vehicle leaves OFFBOARD (companion.runner). What
it then says should be right about who chose the new mode: a pilot (a manual mode), PX4's own
failsafe (announced in a STATUSTEXT the Link heard, companion.link.StatusText), or, for an
automatic mode that nothing explained, no one in particular.
"""

from __future__ import annotations

from companion.link import Link

_MANUAL_MODES = ("MANUAL", "STABILIZED", "ACRO", "ALTCTL", "POSCTL")
"""Modes a pilot's sticks fly. PX4's failsafes choose them only as the offboard-loss fallback
with sticks present (COM_OBL_RC_ACT, Position mode by default), and then say so ("Failsafe
activated"), which failsafe_said hears first."""


FAILSAFE_TEXT_RECENT_S = 3.0
"""A vehicle text naming a failsafe this recent [s] explains a mode change."""


def failsafe_said(link: Link) -> str:
    """The vehicle's newest text naming a failsafe in the last FAILSAFE_TEXT_RECENT_S, or ""
    when it said none. PX4 v1.14+ says "Failsafe activated" (or "..., entering Hold for 5
    seconds"), v1.13 "Failsafe enabled: no datalink", each ending in a tab (PX4's mark of a
    text its events protocol says too), which is left out here, as surrounding blanks are."""
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
