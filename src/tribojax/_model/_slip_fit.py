"""The Python entry for a slip run's fit (`fit_slip_run`): the slip-run model (`_slip`) fitted
alone from its starts (`fit_record`), as `tribojax fit` and `discover`'s baseline fit it."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._result import thrown
from .._io._slip_run import SlipRun
from .._results import RESULTS
from ._fit import MAX_STEPS, fit_record
from ._slip import slip_baseline
from ._start import slip_run_start


def fit_slip_run(
    run: SlipRun,
    *,
    alpha=1.0,
    start=None,
    sigma=None,
    max_steps: int = MAX_STEPS,
    progress=None,
    throw: bool = True,
):
    """Fit F_s (N), K_τ (N/m), C_τ (N s/m) and, if `alpha` is None, α of the slip-run model
    (by default α = 1, as `tribojax fit` and `discover`'s baseline).

    The model is `SlipBaseline` (wang2022 Eq 27, consistent reading, driven by the run's own
    sampled acceleration from rest), the same model, residual, transforms, starts and solver as
    `discover`'s baseline (`fit_record`): with the default `alpha=1` and the same samples both
    give the same parameters. Residuals (model − measured slip)/σ at every sample; parameters as
    logarithms (F_s below a soft cap of 100·m·max|a|); starts from `slip_run_start` (the
    quasi-static limit) with C_τ × (1, 0.1, 10) in turn until one converges; standard errors by
    the delta method;
    `noise_consistent` from `SlipBaseline.noise_test`.

    Args:
        run: the slip run.
        alpha: fixed bristle exponent (> 0; default 1, wang2022's law), or None to fit it
            (start 1).
        start: dict of start values (keys F_s, K_tau, C_tau[, alpha]); missing keys from
            `slip_run_start(run)`; a given C_tau is the only C_τ start.
        sigma: slip noise sd (m); default the run's `noise_std`; if neither, the residual unit is
            the first-difference estimate and the standard errors use the residual scale.
        max_steps: LM step budget (per start).
        progress: optional callable receiving one line per start and its outcome.
        throw: raise `tribojax.FitError` (holding the FitResult) when the fit does not succeed
            (default); False returns it flagged.
    Returns:
        FitResult (names ("F_s", "K_tau", "C_tau"[, "alpha"]); `fixed` holds α when fixed) with
        the fitted `model`, its `prediction` and `scale`.
    Raises:
        ValueError for fewer data than parameters, a bad α/σ/start, or a model that cannot be
        evaluated at any start.
    """
    names = ("F_s", "K_tau", "C_tau", "alpha")[: 4 if alpha is None else 3]
    if len(run) <= len(names):
        raise ValueError(
            f"{run.source}: {len(run)} slip samples are too few to fit "
            f"{len(names)} parameters {names}; need more data than parameters"
        )
    if alpha is not None:
        alpha = _positive(alpha, "alpha", "")
    start = dict(start or {})
    unknown = set(start) - {"F_s", "K_tau", "C_tau", "alpha"}
    if unknown:
        raise ValueError(
            f"start has unknown key(s) {sorted(unknown)}; allowed "
            "['F_s', 'K_tau', 'C_tau', 'alpha']"
        )
    for key, value in start.items():
        start[key] = _positive(value, f"start[{key!r}]", "")
    sigma = run.noise_std if sigma is None else _positive(sigma, "sigma", "m")
    if sigma is not None and sigma != run.noise_std:
        run = dataclasses.replace(run, noise_std=float(sigma))
    guess = (
        {**slip_run_start(run), **start} if not {"F_s", "K_tau", "C_tau"} <= set(start) else start
    )
    model = slip_baseline(run, [guess["F_s"], guess["K_tau"], guess["C_tau"]], alpha=alpha)
    starts = [model.start()] if "C_tau" in start else model.starts()
    if alpha is None:  # the α start
        starts = [np.concatenate([th[:3], [np.log(start.get("alpha", 1.0))]]) for th in starts]
    if progress is not None:
        progress(
            f"start: {len(starts)} C_tau start(s) from F_s = {guess['F_s']:.5g}, K_tau = "
            f"{guess['K_tau']:.5g}, C_tau = {guess['C_tau']:.5g}"
        )
    fit = fit_record(model, starts, max_steps=max_steps)
    if fit.result == RESULTS.model_failed_at_start:
        raise ValueError(
            f"{run.source}: the slip solver fails at the start values; give a "
            "start closer to the data (start=, or tribojax fit --start NAME=VALUE)"
        )
    if progress is not None:
        progress(f"LM: {fit.steps} steps, {'converged' if fit.converged else fit.message}")
    names = model.param_names
    p = len(names)
    fit = dataclasses.replace(
        fit,
        names=names,
        values=fit.values[:p],
        std_errors=fit.std_errors[:p],
        covariance=fit.covariance[:p, :p],
        correlation=fit.correlation[:p, :p],
    )
    fit = fit if alpha is None else dataclasses.replace(fit, fixed={"alpha": float(alpha)})
    return thrown(fit, throw)


def _positive(x, name, unit):
    try:
        x = float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {x!r}") from None
    if not (np.isfinite(x) and x > 0):
        unit = f" {unit}" if unit else ""
        raise ValueError(f"{name} = {x:g}{unit} is outside the allowed range (0, inf)")
    return x
