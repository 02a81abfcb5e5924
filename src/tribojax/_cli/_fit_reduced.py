"""`tribojax fit` on a record reduced as `--decimate` asks (a slip run; a loop through the loop
model): the fit on the reduced samples and the fitted model on every original sample."""

from __future__ import annotations

import numpy as np

from .._fit._measures import rms
from .._limits import MAX_STEPS
from .._model import (
    FittedModel,
    RecordFit,
    evaluate,
    loop_residuals,
    rebuild,
)
from .._predict import RECORD_KINDS, SAVED_KEY, FitReport, saved_if_converged
from .._predict._fit_methods import RecordModel, SteadyLoop
from ._common import reduce_record


def fit_reduced(full, args, start, note, fit):
    """`fit` on the record reduced as `--decimate` asks; after a reduction, the fitted model's
    residuals on every original sample (`_full_residuals`) in "full_record"."""
    # as `discover` reduces it (a loop: its first whole cycles that fit): the same samples
    record, reduction = reduce_record(full, args, whole_cycles=full.kind == "loop")
    result, curves = fit(record, args, start, reduction, note)
    result["decimation"] = reduction.as_dict()
    resid = _full_residuals(full, result, args) if reduction.factor > 1 else None
    if resid is not None:
        result["full_record"] = _full_record(resid, result, reduction)
    return result, curves


def _full_residuals(full, result, args):
    """Model − data on every sample of the unreduced record: the saved model rebuilt on it and
    evaluated (`rebuild`, `evaluate`: what `predict` does), wu2015's steady loop by its own
    formula; None when the fit saved no model (it did not converge)."""
    if args.model == "steady":
        p = result["parameters"]
        return loop_residuals(full, args.element, p["mu_N"], p["K_d"], model="steady")
    if result.get(SAVED_KEY) is None:
        return None
    baseline, theta, _, _ = rebuild(FittedModel.from_dict(result[SAVED_KEY]), full)
    kind = RECORD_KINDS[baseline.kind]
    return evaluate(baseline, theta) - kind.measured(baseline)


def _full_record(resid, result, reduction) -> dict:
    """Residual statistics of the fitted model on every sample of the unreduced record."""
    sigma = reduction.noise_std_original
    dof = max(len(resid) - len(result["fitted"]), 1)
    return {
        "n_data": len(resid),
        "rms_residual": rms(resid),
        "reduced_chi2": float(np.sum((resid / sigma) ** 2) / dof) if sigma else None,
        "sigma": sigma,
        "what": "the fitted model on every sample of the record before the reduction",
    }


def _reduced_sigma_source(reduction, default):
    if reduction.factor == 1:
        return default
    return f"decimation: {reduction.noise_source}, scaled to the reduced samples"


def fit_slip(run, args, start, reduction, note):
    if args.alpha is None:  # the paper's law, as discover's baseline
        alpha = 1.0
    elif args.alpha == "free":
        alpha = None
    else:
        try:
            alpha = float(args.alpha)
        except ValueError:
            raise ValueError(f"--alpha must be 'free' or a number, got {args.alpha!r}") from None
    how = (
        _reduced_sigma_source(reduction, "sidecar noise_std_m")
        if run.noise_std is not None
        else "estimated from the residuals"
    )
    steps = args.max_steps or MAX_STEPS
    fit = RecordModel(alpha=alpha).fit(
        run, start=start or None, max_steps=steps, throw=False, progress=note
    )
    resid = fit.prediction - run.slip  # model − data, m
    d = FitReport(
        fit,
        run,
        "PreSlipLuGre (wang2022 Eq 27), slip at every sample",
        resid,
        run.slip,
        "m",
        run.noise_std,
        how,
        saved_if_converged(fit, str(run.source), [run]),
        {"mass_kg": run.mass},
    ).as_dict()
    curves = dict(
        x=run.t,
        data=run.slip,
        model=run.slip + resid,
        xlabel="t (s)",
        ylabel="slip Δx (m)",
        resid_x=run.t,
        resid=resid,
    )
    return d, curves


def fit_loop_reduced(loop, args, start, reduction, note):
    if len(loop.t) <= 2:
        raise ValueError(f"{loop.source}: {len(loop.t)} samples are too few to fit mu_N and K_d")
    steps = args.max_steps or MAX_STEPS
    model = args.model or "history"
    method = SteadyLoop(args.element) if model == "steady" else RecordModel(element=args.element)
    fit = method.fit(loop, start=start or None, max_steps=steps, throw=False)
    if isinstance(fit, RecordFit):  # the loop model: the samples from the first reversal on
        resid = fit.prediction - loop.f[-len(fit.prediction) :]
    else:
        resid = fit.residuals * (loop.noise_std if loop.noise_std is not None else 1.0)
    m = len(resid)  # N, on the fitted samples (the last m)
    how = "sidecar noise_std_N" if loop.noise_std is not None else "estimated from the residuals"
    how = _reduced_sigma_source(reduction, how)
    eq = 1 if args.element == "jenkins" else 2
    extra = {"normal_load_N": loop.normal_load, "frequency_Hz": loop.frequency}
    if loop.normal_load is not None:
        extra["mu"] = float(fit.values[0] / loop.normal_load)
    # the loop model is saved (not wu2015's steady formula)
    saved = (
        saved_if_converged(fit, str(loop.source), [loop]) if isinstance(fit, RecordFit) else None
    )
    label = f"{args.element} ({model} loop, wu2015 Eq {eq})"
    d = FitReport(fit, loop, label, resid, loop.f[-m:], "N", loop.noise_std, how, saved, extra)
    d = d.as_dict()
    curves = dict(
        x=loop.u[-m:],
        data=loop.f[-m:],
        model=loop.f[-m:] + resid,
        xlabel="displacement u (m)",
        ylabel="force f (N)",
        resid_x=loop.t[-m:],
        resid=resid,
    )
    return d, curves
