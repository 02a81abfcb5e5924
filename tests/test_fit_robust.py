"""The robust (Student-t, EM) fit machinery and the profile likelihoods (issue 19).

The EM and the flags are checked here on a straight-line problem whose data are made by NumPy
(seed 0) and whose Student-t maximum likelihood is found independently by SciPy's Nelder–Mead
on the log-likelihood written out with `scipy.stats.t`. The chain-level fit to the measured
Tables 4–7 is checked in test_reproduce.py (its CLI run includes it); the long profile study is
marked slow.
"""

import math
import os

import jax.numpy as jnp
import numpy as np
import pytest
from scipy import optimize, stats

import tribojax as tj
from tribojax._reproduce import _profile_likelihood as pr
from tribojax._reproduce import _robust_fit as rb

# --- the likelihood, weights, flags (no model) -------------------------------------------------


@pytest.mark.parametrize("nu", [1.0, 4.0, math.inf])
def test_loglik_is_scipys_density(nu):
    rng = np.random.default_rng(1)
    y = rng.normal(5.0, 2.0, 24)
    model = y + rng.normal(0, 0.3, 24)
    sigma = np.abs(y)  # relative noise shape
    s = 0.07
    r = (y - model) / sigma
    dist = stats.norm if math.isinf(nu) else stats.t(nu)
    want = np.sum(dist.logpdf((y - model) / (s * sigma)) - np.log(s * sigma))
    assert rb.student_t_loglik(r, s, sigma, nu) == pytest.approx(want, rel=1e-12)


def test_noise_shapes_and_bad_input():
    y = np.array([[-0.47, 33.05]])
    np.testing.assert_allclose(rb.noise_shape(y, "relative"), [[0.47, 33.05]])
    np.testing.assert_allclose(rb.noise_shape(y, "absolute"), [[1.0, 1.0]])
    mixed = rb.noise_shape(y, "mixed", 1.0)
    # relative far above the floor, absolute far below it
    assert mixed[0, 1] == pytest.approx(33.05, rel=1e-3) and 1.0 < mixed[0, 0] < 1.2
    with pytest.raises(ValueError, match="floor_nm = None"):
        rb.noise_shape(y, "mixed")
    with pytest.raises(ValueError, match="noise = 'percent'"):
        rb.noise_shape(y, "percent")
    with pytest.raises(ValueError, match="nu = 0"):
        tj.robust_fit_measured_slips(nu=0)


def test_flag_threshold_holds_the_family_wise_level():
    # Gaussian data of known scale: the Bonferroni level flags >= 1 of 24 cells in ~5 % of sets
    z = rb.flag_threshold(24)
    assert z == pytest.approx(3.08, abs=0.005)
    rng = np.random.default_rng(0)
    rate = np.mean(np.any(np.abs(rng.standard_normal((20000, 24))) > z, axis=1))
    assert 0.045 < rate < 0.055  # 1 - (1 - 0.05/24)^24 = 0.0488 (±0.0015 sampling)


def test_standardized_residuals_use_the_leverage():
    rng = np.random.default_rng(2)
    X = np.column_stack([np.ones(12), np.linspace(0, 1, 12) ** 3])
    w = rng.uniform(0.2, 1.0, 12)
    r = rng.normal(size=12)
    # independent hat matrix: H = W½X (XᵀWX)⁻¹ XᵀW½
    Xw = np.sqrt(w)[:, None] * X
    H = Xw @ np.linalg.solve(X.T @ (w[:, None] * X), Xw.T)
    z = rb.standardized_residuals(r, Xw, 0.5)
    np.testing.assert_allclose(z, r / (0.5 * np.sqrt(1 - np.diag(H))), rtol=1e-10)


def test_profile_interval_of_a_parabola():
    # ℓ_P = -(x - 1)²/(2·0.2²): the 95 % interval is 1 ± 0.2·√3.84
    x = np.linspace(0.0, 2.0, 81)
    d = ((x - 1.0) / 0.2) ** 2
    i0 = 40
    hi = pr._crossing(x[i0:], d[i0:], pr.CHI2_95)
    lo = pr._crossing(x[: i0 + 1][::-1], d[: i0 + 1][::-1], pr.CHI2_95)
    half = 0.2 * math.sqrt(pr.CHI2_95)
    assert hi == pytest.approx(1 + half, abs=2e-3) and lo == pytest.approx(1 - half, abs=2e-3)
    assert pr._crossing(x[i0:], 0.01 * d[i0:], pr.CHI2_95) is None  # flat: open side


# --- EM on the one engine against SciPy's t maximum likelihood ----------------------------------


def _line_residuals(theta, args):
    x, y, sigma, sqrt_w = args
    return sqrt_w * (theta[0] + theta[1] * x - y) / sigma


@pytest.fixture(scope="module")
def line_data():
    """y = 2 + 3x with 5 % relative Gaussian noise and one cell off by +60 % (seed 0)."""
    rng = np.random.default_rng(0)
    x = np.linspace(0.5, 4.0, 24)
    clean = 2.0 + 3.0 * x
    y = clean * (1 + 0.05 * rng.standard_normal(24))
    y[17] *= 1.6
    return x, y


def _em_line(x, y, nu):
    sigma = np.abs(y)

    def m_step(u, previous):
        args = (jnp.asarray(x), jnp.asarray(y), jnp.asarray(sigma), jnp.asarray(np.sqrt(u)))
        fit = tj.least_squares_fit(_line_residuals, previous.theta, args, names=("a", "b"))
        return fit, fit.theta[0] + fit.theta[1] * x

    first = m_step(np.ones_like(y), tj.FitResult(
        names=("a", "b"), values=np.zeros(2), std_errors=np.zeros(2), covariance=np.eye(2),
        correlation=np.eye(2), theta=np.zeros(2), residuals=np.zeros(0),
        singular_values=np.ones(2), converged=True,
    ))  # fmt: skip
    return rb.student_t_em(m_step, y, sigma, nu, (*first, 1.0), tol=1e-10, max_iterations=500)


@pytest.mark.parametrize("nu", [1.0, 4.0])
def test_em_reaches_scipys_t_maximum_likelihood(line_data, nu):
    x, y = line_data
    fit, r, u, s, history, result = _em_line(x, y, nu)
    assert result == tj.RESULTS.successful
    assert np.all(np.diff(history) > -1e-9)  # EM never lowers the likelihood

    def nll(p):
        a, b, log_s = p
        scale = np.exp(log_s) * np.abs(y)
        return -np.sum(stats.t(nu).logpdf((y - a - b * x) / scale) - np.log(scale))

    ref = optimize.minimize(nll, [2.0, 3.0, np.log(0.05)], method="Nelder-Mead",
                            options=dict(xatol=1e-10, fatol=1e-12, maxiter=20000))  # fmt: skip
    np.testing.assert_allclose(fit.theta, ref.x[:2], rtol=1e-5)
    assert s == pytest.approx(np.exp(ref.x[2]), rel=1e-4)
    assert history[-1] == pytest.approx(-ref.fun, abs=1e-6)
    # the planted outlier is flagged (z ≈ 7.5) and heavily down-weighted; cell 12 is a −2.8σ
    # draw of the Gaussian noise, which the Cauchy fit (ν = 1) places at −3.2: flagged there too
    z = rb.standardized_residuals(r, fit.jacobian)
    flagged = np.flatnonzero(np.abs(z) > rb.flag_threshold(y.size)).tolist()
    assert flagged == ([12, 17] if nu == 1.0 else [17])
    assert u[17] < 0.1 * np.median(u)


def test_gaussian_em_is_one_least_squares_fit(line_data):
    x, y = line_data
    fit, r, u, s, history, result = _em_line(x, y, math.inf)
    assert np.all(u == 1.0) and len(history) == 2  # the start, then one fit that moves nothing
    # the outlier inflates the Gaussian scale and standard errors (measured: ×2.2), not the t's
    t_fit, _, _, t_s, _, _ = _em_line(x, y, 4.0)
    assert s > 1.5 * t_s and np.all(fit.std_errors > 1.5 * t_fit.std_errors)
    assert np.all(np.abs(t_fit.theta - [2.0, 3.0]) < 2 * t_fit.std_errors)  # truth: 2 + 3x


# --- the long profile study (chain) --------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.skipif(
    os.environ.get("TRIBOJAX_FULL") != "1",
    reason="profile likelihoods through the chain take minutes; short form: "
    "test_profile_interval_of_a_parabola and the reproduce CLI test",
)
def test_profile_of_mu_t_is_bounded():
    robust = tj.robust_fit_measured_slips()
    best = robust.parameters["mu_t"]
    prof = tj.chain_profile_likelihood(robust, "mu_t", [0.8 * best, 1.5 * best])
    d = np.asarray(prof["delta_2ll"])
    assert d.min() == pytest.approx(0.0, abs=1e-9) and d.max() > 0
    assert all(prof["converged"])
