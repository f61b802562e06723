"""The parts of JSBSim's F450 model (``aircraft/F450`` in the jsbsim package) that we rely on.

Motor order. Ours is PX4's quad-X: 1 front-right CCW, 2 rear-left CCW, 3 front-left CW,
4 rear-right CW (spin seen from above). The F450 declares its engines in the same order (front
right, aft left, front left, aft right) with propeller sense +1, +1, -1, -1; sense +1 spins CCW
seen from above (raising motors 1 and 2 yaws the body clockwise, +r, as tests check), so our
motor i drives the F450's engine i.

Commands. The model's own flight control adds a pilot throttle and a rate-damping loop (gated by
``fcs/ScasEngage``) to an external input per ESC; we zero the first two and write the external
inputs, which the ESC actuators clip to [0, 1].
"""

MODEL_NAME = "F450"

ESC_COMMAND_PROPERTIES = (
    "fcs/cmdFR_ext_nd",
    "fcs/cmdAL_ext_nd",
    "fcs/cmdFL_ext_nd",
    "fcs/cmdAR_ext_nd",
)
"""JSBSim property written for each of our motors 1..4 (normalised ESC command, 0..1)."""

ENGINE_INDEX_OF_MOTOR = (0, 1, 2, 3)
"""JSBSim engine index driven by each of our motors 1..4."""

OWN_CONTROL_OFF = {"fcs/throttle-cmd-norm": 0.0, "fcs/ScasEngage": 0.0}
"""Properties that switch the model's own pilot throttle and rate-damping loop off."""
