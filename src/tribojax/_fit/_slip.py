"""Fits to a user's slip run: F_s, K_τ, C_τ (and α) of wang2022's pre-slip LuGre element.

The model is wang2022 Eq 27 (consistent reading, `simulate_slip`) driven by the run's own sampled
stage acceleration (`simulate_run`); the residuals are (model slip − measured slip)/σ at every
sample. Parameters are fitted as logarithms by `least_squares_fit` with `NoiseFloorLM` (a
residual from an adaptive ODE solve is noisy at the solver tolerance), differentiated in forward
mode (`diffrax.ForwardMode`, `jac="fwd"`: 3–4 parameters, a long solve). The solve is compiled
once per (record length, parameter count, t_end) and reused across runs; a fixed α travels in
`args`.

Start (`slip_run_start`): the quasi-static limit of the model (C_τ from a damping ratio, and
three LM starts 0.1x, 1x, 10x it). When the body follows the stage,
the friction force is F = m·a(t) and, with C_τ's transients neglected, the bristle law (α = 1)
dz/dΔx = 1 − sgn(v)·z/z_max with z = F/K_τ integrates in closed form:

    Δx(t) = (F_s/K_τ) · Σ_k s_k·[ln(1 − s_k F_{k−1}/F_s) − ln(1 − s_k F_k/F_s)],  s_k = sgn(ΔF_k)

which is linear in 1/K_τ for fixed F_s. F_s comes from a 1-D search (1/K_τ by linear least
squares at each F_s).
"""

from __future__ import annotations

import dataclasses

import diffrax as dfx
import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._dynamics._slip import simulate_slip
from .._friction._lugre import PreSlipLuGre
from .._io._slip_run import SlipRun
from ._engine import FAILED_RESIDUAL, FitResult, least_squares_fit
from ._solver import NoiseFloorLM
from ._start import C_TAU_START_FACTORS, noise_scale, slip_run_start

SLIP_NAMES = ("F_s", "K_tau", "C_tau", "alpha")
# NoiseFloorLM's Cauchy tolerances, and the Gauss–Newton step (standard errors) that a stop may
# leave: the residuals come from an adaptive ODE solve (rtol 1e-6), not smooth below ~1e-8.
_RTOL = _ATOL = 1e-7
_OPTIMUM_TOL = 0.25
_LOG_LIMIT = 300.0  # |log p| beyond this (p > 1e130) is no physical slip parameter


class _SlipResiduals(eqx.Module):
    """(model − data)/scale for a run; θ = log(F_s, K_τ, C_τ[, α]), α from `args` if θ has 3."""

    t_end: float = eqx.field(static=True)

    def __call__(self, theta, args):
        t, profile, slip, mass, scale, log_alpha = args
        # a trial point far outside float64 (exp overflows) is a failed evaluation, which the
        # solver rejects, not an invalid element
        usable = jnp.all(jnp.isfinite(theta) & (jnp.abs(theta) < _LOG_LIMIT))
        p = jnp.exp(jnp.where(usable, theta, 0.0))
        alpha = p[3] if theta.shape[0] == 4 else jnp.exp(log_alpha)
        element = PreSlipLuGre(p[0], p[1], p[2], alpha)
        sol = simulate_slip(
            element, profile, mass, ts=t, t_end=self.t_end, adjoint=dfx.ForwardMode(), throw=False
        )
        r = (sol.slip - slip) / scale
        return jnp.where(usable & sol.ok & jnp.isfinite(r), r, FAILED_RESIDUAL)


@eqx.filter_jit
def _evaluate(fn, theta, args):
    return fn(theta, args)


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
    `least_squares_fit` with `NoiseFloorLM` on the logarithms, forward-mode Jacobian, from each
    C_τ start (the best converged fit is kept); standard errors from the Jacobian at the optimum
    (delta method).

    Args:
        run: the slip run.
        alpha: fixed bristle exponent (> 0), or None to fit it (start 1).
        start: dict of start values (keys F_s, K_tau, C_tau[, alpha]); missing keys are filled
            from `slip_run_start(run)`.
        sigma: slip noise sd (m); default the run's `noise_std`; if neither, σ is estimated from
            the residuals (s² = RSS/(n − p)).
        max_steps: LM step budget (per start).
        progress: optional callable receiving one-line progress messages (one per LM step).
    Returns:
        FitResult with names ("F_s", "K_tau", "C_tau"[, "alpha"]); `fixed` holds α when fixed.
        `result` is a `tribojax.RESULTS` member; `converged` is False (with `message`) when the
        fit did not succeed; it never raises for that.
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
    c_starts = [None] if "C_tau" in start else list(C_TAU_START_FACTORS)
    if not {"F_s", "K_tau", "C_tau"} <= set(start):
        if progress is not None:
            progress("start: quasi-static F_s, K_tau; C_tau from damping ratio 0.1 (x0.1, x10)")
        start = {**slip_run_start(run), **start}
    if not free_alpha:
        start["alpha"] = alpha
    start.setdefault("alpha", 1.0)
    fn, args = _problem(run, None if free_alpha else alpha, scale)
    best = None
    for k, factor in enumerate(c_starts):
        st = dict(start)
        if factor is not None:
            st["C_tau"] = start["C_tau"] * factor
        theta0 = np.log([_positive_number(st[key], f"start[{key!r}]", "") for key in names])
        if progress is not None:
            head = f"start {k + 1}/{len(c_starts)}: " if len(c_starts) > 1 else "start: "
            progress(head + ", ".join(f"{key} = {st[key]:.5g}" for key in names))
        r0 = np.asarray(_evaluate(fn, jnp.asarray(theta0), args))
        if np.any(r0 == FAILED_RESIDUAL):
            if len(c_starts) > 1:
                continue
            raise ValueError(
                f"{run.source}: the slip solver fails at the start values "
                + ", ".join(f"{key} = {st[key]:.5g}" for key in names)
                + "; give a start closer to the data (start=, or tribojax fit --start NAME=VALUE)"
            )
        fit = least_squares_fit(fn, theta0, args, names=names, transform=jnp.exp,
                                sigma_known=sigma_known, max_steps=max_steps, jac="fwd",
                                solver=NoiseFloorLM(_RTOL, _ATOL), optimum_tol=_OPTIMUM_TOL,
                                progress=progress)  # fmt: skip
        key = (not fit.converged, float(fit.residuals @ fit.residuals))
        if best is None or key < best[0]:
            best = (key, fit)
    if best is None:
        raise ValueError(
            f"{run.source}: the slip solver fails at every start; give a start (start=, or "
            "tribojax fit --start F_s=VALUE K_tau=VALUE C_tau=VALUE)"
        )
    fit = best[1]
    if not free_alpha:
        fit = _with_fixed(fit, {"alpha": float(alpha)})
    return fit


def _with_fixed(fit: FitResult, fixed: dict) -> FitResult:
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
