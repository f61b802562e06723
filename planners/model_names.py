"""The nominal models a multirotor's NMPC flies, by name (planners.nominal_models builds each;
its unicycle is the ground robots'), apart from CasADi: a command line lists them at once."""

from __future__ import annotations

MULTIROTOR_MODELS: tuple[str, ...] = ("kinematic_4dof", "first_order_lag", "px4_velocity_pi")
