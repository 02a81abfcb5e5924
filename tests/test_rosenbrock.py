"""Rodas4 (tribojax._dynamics._rodas4) on linear test problems with known solutions."""

import diffrax as dfx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.linalg import expm

import tribojax as tj

A = np.array([[-1.0, 2.0], [-3.0, -50.0]])  # eigenvalues ~ -1.1 and -49.9
B = np.array([1.0, 0.5])
Y0 = np.array([1.0, 0.5])


def exact(t):
    """Solution of y' = A y + b t, y(0) = y0: expm(A t)(y0 − p(0)) + p(t), p(t) = −A⁻¹b t − A⁻²b."""
    ai = np.linalg.inv(A)

    def p(s):
        return -ai @ B * s - ai @ ai @ B

    return expm(A * t) @ (Y0 - p(0.0)) + p(t)


def solve(dt0, controller=None, ts=(0.37, 1.0)):
    term = dfx.ODETerm(lambda t, y, a: jnp.asarray(A) @ y + jnp.asarray(B) * t)
    kw = {} if controller is None else dict(stepsize_controller=controller)
    sol = dfx.diffeqsolve(term, tj.Rodas4(), 0.0, 1.0, jnp.asarray(dt0), jnp.asarray(Y0),
                          saveat=dfx.SaveAt(ts=jnp.asarray(ts)), **kw)  # fmt: skip
    return np.asarray(sol.ys)


def test_fourth_order_convergence_and_dense_output():
    errs = []
    for n in (10, 20, 40, 80):
        mid = (n // 2 + 0.5 + np.arange(5)) / n  # step midpoints past the stiff transient
        ys = solve(1.0 / n, ts=(*mid, 1.0))
        want = np.stack([exact(t) for t in (*mid, 1.0)])
        errs.append((np.abs(ys[-1] - want[-1]).max(), np.abs(ys[:-1] - want[:-1]).max()))
    e = np.array(errs)
    order = np.log2(e[:-1, 0] / e[1:, 0])
    # Rodas4 is order 4 (Hairer & Wanner IV.7); the first halving is still pre-asymptotic
    assert np.all(order[1:] > 3.7) and np.all(order < 4.6), order
    # dense output (RODAS's, order 3 locally) at step midpoints: measured errors ~1.3x the
    # step-end ones and the same global order 4 on this problem
    dense_order = np.log2(e[:-1, 1] / e[1:, 1])
    assert np.all(dense_order > 3.5), dense_order
    assert e[-1, 0] < 1e-10 and e[-1, 1] < 1e-10, e[-1]


def test_adaptive_solve_meets_tolerance():
    ys = solve(1e-3, dfx.PIDController(rtol=1e-8, atol=1e-10))
    np.testing.assert_allclose(ys[1], exact(1.0), rtol=1e-7)
    np.testing.assert_allclose(ys[0], exact(0.37), rtol=1e-6)  # dense output


@pytest.mark.parametrize("lam", [1e4, 1e8])
def test_stiff_prothero_robinson_one_big_step(lam):
    # y' = -lam (y - cos t) - sin t, y(0) = 1: solution cos t. L-stability and stiff accuracy
    # keep one step of h = 0.1 at the smooth solution however large lam is.
    term = dfx.ODETerm(lambda t, y, a: -lam * (y - jnp.cos(t)) - jnp.sin(t))
    sol = dfx.diffeqsolve(term, tj.Rodas4(), 0.0, 0.1, 0.1, jnp.array([1.0]))
    assert abs(float(sol.ys[0, 0]) - np.cos(0.1)) < 1e-6
