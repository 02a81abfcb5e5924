"""The fit engine: optimistix least squares (`least_squares_fit`), then the statistics at the
optimum (`fit_statistics`, `_result`).

Parameters are fitted in unconstrained coordinates θ (log for positive quantities, etc.) and
mapped to the physical ones by a `transform` (`least_squares_fit`, `fit_statistics`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._checks import failures_as_nan
from .._export import cached_jit
from .._limits import MAX_STEPS
from .._precision import ensure_x64
from .._results import RESULTS, result_code, result_from_code
from ._result import FitResult, fit_statistics, thrown
from ._solver import FAILED_RESIDUAL, LevenbergMarquardt, gauss_newton_step, progress_channel


def _solve(
    residual_fn,
    theta0,
    args,
    solver,
    max_steps,
    jac,
    shared=MAX_STEPS,
    bar=None,
    crawl=0.0,
    channel=0,
    floor=1.0,
):
    """The least-squares solve: (θ, optimistix result, steps, (r, J) or None). Traced, lowered
    and compiled with failures as NaN (no host callback), and its trace stored (`cached_jit`).
    The library's `LevenbergMarquardt` takes the budget as a run-time value under a static cap
    of max(`max_steps`, `shared`): one compiled solve for every budget up to `shared`, and
    every `bar` (probe steps, cost limit; default none) and `crawl` (fraction; 0: off);
    `channel`: where a reporting solver sends its steps (`progress_channel`), a run-time value;
    `floor`: the least s² of the solver's gain and noise stops (run-time)."""
    budget = None
    if isinstance(solver, LevenbergMarquardt) and max_steps >= 1:
        probe, limit = (max_steps, np.inf) if bar is None else bar
        budget = (
            jnp.asarray(max_steps),
            (jnp.asarray(probe), jnp.asarray(limit, dtype=float)),
            jnp.asarray(crawl, dtype=float),
            jnp.asarray(channel),
            jnp.asarray(floor, dtype=float),
        )
        max_steps = max(max_steps, shared, MAX_STEPS)
    with failures_as_nan():
        value, code, steps, final = _solve_jit(
            residual_fn, theta0, args, solver, max_steps, jac, budget
        )
    return value, result_from_code(code), steps, final


@cached_jit
def _solve_jit(residual_fn, theta0, args, solver, max_steps, jac, budget):
    # keyed by `residual_fn`'s identity (warm for new data in `args`); outputs are plain arrays
    options = (
        dict(jac=jac)
        if budget is None
        else dict(
            jac=jac,
            budget=budget[0],
            bar=budget[1],
            crawl=budget[2],
            channel=budget[3],
            floor=budget[4],
        )
    )
    sol = optx.least_squares(
        residual_fn, solver, theta0, args, options=options, max_steps=max_steps, throw=False
    )
    # a Gauss–Newton solver's state holds the residual and its linearisation at the returned
    # point: the statistics take them from there instead of evaluating the model again
    info = getattr(sol.state, "f_info", None)
    final = None
    if jac == "fwd" and isinstance(info, optx.FunctionInfo.ResidualJac):
        final = (info.residual, info.jac.as_matrix())
    return sol.value, result_code(sol.result), sol.stats["num_steps"], final


def value_and_jacobian(residual_fn, theta, args, *, solver=None, max_steps=MAX_STEPS):
    """Residual and Jacobian of `residual_fn(θ, args)` at θ from one forward pass, compiled with
    failures as NaN like the solve.

    With `solver` (a `LevenbergMarquardt`) they come from the fit's own compiled solve run with
    a budget of one step (its first step linearises at θ; `max_steps`: the budget of the fits
    that share the program), so a fit's start and scoring compile no second copy of the model
    (`jac="fwd"`); without, from `jax.jacfwd` (one program per `residual_fn` and shapes,
    reused by `least_squares_fit`'s statistics)."""
    if solver is not None:
        theta = jnp.asarray(theta, dtype=jnp.float64)
        *_, final = _solve(residual_fn, theta, args, solver, 1, "fwd", shared=int(max_steps))
        if final is None:
            raise TypeError(f"value_and_jacobian: {type(solver).__name__} keeps no Jacobian")
        return final
    with failures_as_nan():
        return _value_and_jacobian_jit(residual_fn, theta, args)


@cached_jit
def _value_and_jacobian_jit(residual_fn, theta, args):
    def both(th):
        r = residual_fn(th, args)
        return r, r

    J, r = jax.jacfwd(both, has_aux=True)(theta)
    return r, J


def least_squares_fit(
    residual_fn,
    theta0,
    args=None,
    *,
    names,
    transform=None,
    sigma_known: bool = False,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_steps: int = 500,
    jac: str = "bwd",
    solver=None,
    optimum_tol: float | None = None,
    progress=None,
    bar: tuple | None = None,
    crawl: float = 0.0,
    floor: float = 1.0,
    throw: bool = True,
) -> FitResult:
    """Fit θ minimising ½‖residual_fn(θ, args)‖² with an optimistix least-squares solver.

    Args:
        residual_fn: (θ, args) -> residual vector (already divided by its uncertainty);
            `FAILED_RESIDUAL` marks a row where the model could not be evaluated.
        theta0: start, 1-D.
        names: parameter names for the physical vector `transform(θ)`.
        transform: θ -> physical parameter vector (differentiable); None is the identity.
        sigma_known: residuals are in units of their standard deviation (else s² is estimated).
        rtol, atol, max_steps: the default solver's Cauchy tolerances and the step budget.
        jac: how the solver differentiates the residuals (optimistix option), "bwd" (the
            default: docs/fitting.md, "Why some fit rules are set where they are") or "fwd".
        solver: an optimistix least-squares solver in place of LevenbergMarquardt(rtol, atol);
            `LevenbergMarquardt.noise_floor(...)` for residuals computed through an ODE solve.
        optimum_tol: if given, a successful stop counts only when the Gauss–Newton step still
            left is below this many standard errors in every parameter (else
            `RESULTS.short_of_optimum`): the check for the `step_tol` stop on rejected steps.
        progress: callable receiving one line per solver step (a solver with `report=True`).
        bar, crawl: the `LevenbergMarquardt` stops `options["bar"]` ((probe, limit): after
            `probe` steps a cost ‖r‖² above `limit` stops the fit) and `options["crawl"]` (a
            fraction; 0: off) of the solver module's docstring.
        floor: the least s² (RSS/(n − p), units of the residual) of the `LevenbergMarquardt`
            `gain_tol` and `noise_tol` stops (1: the residual's unit is the noise sd; 0: the
            stops count in residual variances whatever the unit).
        throw: raise `FitError` when the fit does not succeed (the default, as
            `optimistix.least_squares`); False returns the flagged `FitResult`.
    The solve is compiled once per `residual_fn` object: pass a module-level function (data in
    `args`) and repeated fits run warm.

    Returns:
        FitResult with `result` (`tribojax.RESULTS`): the solver's code, `model_failed` /
        `model_failed_at_start` if the returned residuals contain `FAILED_RESIDUAL`, or
        `short_of_optimum`. Raises `FitError` for non-convergence unless `throw=False`.
    """
    ensure_x64()
    theta0 = jnp.asarray(theta0, dtype=jnp.float64)
    if solver is None:
        solver = LevenbergMarquardt(float(rtol), float(atol))
    with progress_channel(progress) as channel:
        theta, result, steps, final = _solve(
            residual_fn,
            theta0,
            args,
            solver,
            int(max_steps),
            jac,
            bar=bar,
            crawl=crawl,
            channel=channel,
            floor=floor,
        )
    r, J = final if final is not None else value_and_jacobian(residual_fn, theta, args)
    r, J = np.asarray(r), np.asarray(J)
    message = None
    if np.any(r == FAILED_RESIDUAL) or not (np.all(np.isfinite(r)) and np.all(np.isfinite(J))):
        moved = not np.array_equal(np.asarray(theta), np.asarray(theta0))
        result = RESULTS.model_failed if moved else RESULTS.model_failed_at_start
    elif result == RESULTS.nonlinear_max_steps_reached:
        message = f"{RESULTS[result]} (max_steps = {int(max_steps)})"
    elif optimum_tol is not None and result == RESULTS.successful:
        gn = float(np.max(np.abs(np.asarray(gauss_newton_step(r, J)))))
        if not gn < optimum_tol:
            result = RESULTS.short_of_optimum
            message = (
                f"{RESULTS[result]} The step left is {gn:.3g} standard errors "
                f"(tolerance {optimum_tol:g})."
            )
    steps = int(steps)
    return thrown(
        fit_statistics(
            theta,
            r,
            J,
            names=names,
            transform=transform,
            sigma_known=sigma_known,
            result=result,
            steps=steps,
            message=message,
        ),
        throw,
    )
