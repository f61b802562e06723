"""The autopilot's velocity-loop gains, as the link reports them, for a planner model of PX4's
velocity loop (planners.nominal_models.px4_velocity_pi)."""

from __future__ import annotations

from companion.link import Link
from flightlog.velocity_loop_gains import GAINS_METADATA_KEY, VELOCITY_LOOP_PARAMS


def velocity_loop_gains(link: Link) -> tuple[tuple[str, float], ...]:
    """px4_velocity_pi's parameters read from the autopilot over ``link``.

    Raises:
        ValueError: the autopilot did not report one of them (one line naming it).
    """
    out = []
    for name, param in VELOCITY_LOOP_PARAMS.items():
        value = link.read_param(param)
        if value is None:
            raise ValueError(
                f"the autopilot did not report {param}; px4_velocity_pi needs it "
                f"(give {name} in the NMPC's nominal_params, or fly first_order_lag)"
            )
        out.append((name, float(value)))
    return tuple(out)


def velocity_loop_metadata(link: Link) -> dict[str, object]:
    """The velocity-loop gains for a flight log's sidecar (``velocity_loop_gains``: what
    fit-gp rebuilds px4_velocity_pi's integrator with, gp.velocity_integrator), or nothing
    when the autopilot does not report them all."""
    try:
        return {GAINS_METADATA_KEY: dict(velocity_loop_gains(link))}
    except ValueError:
        return {}
