"""least_squares_fit: recovery from synthetic data and standard errors vs ordinary least squares."""

import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj


def test_power_law_fit_matches_ols_and_recovers_truth():
    # y = A x^b with 2 % multiplicative noise (seed 7); in logs this is linear least squares,
    # so the LM optimum and its standard errors must equal the closed-form OLS ones.
    rng = np.random.default_rng(7)
    x = np.geomspace(1.0, 100.0, 40)
    A, b = 3.0, 0.75
    y = A * x**b * np.exp(0.02 * rng.standard_normal(x.size))

    def residuals(theta, args):
        return theta[0] + theta[1] * jnp.log(x) - jnp.log(y)

    fit = tj.least_squares_fit(
        residuals,
        jnp.array([0.0, 0.0]),
        names=("A", "b"),
        transform=lambda th: jnp.stack([jnp.exp(th[0]), th[1]]),
    )
    assert fit.converged and fit.message == ""
    X = np.column_stack([np.ones_like(x), np.log(x)])
    coef, rss, *_ = np.linalg.lstsq(X, np.log(y), rcond=None)
    cov = rss[0] / (x.size - 2) * np.linalg.inv(X.T @ X)
    np.testing.assert_allclose(fit.theta, coef, rtol=1e-9)
    se_A = np.exp(coef[0]) * np.sqrt(cov[0, 0])  # delta method for A = e^θ0
    np.testing.assert_allclose(fit.std_errors, [se_A, np.sqrt(cov[1, 1])], rtol=1e-6)
    assert abs(fit.values[0] - A) < 2 * fit.std_errors[0]
    assert abs(fit.values[1] - b) < 2 * fit.std_errors[1]
    assert fit.correlation[0, 1] == pytest.approx(
        cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1]), rel=1e-6
    )


def test_unidentifiable_direction_gets_infinite_error():
    # only the sum θ0 + θ1 is determined
    def residuals(theta, args):
        return jnp.array([1.0, 2.0, 3.0]) * (theta[0] + theta[1] - 1.0)

    fit = tj.least_squares_fit(residuals, jnp.array([0.0, 0.0]), names=("a", "b"))
    assert fit.singular_values[-1] < 1e-12 * fit.singular_values[0]
    assert not np.all(np.isfinite(fit.std_errors))


def test_non_convergence_is_reported():
    def residuals(theta, args):
        return jnp.array([jnp.exp(theta[0]) - 1e6, theta[0] * 1e-3])

    fit = tj.least_squares_fit(residuals, jnp.array([-50.0]), names=("a",), max_steps=2)
    assert not fit.converged and fit.message
