"""Turn the numbers inside an SX Function into one more input, so that one compiled routine
serves every model of the same shape.

A learned residual arrives as a CasADi Function with its data (a GP's inducing inputs, weights,
hyperparameters) as constants in its graph, and the nominal model's own constants (a time
constant, the step length) sit beside them. Generated C code would carry those numbers, so each
new model would need its own compile. Rebuilt here with every constant read from an input
``theta`` instead, the C code of two models that differ only in their numbers is the same (and
so is its cache key, planners.compiled_function), and the numbers are passed at each call.
The rebuilt Function evaluates the same operations in the same order: at ``theta`` it gives the
original's results bit for bit.
"""

from __future__ import annotations

import casadi as ca
import numpy as np


def constants_as_input(fn: ca.Function) -> tuple[ca.Function, np.ndarray]:
    """(``fn`` with one more input ``theta`` (n_theta,) holding every constant of its graph,
    theta's values). A graph this cannot rebuild (not an SX Function, or one calling other
    Functions) keeps its constants: theta is then empty and unused (generated code then
    carries the numbers, one build per model)."""
    names = [fn.name_in(i) for i in range(fn.n_in())] + ["theta"]
    out_names = [fn.name_out(i) for i in range(fn.n_out())]
    inputs = [ca.SX.sym(fn.name_in(i), fn.sparsity_in(i)) for i in range(fn.n_in())]
    ops = (
        [fn.instruction_id(k) for k in range(fn.n_instructions())] if fn.is_a("SXFunction") else []
    )
    if not ops or ca.OP_CALL in ops or ca.OP_PARAMETER in ops:
        unused = ca.SX.sym("theta", 0)
        kept = ca.Function(fn.name(), [*inputs, unused], fn.call(inputs), names, out_names)
        return kept, np.zeros(0)
    outputs = [ca.SX(fn.sparsity_out(i)) for i in range(fn.n_out())]
    consts = [k for k, op in enumerate(ops) if op == ca.OP_CONST]
    theta = ca.SX.sym("theta", len(consts))
    values = np.array([fn.instruction_constant(k) for k in consts])
    index = {k: i for i, k in enumerate(consts)}
    work: dict[int, ca.SX] = {}
    for k, op in enumerate(ops):
        arg, res = fn.instruction_input(k), fn.instruction_output(k)
        if op == ca.OP_CONST:
            work[res[0]] = theta[index[k]]
        elif op == ca.OP_INPUT:
            work[res[0]] = inputs[arg[0]].nz[arg[1]]
        elif op == ca.OP_OUTPUT:
            outputs[res[0]].nz[res[1]] = work[arg[0]]
        elif len(arg) == 1:
            work[res[0]] = ca.SX.unary(op, work[arg[0]])
        else:
            work[res[0]] = ca.SX.binary(op, work[arg[0]], work[arg[1]])
    return ca.Function(fn.name(), [*inputs, theta], outputs, names, out_names), values
