"""Fits to a user's slip run: F_s, K_τ, C_τ (and α) of wang2022's pre-slip LuGre element.

The model is wang2022 Eq 27 (consistent reading, `simulate_slip`) driven by the run's own sampled
stage acceleration (`simulate_run`); the residuals are (model slip − measured slip)/σ at every
sample. Parameters are fitted as logarithms with optimistix Levenberg–Marquardt, differentiated in
forward mode (`diffrax.ForwardMode`, `jac="fwd"`: 3–4 parameters, a long solve). The LM solve and
the Jacobian are jitted once per (record length, parameter count, t_end) and reused across runs.

Start (`slip_run_start`): the quasi-static limit of the model (C_τ from a damping ratio, and
three LM starts 0.1x, 1x, 10x it). When the body follows the stage,
the friction force is F = m·a(t) and, with C_τ's transients neglected, the bristle law (α = 1)
dz/dΔx = 1 − sgn(v)·z/z_max with z = F/K_τ integrates in closed form:

    Δx(t) = (F_s/K_τ) · Σ_k s_k·[ln(1 − s_k F_{k−1}/F_s) − ln(1 − s_k F_k/F_s)],  s_k = sgn(ΔF_k)

which is linear in 1/K_τ for fixed F_s. F_s comes from a 1-D search (1/K_τ by linear least
squares at each F_s).
"""

from __future__ import annotations

import time

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._friction._lugre import PreSlipLuGre
from .._io._slip_run import SlipRun
from .._precision import ensure_x64
from ._engine import FitResult, gauss_newton_step_jnp
from ._start import noise_scale, slip_run_start

SLIP_NAMES = ("F_s", "K_tau", "C_tau", "alpha")
_C_FACTORS = (1.0, 0.1, 10.0)
_FAILED = 1e6  # residual (in σ) where the solver failed for a trial parameter set


class _SlipResiduals(eqx.Module):
    """(model − data)/scale for a run, θ = log(F_s, K_τ, C_τ, α), plus one prior row.

    The last residual, w·(θ_α − log α_fixed), holds α at α_fixed with w = 1e6 and vanishes with
    w = 0 (α free): both cases share one compiled solve. The statistics of a fixed-α fit use
    only the data rows and the first three columns (`_subset`), i.e. the 3-parameter fit.
    """

    t_end: float = eqx.field(static=True)

    def __call__(self, theta, args):
        from .._dynamics._slip import simulate_slip

        t, profile, slip, mass, scale, log_alpha, weight = args
        p = jnp.exp(theta)
        element = PreSlipLuGre(p[0], p[1], p[2], p[3])
        sol = simulate_slip(
            element, profile, mass, ts=t, t_end=self.t_end, adjoint=dfx.ForwardMode(), throw=False
        )
        r = (sol.slip - slip) / scale
        r = jnp.where(sol.ok & jnp.isfinite(r), r, _FAILED)
        return jnp.concatenate([r, (weight * (theta[3] - log_alpha))[None]])


@eqx.filter_jit
def _lm_block(fn, theta0, args, rtol, atol, max_steps):
    sol = optx.least_squares(
        fn,
        optx.LevenbergMarquardt(rtol=rtol, atol=atol),
        theta0,
        args,
        options=dict(jac="fwd"),
        max_steps=max_steps,
        throw=False,
    )
    return sol.value, sol.result, sol.stats["num_steps"]


@eqx.filter_jit
def _residuals_and_jacobian(fn, theta, args):
    return fn(theta, args), jax.jacfwd(fn)(theta, args)


@eqx.filter_jit
def _evaluate(fn, theta, args):
    return fn(theta, args)


@eqx.filter_jit
def _costs(fn, thetas, args):
    return jax.vmap(lambda th: jnp.sum(fn(th, args) ** 2))(thetas)


def fit_statistics(theta, r, J, *, names, transform, sigma_known, converged, steps, message):
    """A FitResult from the optimum θ, its residuals r and Jacobian J (as `least_squares_fit`).

    Covariance (JᵀJ)⁻¹·s² through the SVD of J (s² = RSS/(n − p) unless σ is known), mapped to
    the physical parameters by the delta method with the Jacobian of `transform`.
    """
    r, J = np.asarray(r), np.asarray(J)
    n, p = J.shape
    u, sv, vt = np.linalg.svd(J, full_matrices=False)
    tiny = sv <= sv[0] * 1e-14
    inv_s2 = np.where(tiny, np.inf, 1.0 / np.where(tiny, 1.0, sv) ** 2)
    with np.errstate(invalid="ignore"):
        cov_theta = (vt.T * inv_s2[None, :]) @ vt
    cov_theta = np.where(np.isnan(cov_theta), np.inf, cov_theta)
    scale2 = 1.0 if sigma_known else float(r @ r) / max(n - p, 1)
    T = np.asarray(jax.jacfwd(transform)(jnp.asarray(theta)))
    with np.errstate(invalid="ignore"):
        cov = T @ (cov_theta * scale2) @ T.T
        std = np.sqrt(np.diag(cov))
        corr = cov / np.outer(std, std)
    return FitResult(
        names=tuple(names),
        values=np.asarray(transform(jnp.asarray(theta))),
        std_errors=std,
        covariance=cov,
        correlation=corr,
        theta=np.asarray(theta),
        residuals=r,
        singular_values=sv,
        converged=bool(converged),
        steps=int(steps),
        message=str(message),
    )


def gauss_newton_step(r, J) -> np.ndarray:
    """The Gauss–Newton step −(JᵀJ)⁺Jᵀr from θ, in units of θ's standard errors (σ-scaled r).

    Small entries (≪ 1) mean the remaining step is far below the statistical uncertainty.
    """
    return np.asarray(gauss_newton_step_jnp(jnp.asarray(r), jnp.asarray(J)))


def levenberg_marquardt(
    fn,
    theta0,
    args,
    *,
    names,
    transform,
    sigma_known,
    max_steps=200,
    block=10,
    rtol=1e-7,
    atol=1e-7,
    step_tol=0.05,
    stall_tol=0.25,
    subset=None,
    progress=None,
) -> FitResult:
    """LM (optimistix) in blocks of `block` steps, jitted once per problem shape.

    Converged: optimistix's own Cauchy test succeeded, or, after a block, the Gauss–Newton step
    from the current point is below `step_tol` standard errors in every parameter (the
    statistical test), or LM has stalled (½‖r‖² changed by < 1e-10 relative over the block) with
    that step below `stall_tol` standard errors. These are needed because a residual computed
    through an adaptive ODE solve (rtol 1e-6) is not smooth below ~1e-8 relative, and its
    forward-mode Jacobian (of the discretised solve) is not the slope of the noisy cost: LM
    stalls along a flat direction (here C_τ) without meeting a Cauchy test at any useful
    tolerance (measured: 200 steps at 1e-7, the cost settled to 8 digits after 10 steps and the
    Gauss–Newton step stuck at 0.01–0.08 standard errors). `progress(message)` is called
    after each block; the total is capped at `max_steps`. `subset` = (rows, cols): the residual
    rows and parameter columns the statistics (and the convergence test) use.
    """
    ensure_x64()
    theta = jnp.asarray(theta0, dtype=jnp.float64)
    steps, ok, message = 0, False, f"no convergence within max_steps = {max_steps} LM steps"
    t0 = time.perf_counter()
    cost_before = np.inf
    while True:
        n = min(block, max_steps - steps)
        if n > 0:
            theta, result, taken = _lm_block(fn, theta, args, rtol, atol, n)
            steps += int(taken)
        r, J = _residuals_and_jacobian(fn, theta, args)
        if subset is not None:
            r, J = np.asarray(r)[subset[0]], np.asarray(J)[subset[0]][:, subset[1]]
        failed = not np.all(np.asarray(r) != _FAILED)
        gn = float(np.max(np.abs(gauss_newton_step(r, J)))) if not failed else np.inf
        cost = 0.5 * float(np.sum(np.square(r)))
        stalled = abs(cost_before - cost) <= 1e-10 * cost
        cost_before = cost
        if progress is not None:
            progress(f"LM: {steps} steps, cost {cost:.8g}, Gauss-Newton step {gn:.2g} std errors, "
                     f"{time.perf_counter() - t0:.1f} s")  # fmt: skip
        if failed:
            ok, message = False, "the slip solver failed at the current parameters"
            break
        if (
            (n > 0 and result == optx.RESULTS.successful)
            or gn < step_tol
            or (stalled and gn < stall_tol)
        ):
            ok, message = True, ""
            break
        if n > 0 and result != optx.RESULTS.nonlinear_max_steps_reached:
            message = str(optx.RESULTS[result])
            break
        if steps >= max_steps:
            break
    theta = theta if subset is None else np.asarray(theta)[subset[1]]
    return fit_statistics(theta, r, J, names=names, transform=transform, sigma_known=sigma_known,
                          converged=ok, steps=steps, message=message)  # fmt: skip


# ---------------------------------------------------------------------------------------------
# start values


def _problem(run: SlipRun, alpha, scale: float):
    """Residual function and args; `alpha` None = free, else held fixed."""
    fn = _SlipResiduals(t_end=float(run.t[-1]))
    args = (
        jnp.asarray(run.t),
        run.profile(),
        jnp.asarray(run.slip),
        jnp.asarray(run.mass, dtype=jnp.float64),
        jnp.asarray(scale, dtype=jnp.float64),
        jnp.log(jnp.asarray(1.0 if alpha is None else alpha, dtype=jnp.float64)),
        jnp.asarray(0.0 if alpha is None else 1e6, dtype=jnp.float64),
    )
    return fn, args


# ---------------------------------------------------------------------------------------------
# the fit


def fit_slip_run(
    run: SlipRun,
    *,
    alpha=None,
    start=None,
    sigma=None,
    max_steps: int = 200,
    progress=None,
) -> FitResult:
    """Fit F_s (N), K_τ (N/m), C_τ (N s/m) and, if `alpha` is None, α of PreSlipLuGre to a run.

    Model: wang2022 Eq 27 (consistent reading; `simulate_run`: the run's mass and sampled
    acceleration, from rest at t = 0); residuals (model − measured slip)/σ at every sample;
    Levenberg–Marquardt on the logarithms, forward-mode Jacobian; standard errors from the
    Jacobian at the optimum (delta method).

    Args:
        run: the slip run.
        alpha: fixed bristle exponent (> 0), or None to fit it (start 1).
        start: dict of start values (keys F_s, K_tau, C_tau[, alpha]); missing keys are filled
            from `slip_run_start(run)`.
        sigma: slip noise sd (m); default the run's `noise_std`; if neither, σ is estimated from
            the residuals (s² = RSS/(n − p)).
        max_steps: LM step budget.
        progress: optional callable receiving one-line progress messages.
    Returns:
        FitResult with names ("F_s", "K_tau", "C_tau"[, "alpha"]); `fixed` holds α when fixed.
        `converged` is False (with `message`) when LM did not succeed; it never raises for that.
    Raises:
        ValueError for fewer data than parameters, a bad α/σ/start.
    """
    free_alpha = alpha is None
    names = SLIP_NAMES if free_alpha else SLIP_NAMES[:3]
    p = len(names)
    if len(run) <= p:
        raise ValueError(
            f"{run.source}: {len(run)} slip samples are too few to fit {p} parameters "
            f"{names}; need more data than parameters"
        )
    if not free_alpha:
        alpha = _positive_number(alpha, "alpha", "")
    if sigma is None:
        sigma = run.noise_std
    sigma_known = sigma is not None
    scale = _positive_number(sigma, "sigma", "m") if sigma_known else noise_scale(run.slip)
    start = dict(start or {})
    unknown = set(start) - set(SLIP_NAMES)
    if unknown:
        raise ValueError(f"start has unknown key(s) {sorted(unknown)}; allowed {SLIP_NAMES}")
    c_starts = [None] if "C_tau" in start else list(_C_FACTORS)
    if not {"F_s", "K_tau", "C_tau"} <= set(start):
        if progress is not None:
            progress("start: quasi-static F_s, K_tau; C_tau from damping ratio 0.1 (x0.1, x10)")
        start = {**slip_run_start(run), **start}
    if not free_alpha:
        start["alpha"] = alpha
    start.setdefault("alpha", 1.0)
    fn, args = _problem(run, None if free_alpha else alpha, scale)
    subset = (slice(0, len(run)), slice(0, len(names)))
    best = None
    for k, factor in enumerate(c_starts):
        st = dict(start)
        if factor is not None:
            st["C_tau"] = start["C_tau"] * factor
        theta0 = np.log([_positive_number(st[key], f"start[{key!r}]", "") for key in SLIP_NAMES])
        if progress is not None:
            head = f"start {k + 1}/{len(c_starts)}: " if len(c_starts) > 1 else "start: "
            progress(head + ", ".join(f"{key} = {st[key]:.5g}" for key in names))
        r0 = np.asarray(_evaluate(fn, jnp.asarray(theta0), args))
        if np.any(r0[:-1] == _FAILED):
            if len(c_starts) > 1:
                continue
            raise ValueError(
                f"{run.source}: the slip solver fails at the start values "
                + ", ".join(f"{key} = {st[key]:.5g}" for key in names)
                + "; give a start closer to the data (or none: slip_run_start)"
            )
        fit = levenberg_marquardt(fn, theta0, args, names=names, transform=jnp.exp,
                                  sigma_known=sigma_known, max_steps=max_steps, subset=subset,
                                  progress=progress)  # fmt: skip
        key = (not fit.converged, float(fit.residuals @ fit.residuals))
        if best is None or key < best[0]:
            best = (key, fit)
    if best is None:
        raise ValueError(f"{run.source}: the slip solver fails at every start; give a start")
    fit = best[1]
    if not free_alpha:
        fit = _with_fixed(fit, {"alpha": float(alpha)})
    return fit


def _with_fixed(fit: FitResult, fixed: dict) -> FitResult:
    import dataclasses

    return dataclasses.replace(fit, fixed={**fit.fixed, **fixed})


def _positive_number(x, name, unit):
    try:
        x = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {x!r}") from None
    if not (np.isfinite(x) and x > 0):
        unit = f" {unit}" if unit else ""
        raise ValueError(f"{name} = {x:g}{unit} is outside the allowed range (0, inf)")
    return x


# ---------------------------------------------------------------------------------------------
# surface parameters from several runs


