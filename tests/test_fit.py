"""least_squares_fit: recovery from synthetic data and standard errors vs ordinary least squares."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj


def _solve_programs() -> int:
    """The fit engine's solve programs: stored ones and those traced in this process."""
    from tribojax._fit import _engine

    return len(_engine._solve_jit.programs) + _engine._solve_jit.jitted.jitted._cached._cache_size()


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


def test_a_determined_parameter_keeps_a_finite_error_beside_an_undetermined_pair():
    # a and b enter only as a + b; c is determined. The SVD's null direction loads c at
    # round-off level only, which must not make c's standard error infinite.
    # (with these x, y the SVD puts -7.8e-17 of c into the null direction)
    def residuals(theta, args):
        x = jnp.array([1.0, 2.0, 3.0, 4.0, 5.0])
        y = jnp.array([0.3, -1.1, 0.7, 2.9, -0.4])
        return 1.7 * x * (theta[0] + theta[1] - 1.0) + y * (theta[2] - 2.0)

    fit = tj.least_squares_fit(
        residuals, jnp.array([0.3, 0.1, 0.0]), names=("a", "b", "c"), sigma_known=True
    )
    assert np.isinf(fit.std_errors[0]) and np.isinf(fit.std_errors[1])
    assert np.isfinite(fit.std_errors[2]) and fit.std_errors[2] > 0.0


def test_non_convergence_is_reported():
    def residuals(theta, args):
        return jnp.array([jnp.exp(theta[0]) - 1e6, theta[0] * 1e-3])

    fit = tj.least_squares_fit(
        residuals, jnp.array([-50.0]), names=("a",), max_steps=2, throw=False
    )
    assert not fit.converged and fit.message


def _power_law_residuals(theta, args):
    x, y = args
    return theta[0] + theta[1] * jnp.log(x) - jnp.log(y)


def _power_law_data():
    rng = np.random.default_rng(7)
    x = np.geomspace(1.0, 100.0, 40)
    return jnp.asarray(x), jnp.asarray(3.0 * x**0.75 * np.exp(0.02 * rng.standard_normal(40)))


def test_fit_reports_a_results_member():
    fit = tj.least_squares_fit(
        _power_law_residuals, jnp.zeros(2), _power_law_data(), names=("a", "b")
    )
    assert isinstance(fit.result, tj.RESULTS) and fit.result == tj.RESULTS.successful
    assert fit.converged and fit.message == tj.RESULTS[tj.RESULTS.successful] == ""
    assert fit.as_dict()["result"] == "successful" and fit.as_dict()["converged"] is True


def test_a_fit_stopped_by_max_steps_says_so():
    def residuals(theta, args):
        return jnp.array([jnp.exp(theta[0]) - 1e6, theta[0] * 1e-3])

    fit = tj.least_squares_fit(
        residuals, jnp.array([-50.0]), names=("a",), max_steps=1, throw=False
    )
    assert fit.result == tj.RESULTS.nonlinear_max_steps_reached and not fit.converged
    assert "maximum number of steps" in fit.message and "max_steps = 1" in fit.message
    assert fit.as_dict()["result"] == "nonlinear_max_steps_reached"
    assert fit.as_dict()["converged"] is False
    # by default (throw=True) the same failure is raised at the boundary, the FitResult inside
    with pytest.raises(tj.FitError, match="nonlinear_max_steps_reached") as err:
        tj.least_squares_fit(residuals, jnp.array([-50.0]), names=("a",), max_steps=1)
    assert err.value.fit.result == tj.RESULTS.nonlinear_max_steps_reached
    ok = tj.least_squares_fit(residuals, jnp.array([13.0]), names=("a",), throw=True)
    assert ok.converged and ok.values[0] == pytest.approx(np.log(1e6), rel=1e-6)


def test_a_failed_model_evaluation_is_reported():
    from tribojax._fit._engine import FAILED_RESIDUAL

    def residuals(theta, args):  # the model cannot be evaluated anywhere
        return jnp.full(3, FAILED_RESIDUAL) + 0.0 * theta[0]

    fit = tj.least_squares_fit(residuals, jnp.array([1.0]), names=("a",), throw=False)
    assert fit.result == tj.RESULTS.model_failed_at_start and not fit.converged
    assert "start values" in fit.message


def test_fit_result_status_fields_stay_consistent():
    kw = dict(
        names=("a",),
        values=np.ones(1),
        std_errors=np.ones(1),
        covariance=np.eye(1),
        correlation=np.eye(1),
        theta=np.zeros(1),
        residuals=np.zeros(3),
        singular_values=np.ones(1),
    )
    old = tj.FitResult(**kw, converged=False, steps=3, message="stopped")
    assert old.result == tj.RESULTS.not_converged and old.message == "stopped"
    ok = tj.FitResult(**kw, result=tj.RESULTS.successful)
    assert ok.converged and ok.message == ""
    short = ok.with_result(tj.RESULTS.short_of_optimum)
    assert not short.converged and short.message == tj.RESULTS[tj.RESULTS.short_of_optimum]
    with pytest.raises(ValueError, match="contradicts"):
        tj.FitResult(**kw, converged=True, result=tj.RESULTS.model_failed)


def test_noise_floor_lm_stops_on_the_statistical_rule():
    # y = A e^(b x) + noise, and a residual that jitters at 1e-7 of its scale with θ (as one
    # computed through an adaptive ODE solve), which its Jacobian does not see. With the Cauchy
    # test off (rtol = atol = 0) and rejections allowed up to 100, only the Gauss-Newton rule
    # (step left < 0.05 standard errors after an accepted step) can stop it within 50 steps.
    from tribojax._fit._engine import gauss_newton_step
    from tribojax._fit._solver import LevenbergMarquardt

    rng = np.random.default_rng(3)
    x = jnp.linspace(0.0, 1.0, 50)
    y = 2.0 * jnp.exp(-1.5 * x) + 0.01 * jnp.asarray(rng.standard_normal(50))

    def residuals(theta, args):
        x, y = args
        jitter = 1e-9 * jnp.sin(1e9 * jax.lax.stop_gradient(theta[0] + x * theta[1]))
        return (theta[0] * jnp.exp(theta[1] * x) - y) / 0.01 + jitter

    lines = []
    fit = tj.least_squares_fit(
        residuals,
        jnp.array([1.0, 0.0]),
        (x, y),
        names=("A", "b"),
        sigma_known=True,
        max_steps=50,
        jac="fwd",
        solver=LevenbergMarquardt.noise_floor(0.0, 0.0, max_rejections=100, report=True),
        progress=lines.append,
    )
    assert fit.result == tj.RESULTS.successful and fit.steps < 50
    assert float(jnp.max(jnp.abs(gauss_newton_step(fit.residuals, fit.jacobian)))) < 0.05
    assert np.all(np.abs(fit.values - [2.0, -1.5]) < 3 * fit.std_errors)
    assert lines and all(ln.startswith("LM: ") for ln in lines)
    assert "Gauss-Newton step" in lines[-1]
    # plain LM with the same (switched-off) Cauchy test runs to the step budget
    plain = tj.least_squares_fit(
        residuals,
        jnp.array([1.0, 0.0]),
        (x, y),
        names=("A", "b"),
        sigma_known=True,
        max_steps=50,
        jac="fwd",
        rtol=0.0,
        atol=0.0,
        throw=False,
    )
    assert plain.result == tj.RESULTS.nonlinear_max_steps_reached


def test_a_jacobian_that_is_not_finite_is_a_failed_fit_not_a_crash():
    # a residual whose derivative overflows at the optimum: exp(exp(θ)) at θ = 7 (e^1097 > 1.8e308)
    def residuals(theta, args):
        return jnp.array([theta[0] - 7.0, 0.0 * jnp.exp(jnp.exp(theta[0]))])

    fit = tj.least_squares_fit(residuals, jnp.array([7.0]), names=("a",), throw=False)
    assert fit.result == tj.RESULTS.model_failed_at_start and not fit.converged
    assert np.all(np.isinf(fit.std_errors))


def _rosenbrock(theta, args):  # module level: one compiled solve whatever the budget
    return jnp.stack([10.0 * (theta[1] - theta[0] ** 2), 1.0 - theta[0]])


def test_step_budget_is_a_run_time_value_of_one_compiled_solve():
    # the library's LM takes the step budget at run time (options["budget"] under a static cap
    # of MAX_STEPS): the same iterates and outcome as optimistix's own static max_steps, and
    # budgets of 1, 3 and 100 steps share one compiled solve
    import optimistix as optx

    from tribojax._fit import _engine
    from tribojax._fit._solver import LevenbergMarquardt

    solver = LevenbergMarquardt(1e-10, 1e-12)
    y0 = jnp.array([-1.2, 1.0])
    fits = {
        k: tj.least_squares_fit(
            _rosenbrock, y0, names=("a", "b"), solver=solver, max_steps=k, jac="fwd", throw=False
        )
        for k in (3, 100)
    }

    def programs():
        return _solve_programs()

    before = programs()
    for k, fit in fits.items():
        ref = optx.least_squares(
            _rosenbrock, solver, y0, options=dict(jac="fwd"), max_steps=k, throw=False
        )
        assert np.array_equal(fit.theta, np.asarray(ref.value)), k
        assert fit.steps == int(ref.stats["num_steps"])
        ran_out = bool(ref.result == optx.RESULTS.nonlinear_max_steps_reached)
        assert (fit.result == tj.RESULTS.nonlinear_max_steps_reached) == ran_out
    assert fits[3].steps == 3 and not fits[3].converged
    assert fits[100].converged and np.allclose(fits[100].values, [1.0, 1.0], atol=1e-8)
    # a budget of one step is the start's linearisation, from the same compiled program
    r, J = _engine.value_and_jacobian(_rosenbrock, y0, None, solver=solver, max_steps=100)
    assert programs() == before
    want_J = jax.jacfwd(_rosenbrock)(y0, None)
    assert np.allclose(np.asarray(r), np.asarray(_rosenbrock(y0, None)), rtol=1e-14, atol=0)
    assert np.allclose(np.asarray(J), np.asarray(want_J), rtol=1e-14, atol=0)


def test_a_start_above_the_bar_after_its_probe_steps_is_abandoned():
    # options["bar"] = (probe, limit), at run time like the budget: Rosenbrock from (-1.2, 1)
    # has cost ‖r‖² = 24.2 at the start and descends slowly along its valley; a limit below
    # the cost it holds after 3 steps stops it there (as `nonlinear_max_steps_reached`, fewer
    # steps than the budget); a limit it is below by then, or none, lets it converge, along
    # the same iterates, in the same compiled solve
    from tribojax._fit._solver import LevenbergMarquardt

    solver = LevenbergMarquardt(1e-10, 1e-12)
    y0 = jnp.array([-1.2, 1.0])

    def fit(bar):
        return tj.least_squares_fit(
            _rosenbrock,
            y0,
            names=("a", "b"),
            solver=solver,
            max_steps=100,
            jac="fwd",
            bar=bar,
            throw=False,
        )

    free = fit(None)
    three = tj.least_squares_fit(
        _rosenbrock, y0, names=("a", "b"), solver=solver, max_steps=3, jac="fwd", throw=False
    )
    cost3 = float(three.residuals @ three.residuals)
    before = _solve_programs()
    cut = fit((3, 0.5 * cost3))
    assert cut.steps == 3 and cut.result == tj.RESULTS.nonlinear_max_steps_reached
    assert np.array_equal(cut.theta, three.theta)
    kept = fit((3, 2.0 * cost3))
    assert kept.converged and np.array_equal(kept.theta, free.theta) and kept.steps == free.steps
    assert _solve_programs() == before


def _valley(th, args):
    # Rosenbrock's valley of width 1/A with its second row repeated 5,000 times (a record's
    # many samples: a step's promised gain stays above the residual variance while it crawls)
    return jnp.concatenate(
        [jnp.stack([args[0] * (th[1] - th[0] ** 2)]), (1.0 - th[0]) * jnp.ones(5000)]
    )


def test_a_solve_that_crawls_far_from_a_minimum_is_stopped():
    # options["crawl"] = f (run time): the record solver stops a solve whose cost fell by less
    # than f over the last CRAWL_STEPS steps while a Gauss-Newton step promises more than half
    # of it. A narrow valley (A = 1e6) from (-3, 9): 128 steps lower the cost by 6 % only; with
    # f = 1 % it stops after two windows, on the iterate of that budget. A wide one (A = 1e4)
    # from (-1.2, 1) descends slowly but steadily to the minimum in 126 steps: never stopped,
    # the same iterates; f = 0 is off
    from tribojax._fit._solver import CRAWL_STEPS, LevenbergMarquardt

    solver = LevenbergMarquardt.record(
        1e-8, 1e-10, gain_tol=1e-2, noise_tol=1.0, max_rejections=12, padded=0
    )

    def fit(a, y0, crawl, max_steps=128):
        return tj.least_squares_fit(
            _valley,
            jnp.array(y0),
            args=(jnp.asarray(a),),
            names=("a", "b"),
            solver=solver,
            max_steps=max_steps,
            jac="fwd",
            crawl=crawl,
            throw=False,
        )

    def cost(f):
        return float(f.residuals @ f.residuals)

    free = fit(1e6, [-3.0, 9.0], 0.0)
    assert free.steps == 128 and cost(free) > 0.9 * 80_000.0  # 80,000 at the start
    cut = fit(1e6, [-3.0, 9.0], 0.01)
    assert cut.result == tj.RESULTS.nonlinear_max_steps_reached
    assert 2 * CRAWL_STEPS <= cut.steps < 4 * CRAWL_STEPS
    same = fit(1e6, [-3.0, 9.0], 0.0, max_steps=cut.steps)
    assert np.array_equal(cut.theta, same.theta)
    slow = [fit(1e4, [-1.2, 1.0], f) for f in (0.0, 0.01)]
    assert slow[0].converged and slow[0].steps > 4 * CRAWL_STEPS
    assert np.allclose(slow[0].values, [1.0, 1.0], atol=1e-8)
    assert np.array_equal(slow[1].theta, slow[0].theta) and slow[1].steps == slow[0].steps
