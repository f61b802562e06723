"""A within-trial safety governor on the scheduled speed (a safety layer, not in [Ostafew16]).

The speed scheduler (planners.rover.speed_scheduler, eq. 31) moves speeds only between trials,
from what the last pass met. A pass at a speed no pass has driven yet meets a learned model
that extrapolates in speed, and nothing slows the robot before the next trial. Measured on
experiment 3 (`python -m scripts.rover --regime rover_exp3 --seed 1`, before this governor):
trial 5, scheduled up to 1.2 m/s where trial 4 drove 1.1 m/s, swung across the path from the
first arc on and left it by 3.7 m, heading errors up to 1.2 rad; with learning disabled, the
same schedule left experiment 2's path by 1.5 m (seed 0). A 600 kg robot 3.7 m off a taught
path has left the ground known to be safe.

So, as a path-following safety layer does: when the localised lateral or heading error passes
``trip_factor`` times the scheduler's thresholds (lambda_L, lambda_H of Table I), the robot
drops to the first trial's speed v_init (the speed the a-priori model was trusted with) over
the whole horizon, and keeps it until both errors are back under the thresholds themselves.
The scheduler still sees the errors of the pass, so the next trial is slower there.
"""

from __future__ import annotations

from dataclasses import dataclass

from planners.rover.speed_scheduler import SpeedSchedulerConfig


@dataclass
class SpeedGovernor:
    """Caps the commanded speed at v_init while the errors are out of bounds.

    Attributes:
        scheduler: the thresholds (lambda_lat_m, lambda_head_rad) and v_init_mps.
        trip_factor: errors past this times the thresholds trip the governor (> 1).
        slowed: whether the cap is on now.
        trips: how many times it tripped in this pass.
    """

    scheduler: SpeedSchedulerConfig
    trip_factor: float = 2.0
    slowed: bool = False
    trips: int = 0

    def __post_init__(self) -> None:
        if not self.trip_factor > 1:
            raise ValueError(f"trip_factor must be > 1, got {self.trip_factor}")

    def cap_mps(self, e_lat_m: float, e_head_rad: float) -> float:
        """The speed cap [m/s] after this step's localised errors (inf when not slowed)."""
        c = self.scheduler
        lat, head = abs(e_lat_m), abs(e_head_rad)
        if self.slowed:
            self.slowed = not (lat < c.lambda_lat_m and head < c.lambda_head_rad)
        elif lat > self.trip_factor * c.lambda_lat_m or head > self.trip_factor * c.lambda_head_rad:
            self.slowed = True
            self.trips += 1
        return c.v_init_mps if self.slowed else float("inf")
