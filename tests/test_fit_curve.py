"""Steady friction-curve fits (LuGre steady law, asymmetry) and LuGre transients (issue 15)."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tribojax as tj

REAL = Path(__file__).resolve().parents[1] / "data" / "real" / "screwdrive"
TRUE = {"F_c": 2.5, "F_s": 3.2, "v_s": 3.0, "beta": 1.4, "sigma2": 0.03, "T0": 0.3}


def _synthetic_curve(seed=15):
    """Points made with NumPy (no tribojax code), noise per point from its stated scatter."""
    rng = np.random.default_rng(seed)
    v = np.concatenate([-np.geomspace(0.2, 20.0, 14), np.geomspace(0.25, 21.0, 14)])
    mag = TRUE["F_c"] + (TRUE["F_s"] - TRUE["F_c"]) * np.exp(-((np.abs(v) / TRUE["v_s"]) ** 1.4))
    f = np.sign(v) * mag + TRUE["sigma2"] * v + TRUE["T0"]
    scatter, n = np.full(v.size, 0.5), np.full(v.size, 400.0)
    f = f + scatter / np.sqrt(n) * rng.standard_normal(v.size)
    return tj.FrictionCurve(v, f, scatter, 0.0 * v, n)


def test_joint_fit_recovers_law_and_asymmetry():
    fit = tj.fit_steady_curve(_synthetic_curve())
    assert fit.converged and fit.noise_consistent
    for name, value, se in zip(fit.names, fit.values, fit.std_errors):
        assert abs(value - TRUE[name]) < 4 * se, (name, value, se)


def test_per_direction_fit_absorbs_the_asymmetry():
    curve = _synthetic_curve(16)
    pos, neg = (tj.fit_steady_curve(curve, direction=s) for s in (1, -1))
    # the asymmetry adds T0 to the positive magnitudes and removes it from the negative ones
    assert pos.values[0] - neg.values[0] == pytest.approx(2 * TRUE["T0"], abs=0.15)
    with pytest.raises(ValueError, match=r"direction must be \+1, -1 or None"):
        tj.fit_steady_curve(curve, direction=2)


def test_screw_drive_curve_shows_stribeck_viscous_and_asymmetry():
    curve = tj.read_record(REAL / "driveNo1_steady_0.096kg.csv")
    joint = tj.fit_steady_curve(curve)
    p = dict(zip(joint.names, joint.values))
    assert p["F_s"] > p["F_c"] and p["sigma2"] > 0  # Stribeck dip and viscous rise
    # T0 ≈ 0.35 mN m, close to m·g·lead/2π = 0.096·9.81·0.002/2π = 0.30 mN m
    assert 0.25e-3 < p["T0"] < 0.45e-3 and joint.std_errors[-1] < 0.05e-3
    for sign in (1, -1):
        d = dict(zip(joint.names, tj.fit_steady_curve(curve, direction=sign).values))
        assert d["F_s"] > d["F_c"] > 1.5e-3


def test_the_steady_law_keeps_its_lowest_optimum():
    # driveNo2's joint law has separate optima: from the first start alone the fit runs β to a
    # step and stops converged at χ² 68.9; the other starts reach 66.0, the one kept
    curve = tj.read_record(REAL / "driveNo2_steady_0.096kg.csv")
    joint = tj.fit_steady_curve(curve)
    chi2 = float(np.sum(np.square(joint.residuals)))
    assert joint.converged and chi2 < 66.5
    assert chi2 == pytest.approx(joint.reduced_chi2 * (curve.velocity.size - 6), rel=1e-9)
    assert len(tj.STEADY_STARTS) == 9 and tj.STEADY_STARTS[0] == (2.0, 1.0)


def test_transient_with_steady_law_fixed():
    curve = tj.read_record(REAL / "driveNo1_steady_0.096kg.csv")
    tr = tj.read_record(REAL / "driveNo1_start_stop_50.csv")
    steady = tj.fit_steady_curve(curve)
    dyn = tj.fit_transient(tr, steady, sigma=float(np.median(curve.friction_scatter)))
    # the steady law explains the moving samples within the steady points' scatter ...
    assert dyn.reduced_chi2 < 2.0 and tj.transient_nrmse(dyn, tr) < 0.2
    # ... and 40 ms samples cannot resolve the bristle dynamics: σ0 is not determined
    assert dyn.std_errors[0] > 10 * dyn.values[0]


def test_constant_velocity_step_is_exact():
    el = tj.LuGre(50.0, 0.0, 0.0, 2.0, 3.0, 0.5, 1.0, 2.0)
    for v in (0.3, -1.2):
        g = 2.0 + np.exp(-((v / 0.5) ** 2))
        sol = solve_ivp(
            lambda t, z: [v - abs(v) * 50.0 * z[0] / g], (0, 0.2), [0.01], rtol=1e-12, atol=1e-15
        )
        assert float(el.constant_velocity_step(0.01, v, 0.2)) == pytest.approx(
            sol.y[0, -1], rel=1e-9
        )


@pytest.mark.usefixtures("storable_programs")
def test_constant_velocity_step_grad_and_jit():
    import jax
    import jax.numpy as jnp

    def z_end(p):
        el = tj.LuGre(p[0], 0.0, 0.0, p[1], p[2], 0.5, 1.0, 2.0)
        return el.constant_velocity_step(0.0, 0.4, 0.05)

    p = jnp.array([50.0, 2.0, 3.0])
    g = jax.grad(z_end)(p)
    for i in range(3):
        e = jnp.zeros(3).at[i].set(1e-6 * p[i])
        fd = (z_end(p + e) - z_end(p - e)) / (2e-6 * p[i])
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-6)
    assert float(jax.jit(z_end)(p)) == pytest.approx(float(z_end(p)), rel=1e-14)


def test_stribeck_curve_step_limit_has_finite_gradients():
    """A fit running β off to a step (driveNo2's joint fit: β → 1e5) must see g = F_c with
    finite derivatives where |v/v_s|^β overflows, and the closed form elsewhere."""
    import jax
    import jax.numpy as jnp

    from tribojax._friction._lugre import stribeck_curve

    def g(p, v):
        return stribeck_curve(v, p[0], p[1], p[2], p[3])

    for beta, v in ((1.2e5, 3.0), (1.2e5, 0.5), (800.0, 40.0), (1.4, 0.0), (1.4, 2.0)):
        p = jnp.array([2.5, 3.2, 2.0, beta])
        with np.errstate(over="ignore"):  # (1.5)^1.2e5 = inf: exp(-inf) = 0
            closed = 2.5 + 0.7 * np.exp(-(np.float64(abs(v) / 2.0) ** beta))
        assert float(g(p, v)) == pytest.approx(closed, rel=1e-14)
        assert np.all(np.isfinite(jax.grad(g)(p, v)))
