"""Full-chain fit of wang2022's measured reticle slips (Tables 4–7) through the whole model.

optimistix Levenberg–Marquardt fits the free parameters of the chain `tribojax._chain`
((D, G, μ_t, σ_s) → F_s, K_τ, C_τ at Table 3's six loads, Eqs 5–24; with α → phase slips T4…T7,
Eq 27: 24 values) to the *measured* columns of Tables 4–7. The chain is the Table 1/2 pair of
`wang2022_table3_model` with D free (γ = 1.5, M = 1 fixed: G and M are exactly degenerate, see
`calibrate_table3`), T = m·a_max = 0.321 N in T/P and m = 0.321 kg in Eq 24.

Uncertainty model (stated): every measured cell has the same *relative* uncertainty s, estimated
from the fit (s² = RSS/(n − p)); residual_i = model_i/measured_i − 1. This is also the metric of
the acceptance: the RMS relative residual over the 24 cells, computed the same way for the
paper's own theoretical values.

Convergence. The slips come from an adaptive ODE solver (accurate to ~2e-4 here,
`_chain.SLIP_ATOL`); near the optimum the misfit is flat to that level along the D–G valley.
`LevenbergMarquardt.noise_floor` therefore stops on statistical grounds (the Gauss–Newton step left
is below 0.05 standard errors) or after six rejected steps in a row, and a fit counts as converged
only if the Gauss–Newton step still left is below `GN_STEP_TOL` standard errors (else
`RESULTS.short_of_optimum`). Rows where F_s <= m·a_max (the reticle would slide grossly, outside
Eq 27's pre-sliding model) or the contact fails get the residual `FAILED_RESIDUAL` (LM backs off).
"""

from __future__ import annotations

import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np

from .._chain import chain_contact as chain_contact
from .._chain import mu_min, to_physical, to_theta, wang2022_loads
from .._checks import as_f64, runtime_message
from .._fit._engine import FAILED_RESIDUAL, gauss_newton_step, least_squares_fit
from .._fit._solver import LevenbergMarquardt, restart_factors
from .._parallel import in_parallel
from .._presets import CHAIN_DEFAULTS
from ._chain_residuals import _RESIDUALS, CHAIN_LU, PARAMETERS, _shown_run
from ._chain_result import ChainFit, ChainFitError, measured_slips
from ._student_t import student_t_parameters, student_t_residuals_inverse

DEFAULTS = dict(CHAIN_DEFAULTS)
DEFAULT_FREE = ("D", "G_m", "mu_t")
"""The parameters `fit_measured_slips` frees by default (σ_s and α stay at `CHAIN_DEFAULTS`)."""
GN_STEP_TOL = 0.1  # converged: the remaining Gauss–Newton step < 0.1 standard errors
SAME_MISFIT = 5e-3  # fits within 0.5 % RMS of the best reach the same misfit
_SOLVE = ("jac", "lu", "progress", "max_steps", "rtol", "atol")


def fit_measured_slips(
    start=None,
    *,
    free=DEFAULT_FREE,
    target=None,
    loads=None,
    jac="fwd",
    max_steps=60,
    rtol=1e-3,
    atol=1e-4,
    progress=False,
    sigma=None,
    weights=None,
    log_residuals=False,
    student_t=None,
    lu="lapack",
    restarts=True,
) -> ChainFit:
    """Fit the free chain parameters to measured phase slips by Levenberg–Marquardt.

    Args:
        start: dict of physical start values (missing keys from `DEFAULTS`); also supplies the
            fixed parameters.
        free: names (subset of `PARAMETERS`) to fit; the others stay at `start`'s values.
        target: (n, 4) phase slips in nm to fit (default: the measured Tables 4–7); all cells
            finite and non-zero, and more cells than free parameters.
        loads: the n normal loads, N (default Table 3's six).
        jac: "fwd" (forward mode, the cheap direction for a few parameters: through the
            custom-JVP contact and diffrax ForwardMode) or "bwd" (reverse mode).
        max_steps, rtol, atol: LM step budget and Cauchy tolerances (optimistix: both the step in
            θ and the change of every residual below atol + rtol·|value|). The defaults match
            the chain's accuracy (module docstring, Convergence); tighter ones make LM wander
            along the flat D–G valley without lowering the misfit.
        progress: True prints one line per residual evaluation to stderr (long fits); a
            callable receives each line instead.
        sigma: (n, 4) uncertainty shape per cell, nm (default: the target itself, i.e. relative
            residuals model/measured − 1); the common scale is estimated from the fit.
        weights: (n, 4) positive weights per cell (default 1): residuals are multiplied by
            √weight (iteratively reweighted least squares, `robust_fit_measured_slips`).
        log_residuals: residuals (ln|model| − ln|target|)/sigma instead of (model − target)/sigma
            (a relative error model whose heavy-tailed form is a proper density).
        student_t: (ν, s), ν > 0 (inf: Gaussian), s > 0: minimise those residuals' Student-t
            −log-likelihood at the scale s (`student_t_residuals`; `fit.residuals` are ψ).
        lu: the slip solver's factorisation, "lapack" (default) or "auto" (`CHAIN_LU`): the
            two arithmetic settings of the chain.
        restarts: when the fit from `start` stops short of an optimum (the objective's noise
            floor or a ridge), fit again from the starts `start`·(1 ± `RESTART_STEP`) in the
            sign patterns `RESTART_SIGNS` and keep the lowest misfit (False: the one fit).
    Returns:
        ChainFit; `result` a `tribojax.RESULTS` member, `converged` False (with `fit.message`)
        when LM did not succeed or stopped short of the optimum (module docstring,
        Convergence) — never raises for that.
    Raises:
        ValueError: bad input (names the parameter, value and allowed range).
        ChainFitError: an `equinox` runtime check inside the chain failed at a trial point
            (the message names it).
    """
    kw = dict(free=free, target=target, loads=loads, jac=jac, max_steps=max_steps, rtol=rtol)
    kw.update(atol=atol, progress=progress, sigma=sigma, weights=weights, lu=lu)
    kw.update(log_residuals=log_residuals, student_t=student_t)
    first = _fit_once(start, kw)
    if first.converged or not restarts:
        return first
    starts = [_moved(first.start, first.free, f) for f in restart_factors(len(first.free))]
    fits = [first, *in_parallel([lambda s=s: _fit_once(s, kw) for s in starts])]
    return _kept(fits)


def _moved(start: dict, free, factors) -> dict:
    """`start` with the i-th free parameter multiplied by factors[i] (`restart_factors`)."""
    return {k: v * factors[free.index(k)] if k in free else v for k, v in start.items()}


def _kept(fits) -> ChainFit:
    """The fit of lowest misfit (a converged one first), with every start's outcome and the
    spread of the converged fits of the same misfit around it (`ChainFit.spread`)."""
    ok = [f for f in fits if f.converged and np.isfinite(f.rms_relative_residual)]
    best = min(ok or fits, key=lambda f: f.rms_relative_residual)
    same = [
        f for f in ok if f.rms_relative_residual <= (1 + SAME_MISFIT) * best.rms_relative_residual
    ]
    se = dict(zip(best.fit.names, best.fit.std_errors.tolist()))
    spread = {  # (none when no fit converged)
        k: max(abs(f.parameters[k] - best.parameters[k]) / se[k] for f in same)
        for k in (best.free if same else ())
    }
    summary = tuple(
        {
            "start": dict(f.start),
            "converged": f.converged,
            "rms_relative_residual": f.rms_relative_residual,
            "parameters": {k: f.parameters[k] for k in f.free},
        }
        for f in fits
    )
    wall = sum(f.wall_s for f in fits)
    return dataclasses.replace(
        best, start=fits[0].start, restarts=summary, spread=spread, wall_s=wall
    )


def _fit_once(start, options: dict) -> ChainFit:
    """One chain fit from `start` with `fit_measured_slips`' `options` (no restarts)."""
    o = options
    target, loads, sigma, weights = o["target"], o["loads"], o["sigma"], o["weights"]
    jac, lu, progress, max_steps, rtol, atol = (o[k] for k in _SOLVE)
    log_residuals, student_t = o["log_residuals"], o["student_t"]
    free = tuple(o["free"])
    if lu not in CHAIN_LU:
        raise ValueError(f"lu = {lu!r} is outside the allowed values {CHAIN_LU}")
    loads, target, sigma, weights = _checked_data(free, jac, loads, target, sigma, weights)
    inv_nu, t_scale = student_t_parameters(student_t)
    start_full = _full_start(start)
    mu_lo = mu_min(loads)
    theta_full0 = jnp.asarray(to_theta([start_full[k] for k in PARAMETERS], PARAMETERS, mu_lo))
    idx = jnp.array([PARAMETERS.index(n) for n in free])
    data = (jnp.asarray(a) for a in (target, sigma, np.sqrt(weights), float(log_residuals)))
    spread = (jnp.asarray(inv_nu), jnp.asarray(t_scale))

    def transform(theta):
        return to_physical(theta_full0.at[idx].set(theta), PARAMETERS, mu_lo)[idx]

    with _shown_run(progress, target.size) as (number, run):
        args = (theta_full0, idx, jnp.asarray(mu_lo), *data, *spread, loads, jnp.asarray(number))
        t0 = time.perf_counter()
        try:
            fit = least_squares_fit(
                _RESIDUALS[(jac, bool(progress), lu)],
                theta_full0[idx],
                args,
                names=free,
                transform=transform,
                rtol=rtol,
                atol=atol,
                max_steps=max_steps,
                jac=jac,
                solver=LevenbergMarquardt.noise_floor(float(rtol), float(atol), report=False),
                optimum_tol=GN_STEP_TOL,
                throw=False,
            )
        except RuntimeError as err:  # equinox runtime errors inside the compiled fit
            last = dict(zip(PARAMETERS, run.get("last", [])))
            raise ChainFitError(
                f"the full-chain fit failed at the trial point {last}: {runtime_message(err)} "
                "(a runtime check inside the chain failed at this trial point; try another start)"
            ) from err
        wall = time.perf_counter() - t0
        evaluations = run["n"] if progress else fit.steps + 1
    phys = np.asarray(
        to_physical(theta_full0.at[idx].set(jnp.asarray(fit.theta)), PARAMETERS, mu_lo)
    )
    model = _model_at_optimum(fit, target, sigma, weights, log_residuals, inv_nu, t_scale)
    sv, vt = _elasticities(fit, transform)
    return ChainFit(
        fit=fit,
        parameters=dict(zip(PARAMETERS, phys.tolist())),
        free=free,
        model_nm=model,
        target_nm=np.asarray(target),
        scaled_singular_values=sv,
        scaled_right_vectors=vt,
        wall_s=wall,
        evaluations=evaluations,
        start=start_full,
        gauss_newton_step=float(
            np.max(np.abs(np.asarray(gauss_newton_step(fit.residuals, fit.jacobian))))
        ),
    )


def _checked_data(free, jac, loads, target, sigma, weights):
    """(loads, target, sigma, weights) of `fit_measured_slips`, checked (ValueError naming the
    parameter) and defaulted (Table 3's loads, Tables 4–7, relative residuals, weights 1)."""
    bad = [n for n in free if n not in PARAMETERS]
    if bad or len(set(free)) != len(free) or not free:
        raise ValueError(f"free = {free!r}: names must be distinct, from {PARAMETERS}")
    if jac not in ("fwd", "bwd"):
        raise ValueError(f"jac = {jac!r} is outside the allowed values ('fwd', 'bwd')")
    loads = wang2022_loads() if loads is None else as_f64(loads, "loads")
    target = measured_slips() if target is None else np.asarray(target, dtype=float)
    if target.shape != (loads.shape[0], 4):
        raise ValueError(f"target has shape {target.shape}; expected ({loads.shape[0]}, 4)")
    if not np.all(np.isfinite(target)) or np.any(target == 0):
        i = np.argwhere(~np.isfinite(target) | (target == 0))[0]
        raise ValueError(
            f"target[{i[0]}, {i[1]}] = {target[tuple(i)]} is not allowed: relative residuals "
            "need finite, non-zero data"
        )
    if target.size <= len(free):
        raise ValueError(f"{target.size} data for {len(free)} free parameters: too few data")
    sigma = target if sigma is None else np.asarray(sigma, dtype=float)
    weights = np.ones_like(target) if weights is None else np.asarray(weights, dtype=float)
    for name, a in (("sigma", sigma), ("weights", weights)):
        if a.shape != target.shape or not np.all(np.isfinite(a)):
            raise ValueError(f"{name} must be finite with the target's shape {target.shape}")
    if np.any(sigma == 0) or np.any(weights <= 0):
        raise ValueError("sigma must be non-zero and weights > 0 in every cell")
    return loads, target, sigma, weights


def _full_start(start) -> dict:
    """All five physical start values: `start`'s, the others from `DEFAULTS`."""
    full = dict(DEFAULTS)
    for k, v in dict(start or {}).items():
        if k not in PARAMETERS:
            raise ValueError(f"start has unknown parameter {k!r}; allowed: {PARAMETERS}")
        full[k] = float(v)
    return full


def _model_at_optimum(fit, target, sigma, weights, log_residuals, inv_nu, t_scale):
    """The (n, 4) model slips (nm) from the residuals at the optimum (NaN: not evaluated)."""
    r = fit.residuals
    failed = (r == FAILED_RESIDUAL).reshape(target.shape)
    d = student_t_residuals_inverse(np.where(failed.ravel(), 0.0, r), t_scale, inv_nu)
    d = d.reshape(target.shape) / np.sqrt(weights) * sigma
    return np.asarray(np.where(failed, np.nan, target * np.exp(d) if log_residuals else d + target))


def _elasticities(fit, transform):
    """SVD (singular values, right vectors) of ∂r/∂log p = J_θ (dp/dθ)⁻¹ diag(p) (the transform
    is diagonal)."""
    dpdth = np.diag(np.asarray(jax.jacfwd(transform)(jnp.asarray(fit.theta))))
    S = fit.jacobian / dpdth[None, :] * np.asarray(fit.values)[None, :]
    _, sv, vt = np.linalg.svd(S, full_matrices=False)
    return sv, vt
