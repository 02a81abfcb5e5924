"""The Bouc–Wen friction element against an independent SciPy integration of Wen's ODE."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tribojax as tj

K, F_Y, A, OMEGA = 2.0e6, 1.5e3, 2.0e-3, 2.0 * np.pi


def _scipy_force(t, K, F_y, n, b, c):
    """Wen's form with β, γ (not the element's parametrisation), integrated by LSODA."""
    z_y = F_y / K
    beta, gamma = b / z_y**n, (1 - b) / z_y**n

    def vel(s):
        return A * OMEGA * np.cos(OMEGA * s)

    def rhs(s, z):
        v = vel(s)
        return [v - beta * abs(v) * abs(z[0]) ** (n - 1) * z[0] - gamma * v * abs(z[0]) ** n]

    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0], t_eval=t, method="LSODA", rtol=1e-10, atol=1e-14)
    return K * sol.y[0] + c * vel(t)


@pytest.mark.parametrize("n, b, c", [(1.0, 0.5, 0.0), (2.5, 0.8, 0.0), (4.0, 0.3, 500.0)])
def test_matches_scipy_solve_ivp(n, b, c):
    t = np.linspace(0.0, 2.0, 8001)  # 4000 samples per cycle
    u = A * np.sin(OMEGA * t)
    f = np.asarray(tj.drive(tj.BoucWen(K, F_Y, n, b, c), u, t, substeps=2))
    ref = _scipy_force(t, K, F_Y, n, b, c)
    # the drive's velocity is the chord of each sample interval: O(h²) from the exact cos
    assert np.max(np.abs(f - ref)) < 2e-3 * F_Y
    assert np.max(np.abs(f - c * A * OMEGA * np.cos(OMEGA * t))) <= F_Y * (
        1 + 1e-5
    )  # c·v: chord vs exact velocity


def test_sharp_limit_is_jenkins_and_slip_force_is_F_y():
    t = np.linspace(0.0, 2.0, 8001)
    u = A * np.sin(OMEGA * t)
    bw = np.asarray(tj.drive(tj.BoucWen(K, F_Y, n=60.0), u, t))
    jen = np.asarray(tj.drive(tj.Jenkins(F_Y, 1.0, K), u))
    assert np.max(np.abs(bw - jen)) < 0.03 * F_Y
    assert np.max(bw) == pytest.approx(F_Y, rel=1e-3)


@pytest.mark.usefixtures("storable_programs")
def test_grad_matches_finite_differences_and_jit_agrees():
    t = jnp.linspace(0.0, 1.0, 1001)
    u = A * jnp.sin(OMEGA * t)

    def work(p):
        f = tj.drive(tj.BoucWen(p[0], p[1], p[2], 0.5), u, t)
        return jnp.sum(f * jnp.gradient(u))  # dissipated energy per cycle, J

    p = jnp.array([K, F_Y, 2.0])
    g = jax.grad(work)(p)
    for i in range(3):
        h = 1e-6 * p[i]
        e = jnp.zeros(3).at[i].set(h)
        fd = (work(p + e) - work(p - e)) / (2 * h)
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-5, abs=1e-12)
    assert float(jax.jit(work)(p)) == pytest.approx(float(work(p)), rel=1e-12)


def test_bad_parameters_name_themselves():
    with pytest.raises(ValueError, match=r"b = 1.5 is outside the allowed range \[0, 1\]"):
        tj.BoucWen(K, F_Y, 2.0, 1.5)
    with pytest.raises(ValueError, match=r"F_y = -1 N is outside"):
        tj.BoucWen(K, -1.0)
