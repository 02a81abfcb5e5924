"""`tribojax fit` on measured records: history fits of loops and friction-curve fits, each the
fit.json dictionary (`tribojax.FitReport`) and the plot curves."""

from __future__ import annotations

import numpy as np

from .._fit._measures import bic
from .._io._friction_curve import FrictionCurve
from .._limits import DEVICE_MODELS, ELEMENT_MODELS, MAX_STEPS
from .._model._history_fit import predict_history
from .._model._history_model import HISTORY_MODELS
from .._predict import FitReport, saved_if_converged
from .._predict._fit_methods import History, SteadyLaw, fit
from ._common import CommandError

HISTORY_CHOICES = (*ELEMENT_MODELS, *DEVICE_MODELS)
"""`--model` values fitted through a history (`best` chooses among `best_candidates`)."""


def best_candidates(loops) -> tuple[str, ...]:
    """The models `--model best` compares on these records: every element, and the band brake
    when every record is a band brake's (its set tension known)."""
    device = all(lp.band_tension is not None for lp in loops)
    return (*ELEMENT_MODELS, *DEVICE_MODELS) if device else ELEMENT_MODELS


def _law_name(names) -> str:
    """The tension law a history fit has (`TENSION_LAWS`), from its parameter names."""
    if any(n.startswith("gamma") for n in names):
        return "growing"
    return "residual" if any(n.startswith("T_res") for n in names) else "proportional"


def fit_history_record(
    loops,
    model: str,
    max_steps: int | None,
    start: dict,
    decimate: int = 1,
    mixed_scales: bool = False,
    n_starts=None,
    tension_law: str = "auto",
    fixed=None,
    band_tension=None,
):
    """Fit `model` (or every candidate for "best", `best_candidates`, chosen by the lowest BIC
    over the records together) through the
    displacement history of a loop or of several loops together (one parameter set), on every
    `decimate`-th sample, with at most `max_steps` LM steps (None: `MAX_STEPS`) from the
    `start` values given; `n_starts`: Bouc–Wen's starts of n (None: its default);
    `tension_law`: how the slip forces follow the band tension; `fixed`, `band_tension`: the
    parameters held and the tension the slip forces belong to (`fit_history`)."""
    loops = list(loops) if isinstance(loops, list | tuple) else [loops]
    names = best_candidates(loops) if model == "best" else (model,)
    fits = {}
    for name in names:
        given = {k: v for k, v in start.items() if k in dict(HISTORY_MODELS[name])}
        steps = max_steps or MAX_STEPS
        starts = None if n_starts is None else tuple(n_starts)
        method = History(
            name,
            decimate=decimate,
            mixed_scales=mixed_scales,
            n_starts=starts,
            tension_law=tension_law,
            fixed=tuple((fixed or {}).items()),
            band_tension=band_tension,
        )
        fits[name] = fit(loops, method, start=given or None, max_steps=steps, throw=False)
    each = {k: [predict_history(h, lp) for lp in loops] for k, h in fits.items()}
    pred = {k: np.concatenate([force for force, _ in v]) for k, v in each.items()}
    f = np.concatenate([lp.f[::decimate] for lp in loops])
    n = f.size
    scores = {
        k: bic(float(np.sum((pred[k] - f) ** 2)), n, len(h.fit.names)) for k, h in fits.items()
    }
    best = min(scores, key=scores.get)
    h = fits[best]
    resid = pred[best] - f
    stated = [lp.noise_std for lp in loops]
    if all(v is not None for v in stated):  # χ² against it (`fit_history`'s noise rule)
        sigma, how = float(np.sqrt(np.mean(np.square(stated)))), "sidecar noise_std_N"
    else:
        sigma, how = None, "first-difference estimate of each record's residual"
    source = "; ".join(str(lp.source) for lp in loops)
    extra = dict(
        nrmse=h.nrmse,
        route="history",
        bic=scores[best],
        decimate=decimate,
        normal_load_N=loops[0].normal_load,
        frequency_Hz=loops[0].frequency,
        band_tension_N=h.band_tension,
        tension_law=_law_name(h.names) if h.band_tension is not None else None,
    )
    if "bouc_wen" in names and n_starts is not None:
        extra["n_starts"] = [float(v) for v in n_starts]
    saved = saved_if_converged(h, source, loops)
    d = FitReport(h.fit, loops[0], best, resid, f, "N", sigma, how, saved, extra).as_dict()
    if len(loops) > 1:
        d.update(
            source=source,
            records=[
                {
                    "source": str(lp.source),
                    "n_data": int(lp.f[::decimate].size),
                    "nrmse": float(e),
                    "band_tension_N": lp.band_tension,
                }
                for lp, (_, e) in zip(loops, each[best])
            ],
        )
    if model == "best":
        d["selected_by"] = "bic"
        d["candidates"] = {
            k: {
                "nrmse": f.nrmse,
                "bic": scores[k],
                "converged": f.fit.converged,
                "parameters": dict(zip(f.fit.names, f.fit.values.tolist())),
            }
            for k, f in fits.items()
        }
    t, offset = [], 0.0
    for lp in loops:  # records one after another on the plot's time axis
        t.append(lp.t[::decimate] - lp.t[0] + offset)
        offset = t[-1][-1] + (lp.t[1] - lp.t[0])
    u = np.concatenate([lp.u[::decimate] for lp in loops])
    curves = dict(
        x=u,
        data=f,
        model=pred[best],
        xlabel="displacement u (m)",
        ylabel="force f (N)",
        resid_x=np.concatenate(t),
        resid=resid,
    )
    return d, curves


def fit_curve_record(curve: FrictionCurve, model: str, max_steps: int | None):
    """Fit the LuGre steady law with a direction asymmetry to a friction curve, with at most
    `max_steps` LM steps (None: the curve fit's own budget)."""
    if model not in ("lugre", "best"):
        raise CommandError(f"--model {model} does not apply to a friction curve; use lugre or best")
    law = fit(curve, SteadyLaw(), max_steps=max_steps, throw=False)
    resid = law.residuals * curve.friction_error
    unit = curve.units["friction_unit"]
    sigma = float(np.median(curve.friction_error))
    sides = {
        side: fit(curve, SteadyLaw(sign), max_steps=max_steps, throw=False).as_dict()
        for side, sign in (("positive", 1), ("negative", -1))
    }
    extra = dict(route="steady law with direction asymmetry T0", units=curve.units)
    d = FitReport(
        law,
        curve,
        "lugre",
        resid,
        curve.friction,
        unit,
        sigma,
        "per-point scatter / sqrt(samples)",
        saved_if_converged(law, str(curve.source), [curve]),
        {**extra, "per_direction": sides},
    ).as_dict()
    curves = dict(
        x=curve.velocity,
        data=curve.friction,
        model=curve.friction + resid,
        xlabel=f"velocity ({curve.units['velocity_unit']})",
        ylabel=f"friction ({unit})",
        resid_x=curve.velocity,
        resid=resid,
    )
    return d, curves
