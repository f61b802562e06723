"""What the study flies and learns (a frozen config; the CLI builds it)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from companion.nmpc_planner import NmpcSettings
from experiments.executors import check_scheduler_address

STUDY_VEHICLE = "iris_study"
SELECTIONS: tuple[str, ...] = ("low_speed", "cluster")


@dataclass(frozen=True)
class StudyConfig:
    """The study's settings.

    Attributes:
        out_dir: where report.md, the PNGs and the model files go.
        vehicle: simulator preset or config file (default: the study vehicle, see
            vehicle_sim/presets/iris_study.toml).
        n_trajectories: random trajectories of [Kulathunga23]'s experiment.
        length_range_m: their length range [m]; max_speed_mps: their speed limit [m/s];
            max_acc_mps2: their acceleration limit [m/s^2]; ramp_jerk_mps3: the peak jerk of
            their jerk-limited start and end [m/s^3] (None: the plain spline, its acceleration
            stepping at both ends; planners.trajectory_generator.TrajectorySpec).
        repeats: flights per trajectory and planner (nominal seeds 0.., augmented after them).
        selections: inducing-point selections compared at equal ``m``.
        m: inducing points per output.
        n_trials: [Ostafew16] view: trials on one repeated path (1 nominal, then augmented with a
            model refitted on all trials so far); 0 skips the view (the report says so), e.g.
            for a bench that reads only [Kulathunga23]'s flights.
        trajectory_seed: seed of the trajectory generator.
        workers: processes flying in parallel on this machine.
        scheduler: a Dask scheduler address (tcp://host:8786): fly on that cluster's workers
            instead of local processes (None: this machine; see experiments.executors).
        nmpc: the nominal planner ([Kulathunga23]: the kinematic model; command limit, loop period).
        learned_model: the nominal model under the learned residual: "first_order_lag" (its
            time constants identified from the flights, then the GP on what is left; see
            gp.lag_identification) or "kinematic_4dof" ([Kulathunga23]'s GP alone).
        features: GP feature set: "velocity" (paper 000's, the default in every regime but
            wind_field's), "state_input" (the velocity and the command, on first_order_lag: the
            NMPC's optimiser exploits a GP on its own decision variable, see
            experiments.study.regimes), "velocity_history" (adds the velocity one planner
            interval ago, which the NMPC carries along its horizon, on a model with a velocity
            state).
        gp_restarts: hyperparameter restarts per fit.
        compile_augmented: compile each augmented planner's symbolic linearisation to C
            (cached on disk; over 6 minutes and 3 GB per model). The planner the companion and
            the study fly linearises batched in NumPy (planners.batched_linearisation), which
            has nothing to compile and ignores it.
        regime: the name of the regime these settings come from (experiments.study.regimes).
        refit_rounds: [Ostafew16]'s trial-after-trial learning inside [Kulathunga23]'s
            experiment: after the fit on the nominal flights, each round flies every selection's
            model on the nominal flights' seeds (never the held-out seeds the comparison flies)
            and refits its GP on all flights so far (on the structure identified from the
            nominal flights), so the model covers where the augmented planner flies; a refit
            flies only if it predicts the held-out logs better than the model it replaces
            (gp.prediction_check). 0: the model from the nominal flights.
        learn_from_structure: after the fit on the nominal flights, fly its identified
            structure (first_order_lag) alone on the nominal flights' seeds and fit the GP on
            those flights instead, on that same structure (experiments.study.paper000): the
            GP learns what the structure leaves where a planner on it flies.
        closed_loop_check: before the held-out comparison, fly each selection's newest model
            on the training seeds (where the rounds above have not flown it yet) and let it fly
            only if it tracks no worse there than the model it replaces and the identified
            structure alone; otherwise the model it replaced, ultimately the structure alone,
            flies (experiments.study.closed_loop; the structure's flights are flown too unless
            learn_from_structure flew them). On by default in every regime: the open-loop
            check alone passed a GP that flew worse than nominal on JSBSim's F450 (see
            experiments.study.regimes); False skips it (with a learned model without an
            identified structure, kinematic_4dof, there is nothing to check against).
    """

    out_dir: Path = Path("out/study")
    vehicle: str = STUDY_VEHICLE
    n_trajectories: int = 20
    length_range_m: tuple[float, float] = (40.0, 60.0)
    max_speed_mps: float = 1.5
    max_acc_mps2: float = 1.0
    ramp_jerk_mps3: float | None = None
    repeats: int = 3
    selections: tuple[str, ...] = SELECTIONS
    m: int = 30
    n_trials: int = 6
    trajectory_seed: int = 0
    workers: int = 2
    scheduler: str | None = None
    nmpc: NmpcSettings = NmpcSettings(speed_limit_mps=2.5)
    learned_model: str = "first_order_lag"
    features: str = "velocity"
    gp_restarts: int = 2
    compile_augmented: bool = False
    regime: str = "paper000"
    refit_rounds: int = 0
    learn_from_structure: bool = False
    closed_loop_check: bool = True

    def __post_init__(self) -> None:
        if self.n_trajectories < 1:
            raise ValueError(f"trajectories must be >= 1, got {self.n_trajectories}")
        if self.repeats < 1:
            raise ValueError(f"repeats must be >= 1 (flights per trajectory), got {self.repeats}")
        if self.n_trials < 2 and self.n_trials != 0:
            raise ValueError(
                f"trials must be >= 2 (trial 1 flies nominal, the learned model the next) or 0 "
                f"(no trial-to-trial view), got {self.n_trials}"
            )
        if self.m < 1:
            raise ValueError(f"m must be >= 1 (inducing points per output), got {self.m}")
        if self.trajectory_seed < 0:
            raise ValueError(f"seed must be >= 0, got {self.trajectory_seed}")
        if self.refit_rounds < 0:
            raise ValueError(f"refit_rounds must be >= 0, got {self.refit_rounds}")
        if self.workers < 1:
            raise ValueError(f"workers must be >= 1, got {self.workers}")
        if self.scheduler is not None:
            check_scheduler_address(self.scheduler)

    def quick(self) -> StudyConfig:
        """A small smoke version: 2 short trajectories, 1 flight each, 3 trials, no compile."""
        return replace(
            self,
            n_trajectories=2,
            length_range_m=(8.0, 10.0),
            repeats=1,
            n_trials=3,
            m=15,
            gp_restarts=1,
            compile_augmented=False,
        )
