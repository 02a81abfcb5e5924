"""Scoring of candidate effects at the current fit: the columns ∂y/∂s of a design, the Rao
score statistic and ΔBIC. The fit itself is `tribojax._model.fit_model`."""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._fit._engine import value_and_jacobian
from .._fit._measures import delta_bic
from .._fit._noise import ar1_inflation
from .._model import K_MAX, SOLVER, EffectDesign, pack_designs, padded_args, padded_residual


def _knob_jacobian(baseline, theta_b, knobs) -> np.ndarray:
    """∂y/∂knobs (n, n_knobs) at (θ_b, knobs), output units: the residual Jacobian from the
    fit's own compiled solve (`value_and_jacobian(..., solver=SOLVER)`: one step) with the knobs
    as the padded strengths, K_MAX knobs per call, so scoring compiles no second copy of the
    model and its Jacobian. NaN columns where the model is not finite or a check inside it fails."""
    p, m = len(theta_b), len(knobs)
    n = baseline.data().y.shape[0]
    x = jnp.asarray(np.concatenate([theta_b, np.zeros(K_MAX)]), dtype=jnp.float64)
    out = np.empty((n, m))
    for j in range(0, m, K_MAX):
        k = min(K_MAX, m - j)
        gain = np.zeros((m, K_MAX))
        gain[j : j + k, :k] = np.eye(k)
        args = padded_args(baseline, knobs, gain, np.zeros((n, K_MAX)), k, np.zeros(n), 1.0)
        try:
            r, J = (
                np.asarray(v) for v in value_and_jacobian(padded_residual, x, args, solver=SOLVER)
            )
        except eqx.EquinoxRuntimeError:  # a check inside the model failed
            out[:, j : j + k] = np.nan
            continue
        out[:, j : j + k] = J[:n, p : p + k] if np.all(np.isfinite(r[:n])) else np.nan
    return out


def _design_knobs(baseline, state, design: EffectDesign):
    """The knob vector at which `design`'s columns need ∂y/∂knobs (None: they do not)."""
    if design.columns is not None or design.knob_gain is None or not np.any(design.knob_gain):
        return None
    base, gain, _ = pack_designs(baseline, state.designs)
    p = len(baseline.param_names)
    knobs = base + gain[:, : state.theta.size - p] @ state.theta[p:]
    for key, value in design.knob_set.items():
        knobs[baseline.knob_names.index(key)] = value
    return knobs


def _knob_key(knobs):
    return tuple(np.round(knobs, 12))


def prefetch_columns(baseline, state, designs, knob_cache: dict) -> None:
    """Fill `knob_cache` with the knob Jacobians that `_columns` of `designs` will need (e.g.
    one per Stribeck grid v_s), one after another: two of these programs executed side by side
    on a slip run of 5,000 samples never returned (XLA:CPU, jax 0.10.2, 2 cores, failures as
    NaN: every thread waiting, none computing; docs/performance.md)."""
    p = len(baseline.param_names)
    todo = {}
    for d in designs:
        knobs = _design_knobs(baseline, state, d)
        if knobs is not None and _knob_key(knobs) not in knob_cache:
            todo[_knob_key(knobs)] = knobs
    results = [_knob_jacobian(baseline, state.theta[:p], k) for k in todo.values()]
    knob_cache.update(zip(todo, results))


def _columns(baseline, state, design: EffectDesign, knob_cache: dict) -> np.ndarray:
    """∂y/∂s of `design` added to the fitted `state` (n, k), output units."""
    if design.columns is not None:
        return np.asarray(design.columns)
    p, n = len(baseline.param_names), baseline.data().y.shape[0]
    cols = np.zeros((n, design.k))
    knobs = _design_knobs(baseline, state, design)
    if knobs is not None:
        key = _knob_key(knobs)
        if key not in knob_cache:
            knob_cache[key] = _knob_jacobian(baseline, state.theta[:p], knobs)
        cols = cols + knob_cache[key] @ design.knob_gain
    if design.basis is not None:
        cols = cols + design.basis
    return cols


def _score(r, J_cur, cols):
    """Rao score (LM) statistic n·‖P r‖²/‖r‖² for the new columns after projecting out the
    current model's Jacobian; returns (S, rank)."""
    q, _ = np.linalg.qr(J_cur)
    c = cols - q @ (q.T @ cols)
    if not np.all(np.isfinite(c)):
        return 0.0, 0
    u, sv, _ = np.linalg.svd(c, full_matrices=False)
    rank = int(np.sum(sv > sv[0] * 1e-9)) if sv.size and sv[0] > 0 else 0
    if rank == 0:
        return 0.0, 0
    proj = u[:, :rank].T @ r
    return float(r.size * (proj @ proj) / (r @ r)), rank


def _delta_bic(rss1, rss0, n, dk, rho):
    """ΔBIC of the augmented vs the current model, Gaussian errors with unknown variance and an
    AR(1) variance inflation c = (1+ρ)/(1−ρ) of the log-likelihood ratio (ρ from the
    augmented model's residuals)."""
    return delta_bic(rss1, rss0, n, dk, ar1_inflation(rho))
