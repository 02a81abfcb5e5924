"""The held-out check of a record model with its effects (`heldout_residual`): each fold of
the record predicted by the model fitted on the other (the evidence `discover` weighs)."""

from __future__ import annotations

import numpy as np

from .._fit._engine import value_and_jacobian
from .._limits import MAX_STEPS
from .._parallel import in_parallel
from .._results import RESULTS
from ._fit import SOLVER, fit_model
from ._residual import _padded, padded_residual

FOLD_SHARE_MIN = 1e-3  # least share of a parameter's Jacobian energy in each held-out fold
# the held-out check's second try, where the model was not finite: `more_steps(RETRY_FACTOR)`
# (the blind record s3011: a refit's optimum that a plain evaluation could not finish within the
# model's own budget, which is also the restarts' budget; docs/discovery.md)
RETRY_FACTOR = 4


def heldout_residual(baseline, designs, x0, y=None, scale=1.0, effects=(), max_steps=MAX_STEPS):
    """Two-fold held-out residual (output units): the samples of each fold of `baseline.folds()`
    minus the model (with the effects' `designs`, their nuisance values fixed) fitted from
    x0 = [θ_b, s] on the other fold alone. Every sample is predicted once by a fit that did not
    see it. None when the model has no folds, a fold's fit fails, or a parameter has less than
    `FOLD_SHARE_MIN` of its Jacobian energy at x0 (Σ (∂r/∂x)², where it has any) in either
    fold: that fold cannot determine it, so its fit keeps the start value, which saw the
    held-out samples (why at x0: docs/discovery.md, "Held-out evidence"). Where the model is not
    finite (a solve ran out of steps) the check is done again once with
    `baseline.more_steps(RETRY_FACTOR)`.
    Each fold's fit restarts and goes on as `_fold_fit` says."""
    y = np.asarray(baseline.data().y if y is None else y, dtype=float)
    if baseline.folds() is None:  # no held-out check for this model
        return None
    out = _heldout(baseline, designs, x0, y, scale, effects, max_steps)
    wider = baseline.more_steps(RETRY_FACTOR) if out is _NOT_FINITE else None
    if wider is not None:
        out = _heldout(wider, designs, x0, y, scale, effects, max_steps)
    return None if out is _NOT_FINITE else out


_NOT_FINITE = object()  # a held-out check where the model was not finite


def _heldout(baseline, designs, x0, y, scale, effects, max_steps):
    folds = np.asarray(baseline.folds())
    xp, args = _padded(baseline, designs, x0, y, scale)
    npar = len(baseline.param_names) + sum(d.k for d in designs)
    J = np.asarray(value_and_jacobian(padded_residual, xp, args, solver=SOLVER)[1])[: y.size, :npar]
    energy = [np.sum(J[folds == k] ** 2, axis=0) for k in (0, 1)]
    total = energy[0] + energy[1]
    if not np.all(np.isfinite(total)):
        return _NOT_FINITE
    share = np.minimum(*energy)[total > 0] / total[total > 0]
    if np.any(share < FOLD_SHARE_MIN):
        return None
    out = np.empty_like(y)
    fold_fits = in_parallel(
        [
            lambda k=k: _fold_fit(
                baseline, designs, x0, y, scale, effects, max_steps, (folds != k).astype(float)
            )
            for k in (0, 1)
        ]
    )
    for k, f in enumerate(fold_fits):
        if f.result in (RESULTS.model_failed_at_start, RESULTS.model_failed) or not np.all(
            np.isfinite(f.prediction)
        ):
            return _NOT_FINITE
        if not f.converged:
            return None
        out[folds == k] = (y - f.prediction)[folds == k]
    return out


def _fold_fit(baseline, designs, x0, y, scale, effects, max_steps, weights):
    """One fold's fit, as every record-model fit: a stationary stop short of a minimum goes on
    rescaled (`fit_model`'s restarts), and one that ran out of steps goes on once from where it
    stopped (a fold fit left short would make the held-out verdict turn on where it stopped)."""
    f = fit_model(baseline, designs, x0, y, scale, effects, max_steps=max_steps, weights=weights)
    if f.result == RESULTS.nonlinear_max_steps_reached and np.all(np.isfinite(f.theta)):
        more = fit_model(
            baseline, designs, f.theta, y, scale, effects, max_steps=max_steps, weights=weights
        )
        f = more if np.isfinite(more.rss) else f
    return f
