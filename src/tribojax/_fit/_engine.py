"""The fit engine: optimistix least squares, then statistics from the Jacobian at the optimum.

Parameters are fitted in unconstrained coordinates θ (log for positive quantities, etc.) and
mapped to the physical ones by a `transform` (`least_squares_fit`, `fit_statistics`).
"""

from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._checks import failures_as_nan
from .._export import cached_jit
from .._limits import MAX_STEPS
from .._precision import ensure_x64
from .._results import RESULTS, result_code, result_from_code, result_name
from ._noise import ALPHA, chi2_sf
from ._noise import noise_consistent as _noise_test
from ._solver import _PROGRESS, FAILED_RESIDUAL, LevenbergMarquardt, gauss_newton_step

# A direction of θ whose singular value is below this fraction of the largest is reported as not
# identifiable (the Jacobian is numerically rank-deficient at the square root of float64's eps).
IDENTIFIABLE_RTOL = 1e-8


class FitError(RuntimeError):
    """A fit asked to throw (`throw=True`) did not succeed; `fit` holds its `FitResult` (the
    failure is a `RESULTS` value inside, raised only at the entry point, as in optimistix)."""

    def __init__(self, fit: FitResult):
        self.fit = fit
        super().__init__(f"the fit did not succeed ({result_name(fit.result)}): {fit.message}")


def thrown(fit, throw: bool):
    """`fit` itself, or `FitError` when `throw` and the fit did not succeed (the boundary)."""
    if throw and not fit.converged:
        raise FitError(fit)
    return fit


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Outcome of a fit (NumPy arrays; physical coordinates unless stated).

    Attributes:
        names: parameter names.
        values: fitted parameters.
        std_errors: standard errors (delta method from θ).
        covariance, correlation: p×p matrices.
        theta: the unconstrained optimum.
        residuals: residuals at the optimum (as returned by the residual function).
        singular_values: of the Jacobian in θ, largest first (identifiability).
        converged: `result == RESULTS.successful` (derived from `result`; given alone, `result`
            becomes successful or `RESULTS.not_converged`).
        steps: solver steps taken.
        message: `RESULTS[result]` ("" on success), or a more specific text.
        fixed: constants held fixed in the fit (set by the caller, e.g. {"M": 1.0}).
        jacobian: ∂residuals/∂θ at the optimum, (n, p) (`least_squares_fit`; None elsewhere).
        result: the outcome, a `tribojax.RESULTS` member.
        reduced_chi2: RSS/(n − p) of the residuals (in units of the stated noise if known).
        noise_consistent: whether the residual is the stated noise (`tribojax._fit._noise.
            noise_consistent`: its χ² at level α/3, or a record model's full test, which also
            judges an estimated noise); when not, the standard errors are scaled by the
            residual. None when the noise scale was estimated and no record test applies.
        unidentifiable: the directions of θ that the data do not determine (relative singular
            value ≤ `IDENTIFIABLE_RTOL`), each {"direction": {name: component},
            "relative_singular_value": s_k/s_max}; `converged` says nothing about these.
        theta_covariance: covariance of θ itself (inf along undetermined directions).
        prediction: the model's samples at the optimum (output units; record models).
        scale: the residual unit (output units; residuals = (prediction − data)/scale).
        model: the fitted record model (`tribojax._model`), effects: names of the effects it
            carries, designs: their `EffectDesign`s (record models only).
        gain_left: the decrease of the cost that a Gauss–Newton step still predicts at the stop,
            in residual variances (record models only; a stationary stop with gain_left ≥ 1 is
            short of a minimum: `fit_record` then tries its next start).
    """

    names: tuple[str, ...]
    values: np.ndarray
    std_errors: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    theta: np.ndarray
    residuals: np.ndarray
    singular_values: np.ndarray
    converged: bool | None = None
    steps: int = 0
    message: str | None = None
    fixed: dict = dataclasses.field(default_factory=dict)
    jacobian: np.ndarray | None = None
    result: RESULTS | None = None
    reduced_chi2: float | None = None
    noise_consistent: bool | None = None
    unidentifiable: tuple = ()
    theta_covariance: np.ndarray | None = None
    prediction: np.ndarray | None = dataclasses.field(default=None, repr=False)
    scale: float | None = None
    model: object = dataclasses.field(default=None, repr=False)
    effects: tuple = ()
    designs: tuple = dataclasses.field(default=(), repr=False)
    gain_left: float | None = None

    @property
    def rss(self) -> float:
        """Σ residuals² (in units of `scale`²); inf when a residual is not finite."""
        r = np.asarray(self.residuals, dtype=float)
        return float(r @ r) if np.all(np.isfinite(r)) else float("inf")

    def __post_init__(self):
        result = self.result
        if result is None:
            if self.converged is None:
                raise TypeError("FitResult needs `result` (a tribojax.RESULTS member) or converged")
            result = RESULTS.successful if self.converged else RESULTS.not_converged
        elif not isinstance(result, RESULTS):
            result = RESULTS.promote(result)
        ok = bool(result == RESULTS.successful)
        if self.converged is not None and bool(self.converged) != ok:
            raise ValueError(
                f"converged = {self.converged} contradicts result {result_name(result)!r}"
            )
        object.__setattr__(self, "result", result)
        object.__setattr__(self, "converged", ok)
        if self.message is None:
            object.__setattr__(self, "message", str(RESULTS[result]))

    def with_result(self, result, message: str | None = None) -> FitResult:
        """A copy with another outcome (`converged` and `message` follow it)."""
        return dataclasses.replace(self, result=result, converged=None, message=message)

    def as_dict(self) -> dict:
        """Summary as plain Python numbers (non-finite entries mark unidentifiable directions)."""
        return {
            "parameters": dict(zip(self.names, self.values.tolist())),
            "std_errors": dict(zip(self.names, self.std_errors.tolist())),
            "correlation": self.correlation.tolist(),
            "converged": self.converged,
            "steps": self.steps,
            "singular_values": self.singular_values.tolist(),
            "fixed": dict(self.fixed),
            "result": result_name(self.result),
            "reduced_chi2": self.reduced_chi2,
            "noise_consistent": self.noise_consistent,
            "identified": not self.unidentifiable,
            "unidentifiable": [dict(d) for d in self.unidentifiable],
        }


OVERSTATED = 0.5
"""A reduced χ² below this, and significantly so, contradicts a stated noise from below."""


def fit_statistics(
    theta,
    r,
    J,
    *,
    names,
    transform,
    sigma_known,
    result,
    steps,
    message=None,
    noise_consistent=None,
    **extra,
):
    """A FitResult from the optimum θ, its residuals r and Jacobian J = ∂r/∂θ.

    Covariance of θ: s²(JᵀJ)⁻¹ through the SVD of J (s² = RSS/(n − p), or 1 if `sigma_known`);
    directions with singular values ≤ 1e-14 of the largest get infinite variance. Mapped to the
    physical parameters `transform(θ)` by the delta method, T·cov·Tᵀ with T = ∂transform/∂θ
    (`transform`: a callable, None for the identity, or an object whose `value_and_jacobian(θ)`
    gives both, as the record models' fits pass: one compiled program instead of eager steps).
    With `sigma_known` and a χ² that `noise_consistent` rejects (or `noise_consistent` given
    False: a record model's full test) the stated noise is contradicted by the misfit:
    `noise_consistent` is False and s² = RSS/(n − p) is used instead of 1. A residual far below
    the stated noise (reduced χ² under `OVERSTATED` and in χ²'s lower α/3 tail: an overstated
    noise) also gives `noise_consistent` False, with the stated noise's (too large) errors kept.
    """
    theta = np.asarray(theta, dtype=np.float64)
    r, J = np.asarray(r, dtype=np.float64), np.asarray(J, dtype=np.float64)
    n, p = J.shape
    # a Jacobian that is not finite (a failed evaluation) determines nothing: infinite variances
    finite = np.all(np.isfinite(J))
    _, sv, vt = np.linalg.svd(J if finite else np.zeros_like(J), full_matrices=False)
    tiny = sv <= (sv[0] if sv.size else 0.0) * 1e-14  # (no parameters: nothing is tiny)
    chi2 = float(r @ r) / max(n - p, 1)
    consistent = noise_consistent
    if consistent is None and sigma_known:  # the χ² part of the one noise test
        consistent = _noise_test(r, 1.0, n_params=p)[0]
    # a residual far below the stated noise contradicts it too (its errors are too large); they
    # are kept, not scaled down by the residual (a noiseless record would get zero errors)
    overstated = bool(consistent and sigma_known and chi2 < OVERSTATED and n > p
                      and 1.0 - chi2_sf(float(r @ r), n - p) < ALPHA / 3)  # fmt: skip
    scale2 = 1.0 if sigma_known and consistent else chi2
    consistent = False if overstated else consistent

    def delta(T):
        # T·V·S⁻¹ over the determined directions; a parameter that moves along an undetermined
        # one (singular value ~0) gets infinite variance (and no NaN from 0·inf); a component at
        # round-off level, |T·v| ≤ 1e-10·|T row|, is not a dependence
        A = (T @ vt[~tiny].T) / sv[~tiny][None, :]
        cov = scale2 * (A @ A.T)
        load = np.abs(T @ vt[tiny].T)
        with np.errstate(over="ignore"):  # a row of ~1e300 (a start far off): its norm is inf
            free = np.any(load > 1e-10 * np.linalg.norm(T, axis=1, keepdims=True), axis=1)
        cov[np.ix_(free, free)] = np.inf
        return cov

    if callable(getattr(transform, "value_and_jacobian", None)):  # one compiled program
        values, T = (np.asarray(v, dtype=np.float64) for v in transform.value_and_jacobian(theta))
    elif transform is None:  # the identity: no JAX operation
        values, T = theta.copy(), np.eye(theta.size)
    else:
        values = np.asarray(transform(jnp.asarray(theta)))
        T = np.asarray(jax.jacfwd(transform)(jnp.asarray(theta)))
    cov = delta(T)
    with np.errstate(invalid="ignore"):
        std = np.sqrt(np.diag(cov))
        corr = cov / np.outer(std, std)
    return FitResult(
        names=tuple(names), values=values, std_errors=std,
        covariance=cov, correlation=corr, theta=theta, residuals=r, singular_values=sv,
        steps=int(steps), message=message, jacobian=J, result=result, reduced_chi2=chi2,
        noise_consistent=consistent, unidentifiable=_singular_directions(sv, vt, names),
        theta_covariance=delta(np.eye(p)), **extra,
    )  # fmt: skip


def _singular_directions(sv, vt, names) -> tuple:
    """The directions of θ with singular values ≤ IDENTIFIABLE_RTOL of the largest."""
    top = sv[0] if sv.size else 0.0
    p = vt.shape[1]
    labels = list(names) if len(names) == p else [f"theta[{i}]" for i in range(p)]
    out = []
    for k in np.flatnonzero(sv <= top * IDENTIFIABLE_RTOL):
        v = vt[k] * np.sign(vt[k][np.argmax(np.abs(vt[k]))])  # largest component positive
        out.append({"direction": dict(zip(labels, v.tolist())),
                    "relative_singular_value": float(sv[k] / top) if top > 0 else 0.0})  # fmt: skip
    return tuple(out)


def _solve(residual_fn, theta0, args, solver, max_steps, jac, shared=MAX_STEPS, bar=None,
           crawl=0.0):  # fmt: skip
    """The least-squares solve: (θ, optimistix result, steps, (r, J) or None). Traced, lowered
    and compiled with failures as NaN (no host callback), and its trace stored (`cached_jit`).
    The library's `LevenbergMarquardt` takes the budget as a run-time value under a static cap
    of max(`max_steps`, `shared`): one compiled solve for every budget up to `shared`, and
    every `bar` (probe steps, cost limit; default none) and `crawl` (fraction; 0: off)."""
    budget = None
    if isinstance(solver, LevenbergMarquardt) and max_steps >= 1:
        probe, limit = (max_steps, np.inf) if bar is None else bar
        budget = (jnp.asarray(max_steps), (jnp.asarray(probe), jnp.asarray(limit, dtype=float)),
                  jnp.asarray(crawl, dtype=float))  # fmt: skip
        max_steps = max(max_steps, shared, MAX_STEPS)
    with failures_as_nan():
        value, code, steps, final = _solve_jit(residual_fn, theta0, args, solver, max_steps, jac,
                                               budget)  # fmt: skip
    return value, result_from_code(code), steps, final


@cached_jit
def _solve_jit(residual_fn, theta0, args, solver, max_steps, jac, budget):
    # keyed by `residual_fn`'s identity (warm for new data in `args`); outputs are plain arrays
    options = dict(jac=jac) if budget is None else \
        dict(jac=jac, budget=budget[0], bar=budget[1], crawl=budget[2])  # fmt: skip
    sol = optx.least_squares(residual_fn, solver, theta0, args, options=options,
                             max_steps=max_steps, throw=False)  # fmt: skip
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
    if progress is not None:
        _PROGRESS.append((progress, time.perf_counter()))
    try:
        theta, result, steps, final = _solve(residual_fn, theta0, args, solver, int(max_steps), jac,
                                             bar=bar, crawl=crawl)  # fmt: skip
    finally:
        if progress is not None:
            _PROGRESS.pop()
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
            message = (f"{RESULTS[result]} The step left is {gn:.3g} standard errors "
                       f"(tolerance {optimum_tol:g}).")  # fmt: skip
    steps = int(steps)
    return thrown(fit_statistics(theta, r, J, names=names, transform=transform,
                                 sigma_known=sigma_known, result=result, steps=steps,
                                 message=message), throw)  # fmt: skip
