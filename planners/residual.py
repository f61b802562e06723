"""A learned residual as the NMPC sees it: any CasADi Function g(z) plus how z is built.

planners/ never imports the learning code: a residual arrives as a ``casadi.Function`` whose
first output is a 3-vector [m/s^2] (further outputs, e.g. a variance, are ignored), and a
feature map that builds its input z from the model state and input.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from planners.nominal_models import NominalModel

FeatureMap = Callable[[ca.SX, ca.SX], ca.SX]
# z (n, nz) -> (g (n, 3) [m/s^2], d g / d z (n, 3, nz)): the same g evaluated at many rows at once
BatchedResidual = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class ResidualTerm:
    """g(z(x, u)) for eq. 1 of [Kulathunga23]: x_dot = f(x, u) + B_z g(z).

    Attributes:
        fn: CasADi Function z[nz] -> (g[3], ...) in m/s^2 (NED).
        features: builds z (SX column, nz) from the model state x (nx) and input u (nu).
        batch: optional, the same g and its Jacobian in NumPy at many rows at once (e.g.
            gp.batched_mean.BatchedMean); the fast solver path then linearises with it instead
            of differentiating ``fn``'s graph (planners.batched_linearisation).
    """

    fn: ca.Function
    features: FeatureMap
    batch: BatchedResidual | None = None

    def __post_init__(self) -> None:
        if self.fn.n_in() != 1 or self.fn.size1_out(0) * self.fn.size2_out(0) != 3:
            raise ValueError(
                f"residual Function {self.fn.name()!r} must map one input z to a 3-vector first "
                f"output; it has {self.fn.n_in()} inputs and first output "
                f"{self.fn.size1_out(0)}x{self.fn.size2_out(0)}"
            )

    @classmethod
    def of_velocity(cls, fn: ca.Function, model: NominalModel) -> ResidualTerm:
        """The common case ([Kulathunga23]): z = the model's velocity [m/s] (``model.velocity_of``).

        For the kinematic model that is the commanded velocity u[:3].
        """
        return cls(fn, lambda x, u: model.velocity_of(x, u))

    def __call__(self, x: ca.SX, u: ca.SX) -> ca.SX:
        """g(z(x, u)) as a 3x1 SX expression."""
        z = ca.vec(self.features(x, u))
        if z.numel() != self.fn.numel_in(0):
            raise ValueError(
                f"residual Function {self.fn.name()!r} expects z of size {self.fn.numel_in(0)}, "
                f"the feature map built {z.numel()}"
            )
        return ca.reshape(self.fn.call([z])[0], 3, 1)
