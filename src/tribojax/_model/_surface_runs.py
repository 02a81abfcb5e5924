"""Surface parameters D, G and μ_t from slip runs at several normal loads (two-stage fit)."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._chain import mu_min as _mu_min
from .._chain import to_physical, to_theta
from .._contact._presets import wang2022_table3_model
from .._fit._engine import least_squares_fit
from .._fit._result import FitResult, thrown
from .._presets import (
    CALIBRATED_G_M,
    CALIBRATED_M,
    CALIBRATED_MU_T,
    CALIBRATED_SIGMA_S,
    WANG2022_TABLE1_D,
)
from ._slip_fit import fit_slip_run

SURFACE_NAMES = ("D", "G_m", "mu_t")


def surface_contact_model(D, G, mu_t, *, sigma_s=CALIBRATED_SIGMA_S, M=CALIBRATED_M, throw=False):
    """The wang2022 reticle/chuck contact with free D, G (m) and μ_t (wang2022 Sections 2–3):
    `tribojax.wang2022_table3_model` with D free. Defaults: σ_s (Pa) and M of the Table 3
    calibration (docs/reproduction.md: G, μ_t, σ_s are strongly correlated; σ_s is held fixed
    here, M is exactly degenerate with G)."""
    return wang2022_table3_model(G, mu_t, sigma_s, M=M, D=D, throw=throw)


class _SurfaceResiduals(eqx.Module):
    """Whitened log differences of (F_s, K_τ, C_τ), model − stage 1, at each run's load; data in
    `args` (loads, stage-1 log values, whitening factors, μ_t lower bound): one compilation per
    (σ_s, M) and number of runs."""

    sigma_s: float = eqx.field(static=True)
    M: float = eqx.field(static=True)

    def __call__(self, theta, args):
        loads, target, whiten, mu_min = args
        D, G, mu_t = to_physical(theta, SURFACE_NAMES, mu_min)  # the chain's one mapping
        model_fn = surface_contact_model(D, G, mu_t, sigma_s=self.sigma_s, M=self.M)
        out = jax.vmap(model_fn)(loads)
        model = jnp.log(jnp.stack([out.F_s, out.K_tau, out.C_tau], axis=1))
        return jnp.einsum("nij,nj->ni", whiten, model - target).ravel()


def fit_surface_from_runs(
    runs,
    *,
    alpha=1.0,
    start=(WANG2022_TABLE1_D, CALIBRATED_G_M, CALIBRATED_MU_T),
    sigma_s=CALIBRATED_SIGMA_S,
    M=CALIBRATED_M,
    fits=None,
    progress=None,
    throw: bool = True,
) -> FitResult:
    """Fit D, G (m) and μ_t jointly to slip runs at different normal loads (two-stage).

    Stage 1: each run's F_s, K_τ, C_τ by `fit_slip_run` (α fixed), with their covariance.
    Stage 2: D, G, μ_t of `surface_contact_model` (wang2022 Eqs 5–24 → F_s, K_τ, C_τ at each run's
    `normal_load`) by Levenberg–Marquardt on the whitened differences L_i⁻¹(log p_model − log p̂_i),
    L_i the Cholesky factor of run i's covariance of log(F_s, K_τ, C_τ). To first order this is
    the joint full-chain fit of all slip samples (the slip enters only through F_s, K_τ, C_τ of
    each run), at a fraction of the cost; its standard errors carry the stage-1 uncertainties.

    Args:
        runs: SlipRun records, each with `normal_load` (N) set; at least 2 (6 data ≥ 3 params).
        alpha: the bristle exponent used for every run.
        start: (D, G in m, μ_t), inside the fit's box: 2.05 < D < 2.98, 1e-11 < G < 1e-5 m,
            μ_t > T/P at the smallest load (`tribojax._chain.to_theta`).
        sigma_s, M: fixed strength (Pa) and number of ridges of the contact model.
        fits: stage-1 FitResults to reuse (one per run), else computed.
        progress: optional callable for progress lines.
        throw: raise `FitError` if the fit does not converge (False: return it flagged).
    Returns:
        FitResult names ("D", "G_m", "mu_t"); `fixed` holds α, σ_s, M and the stage-1 values.
    Raises:
        ValueError: a run without normal_load, fewer than 2 runs, a start outside the box, a
        stage-1 fit that did not converge.
    """
    runs = list(runs)
    if len(runs) < 2:
        raise ValueError(
            f"{len(runs)} run(s) give {3 * len(runs)} data for 3 parameters (D, G, mu_t); "
            "need runs at 2 or more normal loads"
        )
    missing = [r.source for r in runs if r.normal_load is None]
    if missing:
        raise ValueError(
            f"{missing[0]}: normal_load_N is required for the surface fit (set it in the sidecar)"
        )
    if fits is None:
        fits = []
        for i, run in enumerate(runs):
            if progress is not None:
                progress(f"run {i + 1}/{len(runs)} ({run.source}, {run.normal_load:g} N)")
            fits.append(fit_slip_run(run, alpha=alpha, progress=progress, throw=False))
    for run, fit in zip(runs, fits):
        if not fit.converged:
            raise ValueError(f"{run.source}: the slip fit did not converge ({fit.message})")
    loads = jnp.asarray([r.normal_load for r in runs])
    target = jnp.asarray(np.stack([f.theta[:3] for f in fits]))
    whiten = []
    for f in fits:
        inv_p = 1.0 / f.values[:3]
        cov = f.covariance[:3, :3] * np.outer(inv_p, inv_p)
        whiten.append(np.linalg.inv(np.linalg.cholesky(cov)))
    whiten = jnp.asarray(np.stack(whiten))
    mu_min = _mu_min(loads)

    theta0 = jnp.asarray(to_theta(start, SURFACE_NAMES, mu_min))  # ValueError outside the box
    if progress is not None:
        progress("surface: D, G, mu_t from the runs' F_s, K_tau, C_tau")
    fit = least_squares_fit(
        _SurfaceResiduals(float(sigma_s), float(M)),
        theta0,
        (loads, target, whiten, jnp.asarray(mu_min)),
        names=SURFACE_NAMES,
        transform=lambda th: to_physical(th, SURFACE_NAMES, mu_min),
        sigma_known=True,
        throw=False,
    )
    fixed = {
        "alpha": float(alpha),
        "sigma_s_Pa": float(sigma_s),
        "M": float(M),
        "loads_N": [float(x) for x in loads],
        "stage1": [dict(zip(f.names, f.values.tolist())) for f in fits],
    }
    return thrown(dataclasses.replace(fit, fixed=fixed), throw)
