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
from .._fit._measures import rms
from .._fit._result import FitResult
from .._fit._solver import LevenbergMarquardt
from .._presets import CHAIN_DEFAULTS
from .._results import RESULTS, result_name
from .._tables import wang2022_table
from ._chain_residuals import _RESIDUALS, PARAMETERS, _shown_run
from ._student_t import student_t_parameters, student_t_residuals_inverse

DEFAULTS = dict(CHAIN_DEFAULTS)
DEFAULT_FREE = ("D", "G_m", "mu_t")
"""The parameters `fit_measured_slips` frees by default (σ_s and α stay at `CHAIN_DEFAULTS`)."""
TABLES = (4, 5, 6, 7)
GN_STEP_TOL = 0.1  # converged: the remaining Gauss–Newton step < 0.1 standard errors


def measured_slips() -> np.ndarray:
    """Measured [T4, T5, T6, T7] (nm) of wang2022 Tables 4–7, shape (6, 4) (rows: Table 3's)."""
    return np.stack([wang2022_table(n)["measured_nm"] for n in TABLES], axis=1)


def paper_theory_slips() -> np.ndarray:
    """The paper's theoretical [T4, T5, T6, T7] (nm), shape (6, 4)."""
    return np.stack([wang2022_table(n)["theory_nm"] for n in TABLES], axis=1)


def rms_relative(model, measured, keep=None) -> float:
    """√mean((model/measured − 1)²) over all cells (or those where `keep` is True): the
    acceptance metric."""
    r = np.asarray(model, dtype=float) / np.asarray(measured, dtype=float) - 1.0
    return rms(r if keep is None else r[np.asarray(keep, dtype=bool)])


def symmetric_bound(measured=None) -> dict:
    """Best RMS relative residual that any model with T6 = −T4 and T7 = −T5 can reach.

    For a measured pair (a, b) and model (x, −x) the relative squared error (x/a − 1)² +
    (x/b + 1)² is least at x* = (1/a − 1/b)/(1/a² + 1/b²). Returns the bound over the 24 cells
    and the per-pair optimum (nm). The chain is symmetric to ~1e-3 (|T4 + T6|/|T4|), so this
    bounds what it can reach.
    """
    m = measured_slips() if measured is None else np.asarray(measured, dtype=float)
    model = np.empty_like(m)
    for i, j in ((0, 2), (1, 3)):
        a, b = m[:, i], m[:, j]
        x = (1 / a - 1 / b) / (1 / a**2 + 1 / b**2)
        model[:, i], model[:, j] = x, -x
    return {"rms_relative_residual": rms_relative(model, m), "best_symmetric_nm": model.tolist()}


# --- the fit -----------------------------------------------------------------------------------


class ChainFitError(RuntimeError):
    """The full-chain fit could not be carried out (names the trial point and the cause)."""


@dataclasses.dataclass(frozen=True)
class ChainFit:
    """A full-chain fit: the `FitResult` (free parameters) plus the chain's view of it.

    Attributes:
        fit: FitResult over the free parameters (θ statistics, covariance by the delta method).
        parameters: all five physical parameters (free and fixed), dict.
        free: names of the free parameters.
        model_nm, target_nm: (n, 4) phase slips at the optimum (NaN: not evaluated), the data.
        scaled_singular_values, scaled_right_vectors: SVD of the Jacobian of the residuals with
            respect to log p (elasticities); rows of the right vectors are parameter combinations,
            largest singular value first.
        wall_s: wall time of the fit (s). evaluations: residual evaluations (incl. Jacobians),
            counted when progress is shown; else LM steps + 1 (one evaluation per trial point:
            the count itself is a host callback, which would keep the fit out of the cache).
        start: the physical start.
        gauss_newton_step: the Gauss–Newton step left at the end, max |δp|/std error (module
            docstring, Convergence).
    """

    fit: FitResult
    parameters: dict
    free: tuple
    model_nm: np.ndarray
    target_nm: np.ndarray
    scaled_singular_values: np.ndarray
    scaled_right_vectors: np.ndarray
    wall_s: float
    evaluations: int
    start: dict
    gauss_newton_step: float = float("nan")

    @property
    def converged(self) -> bool:
        return self.fit.converged

    @property
    def result(self) -> RESULTS:
        """The outcome (`tribojax.RESULTS`), that of `fit`."""
        return self.fit.result

    @property
    def rms_relative_residual(self) -> float:
        return rms_relative(self.model_nm, self.target_nm)

    def combinations(self, tol=1e-3) -> list[dict]:
        """Parameter combinations (in log p) the data determine, best first; `determined` is
        False for singular values below `tol` × the largest."""
        sv = self.scaled_singular_values
        return [
            {
                "singular_value": float(s),
                "determined": bool(s > tol * sv[0]),
                "log_combination": {
                    k: float(c) for k, c in sorted(zip(self.free, v), key=lambda t: -abs(t[1]))
                },
            }
            for s, v in zip(sv, self.scaled_right_vectors)
        ]

    def as_dict(self) -> dict:
        """JSON-ready report (the `fit_measured` block of reproduction.json)."""
        f = self.fit
        resid = self.model_nm / self.target_nm - 1.0
        vac = wang2022_table(3)["vacuum_kPa"]
        cells = [
            {
                "table": n,
                "vacuum_kPa": float(vac[i]) if self.target_nm.shape[0] == len(vac) else i,
                "measured_nm": float(self.target_nm[i, j]),
                "model_nm": float(self.model_nm[i, j]),
                "rel_residual": float(resid[i, j]),
            }
            for i in range(self.target_nm.shape[0])
            for j, n in enumerate(TABLES)
        ]
        return {
            "parameters": dict(self.parameters),
            "free_parameters": list(self.free),
            "std_errors": dict(zip(f.names, f.std_errors.tolist())),
            "correlation": f.correlation.tolist(),
            "rms_relative_residual": self.rms_relative_residual,
            "converged": f.converged,
            "message": f.message,
            "result": result_name(f.result),
            "steps": f.steps,
            "residual_evaluations": self.evaluations,
            "gauss_newton_step_over_std_error": self.gauss_newton_step,
            "wall_s": self.wall_s,
            "relative_scatter": float(
                np.sqrt(np.sum(f.residuals**2) / max(f.residuals.size - len(f.names), 1))
            ),
            "singular_values_theta": f.singular_values.tolist(),
            "scaled_singular_values": self.scaled_singular_values.tolist(),
            "identifiability": self.combinations(),
            "cells": cells,
            "start": dict(self.start),
            "fixed": {k: v for k, v in self.parameters.items() if k not in self.free},
        }


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
    Returns:
        ChainFit; `result` a `tribojax.RESULTS` member, `converged` False (with `fit.message`)
        when LM did not succeed or stopped short of the optimum (module docstring,
        Convergence) — never raises for that.
    Raises:
        ValueError: bad input (names the parameter, value and allowed range).
        ChainFitError: an `equinox` runtime check inside the chain failed at a trial point
            (the message names it).
    """
    free = tuple(free)
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
                _RESIDUALS[(jac, bool(progress))],
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
