"""Experiment (issue 3): why reverse mode through diffrax's checkpointed adjoint fails with Rodas4.

1. Bitwise reproducibility: the slip vector field and one Rodas4 step evaluated at 200 random
   states in a plain jitted program and inside jitted jvp / vjp programs (measured: 74 and 129
   of 200 steps differ). XLA fuses (and contracts a*b + c into fused multiply-adds) differently
   in each program, so some results differ in the last bits.
2. Consequence: RecursiveCheckpointAdjoint recomputes the forward steps inside its backward pass.
   Logging every Rodas4 step (t0, t1) of the forward pass and of the backward pass (t_end 0.26 s,
   one load) shows steps in the backward pass that the forward pass never took: the recomputed
   trajectory drifts from the recorded one (measured: 2210 of 5593 step calls), and jax.jacrev
   disagrees with jax.jacfwd (1.7e-3 of the largest entry here; 6e-3 with other tolerances).
   Kvaerno5's solves came out bitwise identical under all adjoints (jacrev = jacfwd to 1e-15);
   presumably its converged Newton corrections are too small for the rounding differences to
   reach y.
`tribojax.simulate_slip` therefore differentiates Rodas4 solves by forward mode in both
directions (a jax.custom_jvp). Run: python benchmarks/experiments/rodas4_reverse_mode.py
"""

import diffrax as dfx
import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

import tribojax as tj
from tribojax._dynamics._slip import _vector_field

PROFILE = tj.TrapezoidProfile()
THETA = jnp.array([0.7372, 2.1478e7, 708.8274, 1.2])  # Table 3, 2 kPa; alpha 1.2


def _args(th):
    el = tj.PreSlipLuGre(th[0], th[1], th[2], th[3])
    _, unravel = ravel_pytree(el.initial_state())
    return el, (el, PROFILE, 0.321, unravel)


def bitwise():
    def one(th, y0, t0, h, part):
        _, args = _args(th)
        term = dfx.ODETerm(_vector_field)
        if part == "vector field":
            return term.vf(t0, y0, args)
        y1, err, *_ = tj.Rodas4().step(term, t0, t0 + h, y0, args, None, False)
        return jnp.concatenate([y1, err])

    rng = np.random.default_rng(0)
    n = 200
    v = rng.normal(size=n) * 5e-7 * 10.0 ** -rng.integers(0, 8, n)
    cols = [rng.normal(size=n) * 4e-8, v, rng.normal(size=n) * 2e-8, rng.normal(size=n) * 1e-9]
    ys = jnp.asarray(np.stack(cols, 1))
    t0s, hs = jnp.asarray(rng.uniform(0.1, 0.6, n)), jnp.asarray(10.0 ** rng.uniform(-6, -3, n))
    for part in ("vector field", "Rodas4 step"):

        def f(th, y, t, h, part=part):
            return one(th, y, t, h, part)

        plain = jax.jit(jax.vmap(f, (None, 0, 0, 0)))(THETA, ys, t0s, hs)

        def fwd(y, t, h, f=f):
            return jax.jvp(lambda th: f(th, y, t, h), (THETA,), (jnp.ones(4),))[0]

        def rev(y, t, h, f=f):
            out, vjp = jax.vjp(lambda th: f(th, y, t, h), THETA)
            return out, vjp(jnp.ones_like(out))[0]

        a = jax.jit(jax.vmap(fwd))(ys, t0s, hs)
        b = jax.jit(jax.vmap(rev))(ys, t0s, hs)[0]
        print(
            f"{part}: primal differs bitwise from the plain program in "
            f"{int(jnp.sum(jnp.any(plain != a, -1)))}/{n} (jvp program), "
            f"{int(jnp.sum(jnp.any(plain != b, -1)))}/{n} (vjp + backward program)"
        )


def recomputation(t_end=0.26):
    log = []
    step = tj.Rodas4.step

    def logged(self, terms, t0, t1, y0, args, ss, mj):
        out = step(self, terms, t0, t1, y0, args, ss, mj)
        jax.debug.callback(lambda a, b: log.append((float(a), float(b))), t0, t1)
        return out

    def solve(th, adjoint):
        el, args = _args(th)
        y0 = jnp.zeros(4)
        atol = jnp.array([1e-18, 1e-15, 1e-18, 1e-19])
        ctrl = dfx.PIDController(
            rtol=1e-8, atol=atol, pcoeff=0.3, icoeff=0.4, factormax=3.0, jump_ts=PROFILE.kinks()
        )
        sol = dfx.diffeqsolve(
            dfx.ODETerm(_vector_field),
            tj.Rodas4(),
            0.0,
            t_end,
            1e-4,
            y0,
            args=args,
            stepsize_controller=ctrl,
            max_steps=100_000,
            adjoint=adjoint,
        )
        return sol.ys[-1] / jnp.array([1e-9, 1e-6, 1e-9, 1e-9])

    tj.Rodas4.step = logged
    try:
        rc = dfx.RecursiveCheckpointAdjoint()
        jax.block_until_ready(jax.jit(lambda th: solve(th, rc))(THETA))
        forward, log[:] = set(log), []
        jr = np.asarray(jax.jit(jax.jacrev(lambda th: solve(th, rc)))(THETA))
        backward = list(log)
    finally:
        tj.Rodas4.step = step
    new = sum(s not in forward for s in backward)
    jf = np.asarray(jax.jit(jax.jacfwd(lambda th: solve(th, dfx.ForwardMode())))(THETA))
    scale = np.abs(jf * np.asarray(THETA)).max()
    print(
        f"forward pass: {len(forward)} steps; backward pass: {len(backward)} step calls, "
        f"{new} of them at (t0, t1) the forward pass never visited"
    )
    print(
        f"|jacrev - jacfwd| / largest elasticity: "
        f"{np.abs((jr - jf) * np.asarray(THETA)).max() / scale:.1e}"
    )


if __name__ == "__main__":
    bitwise()
    recomputation()
