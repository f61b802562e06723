"""Starting, stopping and checking a rover over any companion Link, and its pose in the path
frame: what the teach pass, the repeat drives and the drive back share. No planner and no
learning here, so a teach pass over MAVLink loads neither (experiments.rover.link_drive drives
the NMPC and the GP).
"""

from __future__ import annotations

import numpy as np

from companion.link import ZERO_VELOCITY, Link, LinkError, LinkState


class NotARover(LinkError):
    """The vehicle on the link says it is not a ground rover (nothing was sent to it)."""


def require_a_rover(link: Link) -> None:
    """Raise :class:`NotARover` unless the connected vehicle may be a rover (its link says
    so, or says nothing): a multicopter must not be driven as one."""
    kind = link.read_state().vehicle_kind
    if kind not in (None, "rover", "boat", "other"):
        hint = "; fly a multicopter with companion" if kind in ("multirotor", "VTOL") else ""
        raise NotARover(
            f"the vehicle on the {link.name} link is a {kind} (its HEARTBEAT's MAV_TYPE), not "
            f"a ground rover: rover-path drives only rovers{hint}"
        )


def pose_of(link: Link) -> np.ndarray:
    """(x_m, y_m, heading_rad) in the path frame from the Link's NED state."""
    return state_pose(link.read_state())


def state_pose(st: LinkState) -> np.ndarray:
    """(x_m, y_m, heading_rad) in the path frame of the NED state ``st``: a drive steers by
    the very state it checked (a second read may be newer, and not finite)."""
    return np.array([st.pos_ned_m[0], -st.pos_ned_m[1], -st.yaw_rad])


def start_driving(link: Link) -> None:
    """A zero velocity, arm and OFFBOARD: how every drive of the rover starts. Ctrl-C meanwhile
    stops the rover (zero velocity and Hold: it may be armed already) and is raised on.

    Raises:
        LinkError: the rover refused arming or OFFBOARD (its reason in the message).
    """
    try:
        link.send_velocity(ZERO_VELOCITY)
        for what, outcome in (("arm", link.arm), ("offboard", link.start_offboard)):
            result = outcome()
            if not result.accepted:
                raise LinkError(f"rover refused {what}: {result.detail or 'no reason given'}")
    except KeyboardInterrupt:
        stop_rover(link)
        raise


def stop_rover(link: Link) -> bool:
    """Command a zero velocity and Hold, whatever state the link is in; True if Hold was
    accepted (False also when the link is gone: nothing more can be sent then)."""
    try:
        link.send_velocity(ZERO_VELOCITY)
        return link.hold().accepted
    except LinkError:
        return False
