"""Refits of the discovery workflow: the starts of a candidate's refit, the further grid seeds,
the noise model sharpened by each refit, and a refit that only moved the current model's own
optimum."""

from __future__ import annotations

import numpy as np

from .._fit._measures import bic
from .._fit._noise import residual_rho
from .._model import MAX_STEPS, fit_model
from ._fitting import _columns, _delta_bic
from ._parallel import in_parallel


def _refit(baseline, state, design, name, y, scale, r, cache):
    """Fit the model augmented by `design`: from one Gauss–Newton step of the augmented model
    (the step the score test looks along), and from the current fit with the new strengths at
    zero when that fails or ends above the current cost (the nested model's optimum is a point
    of the augmented model, so ending above it is a local minimum); then from each of the
    design's own `starts`; keep the lowest cost. (Stopping the starts once a fit passed the
    noise test lost the better optimum: a hidden-Stribeck record where δ at its bound passed
    with 1.15 noise variances, the next start reached 1.00, and `vibration` won on ΔBIC.)

    Measured on a hidden-Stribeck slip record (2 kPa, 0.1 nm noise, seed 2): the zero start
    stopped at δ = 0.044 with 2.1x the noise left; the Gauss–Newton start reached δ = 0.10 (the
    hidden 0.1) at the noise level.
    """
    zero = np.concatenate([state.theta, np.zeros(design.k)])
    designs, names = state.designs + (design,), state.effects + (name,)

    def fit_from(x0):
        return lambda: fit_model(baseline, designs, x0, y, scale, names)

    first = []
    A = np.concatenate([state.jacobian, _columns(baseline, state, design, cache) / scale], axis=1)
    if np.all(np.isfinite(A)):
        step = np.linalg.lstsq(A, r, rcond=None)[0]
        p = state.theta.size
        first.append(fit_from(np.concatenate([state.theta + step[:p], step[p:]])))
    starts = [fit_from(np.concatenate([state.theta, np.asarray(s0, dtype=float)]))
              for s0 in design.starts]  # fmt: skip
    # independent fits run side by side (`in_parallel`); the zero start, when the Gauss–Newton
    # start needs it, on this thread meanwhile
    running = in_parallel([*first, *starts], wait=False)
    fits = [running[0].result()] if first else []
    if not fits or not fits[0].converged or not fits[0].rss <= state.rss:
        fits.append(fit_from(zero)())
    fits += [f.result() for f in running[len(first) :]]
    good = [f for f in fits if f.converged and np.isfinite(f.rss)]
    if not good:
        # a fit that ran out of steps while still descending (e.g. an unidentified F_s walking
        # to its bound: a hidden position error at 20 kPa, 128 steps) goes on from where it
        # stopped, once
        run = [f for f in fits if np.isfinite(f.rss) and f.steps >= MAX_STEPS]
        if run:
            fits.append(fit_model(baseline, designs, min(run, key=lambda f: f.rss).theta, y, scale,
                             names))  # fmt: skip
            good = [f for f in fits[-1:] if f.converged and np.isfinite(f.rss)]
    return min(good, key=lambda f: f.rss) if good else fits[-1]


def _apart(d1, d2):
    if d1.k != d2.k:  # another number of strengths: another model (e.g. a drift's degree)
        return True
    n1, n2 = d1.nuisance, d2.nuisance
    switch = [k for k in n1 if n1[k] in (0.0, 1.0) or n2[k] in (0.0, 1.0)]
    if any(n1[k] != n2[k] for k in switch):  # another form (e.g. a mode's static part): apart
        return True
    rest = [k for k in n1 if k not in switch]
    return bool(rest) and all(abs(np.log10(abs(n1[k]) / abs(n2[k]))) >= 1 for k in rest)


def _bic(fit, design, n):
    """BIC with k + nuisance parameters: compares refits of one effect's designs (the RSS
    alone when they have as many parameters)."""
    return bic(fit.rss, n, design.k + design.n_nuisance)


def _seeds(scored, n):
    """Further refit starts: the best-scoring grid designs a decade from the chosen ones."""
    chosen = [scored[0][4]]
    for z in scored[1:]:
        if len(chosen) >= n:
            break
        if z[3] and z[4].nuisance and all(_apart(z[4], c) for c in chosen):
            chosen.append(z[4])
    return chosen[1:]


def _sharpen(baseline, fit, y, noise, estimated):
    """Update the noise model `noise` ({"sigma", "rho", "hat"}) from `fit`'s residual when its
    first-difference estimate σ̂ is below the smallest seen so far ("hat"): then ρ̂ is taken from
    it, and σ too when σ is estimated (not given in the record). σ̂ from a residual that still
    holds a misfit is inflated by it, and ρ̂ with it (measured: σ̂ 4.6x the true σ and ρ̂ at its
    0.95 bound on a hidden-Stribeck record, so that a refit leaving 3.8 σ of misfit passed as
    noise); every refit's residual is a further estimate, the smallest the least contaminated."""
    if not (fit.converged and np.all(np.isfinite(fit.prediction))):
        return
    s_new, rho_new = baseline.noise_model(y - fit.prediction)
    if 0 < s_new < noise["hat"]:
        noise["hat"], noise["rho"] = float(s_new), float(rho_new)
        if estimated:
            noise["sigma"] = float(s_new)


MAX_MOVES = 2  # times a refit may replace the current model by a better optimum of itself


def _moved_optimum(baseline, state, best, y, scale, threshold):
    """The current model refitted from `best`'s optimum (its new strengths dropped) when those
    strengths are all zero within 2 standard errors and dropping them costs no significant ΔBIC:
    the refit's gain came from moving the current model's own parameters to a better optimum,
    not from the effect (measured: a lagged slip reading, 0.6 kPa, where `load_coupling` was
    added with κ = 0.0006 ± 0.0004 per g and 24 noise sd of misfit went to 0.2). Else None."""
    k = best.designs[-1].k
    s, se = best.theta[-k:], np.sqrt(np.abs(np.diag(best.theta_covariance)))[-k:]
    if np.any(np.abs(s) > 2 * se) or not np.all(np.isfinite(se)):
        return None
    f = fit_model(baseline, state.designs, best.theta[:-k], y, scale, state.effects)
    if not (f.converged and np.isfinite(f.rss) and f.rss < state.rss):
        return None
    dk = best.designs[-1].k + best.designs[-1].n_nuisance
    if _delta_bic(best.rss, f.rss, y.size, dk, residual_rho(y - best.prediction)) < threshold:
        return None  # the effect still earns its place against the moved model
    return f
