"""Derivatives of an ODE solve by forward mode in every direction (the slip model's adjoint).

`ForwardJacobianAdjoint` is what `simulate_slip` uses with its default solver, `Rodas4`: the solve
sits inside a `jax.custom_jvp` whose rule builds the Jacobian of the saved states w.r.t. the
differentiated float leaves of the inputs by `jax.jacfwd` through diffrax's `ForwardMode`, and
applies it to the tangent. The rule is linear in the tangent, so `jax.grad` / `jax.jacrev`
transpose it: reverse mode never recomputes the solve, and jacrev and jacfwd give the same
numbers. Why reverse mode must not recompute a Rosenbrock solve: see `Rodas4`.

It wraps the solve function rather than being a `diffrax.AbstractAdjoint`, whose `loop(...)`
takes and returns diffrax's private solver state (integer leaves, `SaveAt`, the controller's
`jump_ts`), all of which a rule there would differentiate and depend on; the slip model needs
derivatives w.r.t. the solve function's arguments only (element, profile, mass, save times).
"""

from __future__ import annotations

import functools

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.custom_derivatives import SymbolicZero
from jax.flatten_util import ravel_pytree


class ForwardJacobianAdjoint(eqx.Module):
    """Differentiate a solve by its forward-mode Jacobian, in forward and reverse mode alike.

    Pass as `simulate_slip(..., adjoint=ForwardJacobianAdjoint())` (the default with Rodas4; any
    other solver may use it too). `primal`: the diffrax adjoint of the undifferentiated solve
    (default `diffrax.RecursiveCheckpointAdjoint()`; `diffrax.ForwardMode()` gives the same
    numbers). The derivative solves always use `diffrax.ForwardMode()`.

    Cost of one derivative pass (either direction): one solve carrying as many tangents as there
    are differentiated scalars (4 for (F_s, K_τ, C_τ, α)). Save times enter through
    dys/dts = f(ts, ys).
    """

    primal: dfx.AbstractAdjoint = dfx.RecursiveCheckpointAdjoint()

    def solve(self, solve, rate, inputs):
        """ys, aux of `solve(*inputs, adjoint)` with derivatives by the forward-mode Jacobian.

        `inputs` = (element, profile, mass, ts); `solve(element, profile, mass, ts, adjoint)`
        returns (ys, aux) with ys of shape (len(ts), n_state); `rate(element, profile, mass, ts,
        ys)` returns the vector field at every saved point (for the derivative w.r.t. ts).
        """
        dyn, static = eqx.partition(inputs, eqx.is_array)
        has_ts = eqx.is_array(inputs[3])

        def primal(d):
            return solve(*eqx.combine(d, static), self.primal)

        @jax.custom_jvp
        def run(d):
            return primal(d)

        @functools.partial(run.defjvp, symbolic_zeros=True)
        def _jvp(primals, tangents):
            (d,), (td,) = primals, tangents
            leaves, treedef = jax.tree.flatten(d)
            tleaves = treedef.flatten_up_to(td)
            ts_leaf = len(leaves) - 1 if has_ts else None  # ts is the last leaf
            active = [
                i
                for i, t in enumerate(tleaves)
                if i != ts_leaf
                and not isinstance(t, SymbolicZero)
                and jnp.issubdtype(leaves[i].dtype, jnp.inexact)
            ]
            if active:
                flat, unflat = ravel_pytree([leaves[i] for i in active])

                def ys_of(p):
                    new = list(leaves)
                    for i, x in zip(active, unflat(p)):
                        new[i] = x
                    inp = eqx.combine(jax.tree.unflatten(treedef, new), static)
                    ys, aux = solve(*inp, dfx.ForwardMode())
                    return ys, (ys, aux)

                jac, (ys, aux) = jax.jacfwd(ys_of, has_aux=True)(flat)
                dp, _ = ravel_pytree([tleaves[i] for i in active])
                tys = jac @ dp
            else:
                ys, aux = primal(d)
                tys = jnp.zeros_like(ys)
            if ts_leaf is not None and not isinstance(tleaves[ts_leaf], SymbolicZero):
                tys = tys + rate(*eqx.combine(d, static), ys) * tleaves[ts_leaf][:, None]
            taux = jax.tree.map(
                lambda x: (
                    np.zeros(np.shape(x), jax.dtypes.float0)
                    if not jnp.issubdtype(x.dtype, jnp.inexact)
                    else jnp.zeros_like(x)
                ),
                aux,
            )
            return (ys, aux), (tys, taux)

        return run(dyn)
