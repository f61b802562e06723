"""Feature definitions: which logged signals (at which lags) form the GP input vector.

A :class:`FeatureDefinition` is recorded in every model file; the NMPC builds its GP query in
exactly this order, and loading a model against another definition is an error.

The built-in sets are in :mod:`gp.feature_sets` (names and columns, apart from CasADi).
In the NMPC, "vel" is the velocity the (augmented) model predicts for the vehicle.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import casadi as ca

from gp.feature_sets import CHANGE, CMD_COLUMNS, FEATURE_SETS, INTERVAL, POS_COLUMNS, VEL_COLUMNS
from planners.nominal_models import HISTORY_STATES, MODELS, NominalModel, make_model
from planners.velocity_history import with_velocity_history

RESIDUAL_OUTPUTS: tuple[str, ...] = ("res_acc_n_mps2", "res_acc_e_mps2", "res_acc_d_mps2")

# Where the NMPC takes each feature column from: (model, state x, input u, model velocity) ->
# scalar. A position is the model's position state of that name.
_PLANNER_SOURCES: dict[str, Callable[..., ca.SX]] = {
    **{c: (lambda m, x, u, vel, i=i: vel[i]) for i, c in enumerate(VEL_COLUMNS)},
    **{c: (lambda m, x, u, vel, i=i: u[i]) for i, c in enumerate(CMD_COLUMNS)},
    "cmd_yaw_rate_radps": lambda m, x, u, vel: u[3],
    **{c: (lambda m, x, u, vel, c=c: x[m.state_names.index(c)]) for c in POS_COLUMNS},
}
# A velocity one interval ago is the model's previous-velocity state (planners.velocity_history).
_HISTORY_SOURCES: dict[str, Callable[..., ca.SX]] = {
    c: (lambda m, x, u, vel, h=h: x[m.state_names.index(h)])
    for c, h in zip(VEL_COLUMNS, HISTORY_STATES, strict=True)
}


def _source(column: str, lag: int) -> Callable[..., ca.SX]:
    """Where the NMPC takes a feature (column, lag) from (planner_map has checked the lag)."""
    if lag == 0:
        return _PLANNER_SOURCES[column]
    past = _HISTORY_SOURCES[column]
    if lag > 0:
        return past
    now = _PLANNER_SOURCES[column]
    return lambda m, x, u, vel: now(m, x, u, vel) - past(m, x, u, vel)


@dataclass(frozen=True)
class FeatureDefinition:
    """What a residual model was trained on.

    Attributes:
        name: feature-set name (a key of FEATURE_SETS).
        inputs: (log column, lag L in control steps) per feature, in input-vector order: L = 0
            the value at k, L > 0 the value at k - L, L < 0 the change x[k] - x[k - |L|].
        outputs: residual names, in output order (units in the names).
        nominal_model: name of the planners' nominal model the residual is taken against.
        nominal_params: that model's parameters as sorted (name, value) pairs.
        residual_steps: H, the log steps the residual is measured over (gp.datasets): 1 is
            [Kulathunga23]'s one-step residual; the planner's interval (0.1 s = 5 steps at
            50 Hz) lets the GP see what one 20 ms step hides under noise: the dead time and the
            second-order part of the velocity response, drag at speed, a wind field.
    """

    name: str
    inputs: tuple[tuple[str, int], ...]
    outputs: tuple[str, ...] = RESIDUAL_OUTPUTS
    nominal_model: str = "kinematic_4dof"
    nominal_params: tuple[tuple[str, float], ...] = ()
    residual_steps: int = 1

    def __post_init__(self) -> None:
        if self.residual_steps < 1:
            raise ValueError(f"residual_steps must be >= 1, got {self.residual_steps}")

    @property
    def input_names(self) -> tuple[str, ...]:
        """Feature names: the column, with ``[k-L]`` for a lag L > 0 (e.g. vel_n_mps[k-1]),
        ``[k]-...[k-L]`` for a change (e.g. vel_n_mps[k]-vel_n_mps[k-5])."""
        return tuple(
            c if lag == 0 else f"{c}[k-{lag}]" if lag > 0 else f"{c}[k]-{c}[k-{-lag}]"
            for c, lag in self.inputs
        )

    @property
    def n_features(self) -> int:
        return len(self.inputs)

    @property
    def max_lag(self) -> int:
        return max(abs(lag) for _, lag in self.inputs)

    @property
    def speed_columns(self) -> tuple[int, ...]:
        """Indices of the current measured velocity components (used by low_speed inducing)."""
        return tuple(i for i, (c, lag) in enumerate(self.inputs) if c in VEL_COLUMNS and lag == 0)

    @property
    def history_lag(self) -> int:
        """The lag [log steps] of the lagged measured velocities (or their changes), 0 without
        any."""
        return max((abs(lag) for c, lag in self.inputs if c in VEL_COLUMNS), default=0)

    def nominal(self) -> NominalModel:
        """The nominal model instance."""
        return make_model(self.nominal_model, **dict(self.nominal_params))

    def planner_model(self) -> NominalModel:
        """The model the NMPC plans with: the nominal model, with the velocity one interval
        ago as extra states when a feature is a lagged velocity and the model has a velocity
        state (planners.velocity_history; else planner_map refuses the lag)."""
        nominal = self.nominal()
        if self.history_lag and nominal.carries_velocity:
            return with_velocity_history(nominal)
        return nominal

    def planner_map(self, model: NominalModel) -> Callable[[ca.SX, ca.SX], ca.SX]:
        """z(x, u) (SX, n_features) for the NMPC, from the same ``inputs`` the dataset reads
        from the logs: a measured velocity is the model's velocity (``model.velocity_of``), a
        command is the input u, a velocity one residual interval ago the model's
        previous-velocity state (``planner_model``). Raises ValueError (one line) if the
        planner cannot build it: other lagged features, or a measured velocity beside other
        features on a model that does not carry the velocity ([Kulathunga23]'s "velocity" set
        queries the kinematic model at its commanded velocity, its only notion of velocity)."""
        carried = HISTORY_STATES[0] in model.state_names
        lagged = [
            n
            for n, (c, lag) in zip(self.input_names, self.inputs, strict=True)
            if lag and not (carried and c in VEL_COLUMNS and abs(lag) == self.residual_steps)
        ]
        if lagged:
            fix = (
                "use the 'velocity', 'state_input' or 'velocity_history' feature set"
                if model.carries_velocity
                else f"{model.name} has none: use the 'velocity' feature set, or a model with a "
                "velocity state (first_order_lag) for 'velocity_history'"
            )
            raise ValueError(
                f"the NMPC cannot feed lagged features {lagged} (it carries only the velocity "
                "one residual interval ago along the horizon, on a model with a velocity "
                f"state); {fix}"
            )
        uses = {c in VEL_COLUMNS for c, _ in self.inputs if c not in POS_COLUMNS}
        if uses == {True, False} and not model.carries_velocity:
            raise ValueError(
                f"the NMPC cannot feed features {self.name!r} from {model.name}'s state: they "
                f"need the measured velocity beside the command and it has no velocity state; "
                "use 'velocity', or 'state_input' with first_order_lag"
            )
        unknown = [
            c
            for c, _ in self.inputs
            if c not in _PLANNER_SOURCES or (c in POS_COLUMNS and c not in model.state_names)
        ]
        if unknown:
            raise ValueError(f"the NMPC has no source for features {unknown}")

        def z(x: ca.SX, u: ca.SX) -> ca.SX:
            vel = model.velocity_of(x, u)
            return ca.vertcat(*(_source(c, lag)(model, x, u, vel) for c, lag in self.inputs))

        return z

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "inputs": [[c, lag] for c, lag in self.inputs],
            "input_names": list(self.input_names),
            "outputs": list(self.outputs),
            "nominal_model": {"name": self.nominal_model, "params": dict(self.nominal_params)},
            "residual_steps": self.residual_steps,
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, object]) -> FeatureDefinition:
        nominal = data["nominal_model"]
        return cls(
            name=str(data["name"]),
            inputs=tuple((str(c), int(lag)) for c, lag in data["inputs"]),
            outputs=tuple(str(o) for o in data["outputs"]),
            nominal_model=str(nominal["name"]),
            nominal_params=tuple(sorted((str(k), float(v)) for k, v in nominal["params"].items())),
            residual_steps=int(data.get("residual_steps", 1)),
        )

    def describe(self) -> str:
        """One line: name, inputs and nominal model."""
        params = ", ".join(f"{k}={v:g}" for k, v in self.nominal_params)
        over = "" if self.residual_steps == 1 else f", residual over {self.residual_steps} steps"
        return (
            f"{self.name!r} ({', '.join(self.input_names)}) against {self.nominal_model}({params})"
            f"{over}"
        )


def feature_definition(
    name: str = "velocity",
    nominal_model: str = "kinematic_4dof",
    *,
    residual_steps: int = 1,
    **nominal_params: float,
) -> FeatureDefinition:
    """A built-in feature set against a nominal model, its residual measured over
    ``residual_steps`` log steps (an INTERVAL lag becomes that many, a CHANGE lag minus that
    many); bad names (of the set, the model or its parameters) and parameter values out of the
    model's range raise ValueError."""
    if name not in FEATURE_SETS:
        raise ValueError(f"unknown feature set {name!r}; choose one of {', '.join(FEATURE_SETS)}")
    if nominal_model not in MODELS:
        raise ValueError(
            f"unknown nominal model {nominal_model!r}; choose one of {', '.join(MODELS)}"
        )
    taken = inspect.signature(MODELS[nominal_model]).parameters
    unknown = sorted(set(nominal_params) - set(taken))
    if unknown:
        raise ValueError(
            f"nominal model {nominal_model} has no parameter {', '.join(unknown)}; "
            f"it takes {', '.join(taken) or 'none'}"
        )
    params = tuple(sorted((k, float(v)) for k, v in nominal_params.items()))
    resolve = {INTERVAL: residual_steps, CHANGE: -residual_steps}
    inputs = tuple((c, resolve.get(lag, lag)) for c, lag in FEATURE_SETS[name])
    definition = FeatureDefinition(
        name,
        inputs,
        nominal_model=nominal_model,
        nominal_params=params,
        residual_steps=residual_steps,
    )
    definition.nominal()  # a value out of range raises the model's own ValueError
    return definition
