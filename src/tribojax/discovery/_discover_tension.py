"""Discovery over records at several band tensions: which parts of the tension law they demand.

A history model (default the band brake) is fitted to all records together with its slip forces
in proportion to the band tension (the capstan law: the baseline); then, in turn, the law's two
components are tried as effects (`_history_model` docstring):

    residual_tension   T_res: a slip force that stays when the band is slack (the drag at 0 lb)
    tension_growth     γ: the wrap μφ grows with the tension (s(T) grows faster than T)

A component is kept when it lowers BIC by more than the threshold and the law with it, fitted to
the first two thirds of every record, predicts their last third better than the law without it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._measures import bic, nrmse
from .._io._hysteresis_loop import HysteresisLoop
from .._limits import TENSION_LAWS
from .._model._history_fit import fit_history, predict_history
from .._model._history_model import HISTORY_MODELS
from ._discover import DELTA_BIC_THRESHOLD

TENSION_EFFECTS = (("residual_tension", "residual"), ("tension_growth", "growing"))
HELDOUT_SHARE = 1.0 / 3.0  # the later part of every record, predicted by a fit to the rest


@dataclasses.dataclass(frozen=True)
class TensionDiscovery:
    """The result of `discover_tension`: the baseline (proportional law) and final fits
    (`HistoryFit`), the effects kept, each candidate's figures, the records' tensions (N) and
    the settings."""

    baseline: object
    final: object
    effects: tuple
    candidates: tuple
    records: tuple
    settings: dict

    @property
    def law(self) -> str:
        """The final tension law: "proportional", "residual" or "growing" (`fit_history`)."""
        return dict(TENSION_EFFECTS).get(self.effects[-1], "") if self.effects else "proportional"

    @property
    def converged(self) -> bool:
        """Whether the final fit converged."""
        return bool(self.final.fit.converged)

    @property
    def verdict(self) -> str:
        """ "explained" (effects kept, the final fit consistent with the noise), "partly_explained"
        (effects kept, a misfit left), "none" (no effect, the baseline consistent) or
        "unexplained" (no effect, a misfit left)."""
        return verdict_of(self.effects, bool(self.final.fit.noise_consistent))

    def as_dict(self) -> dict:
        """discovery.json's dictionary (`tribojax discover` adds "source" and "fitted_model")."""
        return report_dict("tension", self, self.final, tension_law=self.law)

    def summary(self) -> str:
        """The lines `tribojax discover` prints."""
        lines = [f"baseline: {self.settings['model']} with the proportional (capstan) law"]
        lines += candidate_lines(self.candidates)
        lines.append(f"verdict: {self.verdict}; effects {list(self.effects) or 'none'}")
        return "\n".join(lines)


def report_dict(kind: str, report, final, **extra) -> dict:
    """The keys of a multi-record discovery.json (`extra` after "effects")."""
    return {
        "kind": kind,
        "effect": report.effects[0] if report.effects else "none",
        "verdict": report.verdict,
        "effects": list(report.effects),
        **extra,
        "converged": report.converged,
        "candidates": [dict(c) for c in report.candidates],
        "records": [dict(r) for r in report.records],
        "baseline_fit": report.baseline.as_dict(),
        "final_fit": final.as_dict(),
        "settings": dict(report.settings),
    }


def candidate_lines(candidates) -> list:
    """One printed line per candidate: ΔBIC, the held-out check and whether it was kept."""
    lines = []
    for c in candidates:
        held = c["heldout"]
        keep = "kept" if c["accepted"] else f"not kept ({c['reason']})"
        lines.append(
            f"  {c['name']}: dBIC {c['delta_bic']:.4g}, last third of each record held out: "
            f"NRMSE {held['nrmse_before']:.3g} -> {held['nrmse_after']:.3g}; {keep}"
        )
    return lines


def verdict_of(effects, consistent: bool) -> str:
    """A multi-record discovery's verdict from its effects and the final noise test."""
    if effects:
        return "explained" if consistent else "partly_explained"
    return "none" if consistent else "unexplained"


def _fit_law(loops, model, law, start, kw):
    """`fit_history` of `loops` under `law`; the proportional law leaves a record at 0 N no slip
    force (a slack band is its offset alone, `_predict`), so it is fitted to the others."""
    use = [lp for lp in loops if lp.band_tension > 0] if law == "proportional" else loops
    return fit_history(use, model, tension_law=law, start=start, **kw)


def _predict(fit, lp) -> np.ndarray:
    """Force (N) of `fit` along record `lp`, every `fit.decimate`-th sample: a record at 0 N
    under the proportional law is its mean (no slip force; its offset)."""
    f = np.asarray(lp.f, dtype=float)[:: fit.decimate]
    if lp.band_tension == 0 and not any(n.startswith("T_res") for n in fit.names):
        return np.full_like(f, np.mean(f))
    return np.asarray(predict_history(fit, lp)[0])


def _scores(fit, loops) -> tuple:
    """(BIC, NRMSE of each record) of a history fit: BIC from the residuals in units of each
    record's force sd (the weighting the fit minimises, fixed by the records: the same for
    every law)."""
    rss, n, each = misfit(fit, loops)
    return bic(rss, n, len(fit.fit.names)), each


def misfit(fit, loops) -> tuple:
    """(RSS in units of each record's force sd, samples, NRMSE of each record) of a history
    fit on `loops` (every `fit.decimate`-th sample)."""
    rss, n, each = 0.0, 0, []
    for lp in loops:
        f = np.asarray(lp.f, dtype=float)[:: fit.decimate]
        r = _predict(fit, lp) - f
        rss += float(np.sum((r / np.std(f)) ** 2))
        n += f.size
        each.append(nrmse(r, f))
    return rss, n, each


def _first_part(loops) -> tuple:
    """(each record's first 1 − `HELDOUT_SHARE` of samples as a record, the cut indices)."""
    cut = [int(round((1.0 - HELDOUT_SHARE) * lp.t.size)) for lp in loops]
    first = [
        dataclasses.replace(lp, t=lp.t[:m], u=lp.u[:m], f=lp.f[:m]) for lp, m in zip(loops, cut)
    ]
    return first, cut


def _heldout_nrmse(fit, loops, cut) -> float:
    """Mean NRMSE over the records of the samples after each cut, predicted by `fit`."""
    errs = []
    for lp, m in zip(loops, cut):
        f = np.asarray(lp.f, dtype=float)[:: fit.decimate]
        k = -(-m // fit.decimate)  # the first decimated sample not fitted
        errs.append(nrmse(_predict(fit, lp)[k:] - f[k:], f[k:]))
    return float(np.mean(errs))


def _values(fit) -> dict:
    return dict(zip(fit.names, fit.values.tolist()))


def discover_tension(
    loops,
    model: str = "band_brake",
    *,
    decimate: int = 1,
    delta_bic_threshold: float = DELTA_BIC_THRESHOLD,
    band_tension=None,
) -> TensionDiscovery:
    """Which components of the tension law (module docstring) records at several band tensions
    demand, as discovery's effects `residual_tension` and `tension_growth`.

    Args:
        loops: `HysteresisLoop`s (histories), each with its `band_tension` (N), at two or more
            distinct tensions.
        model: the history element (`fit_history`'s models; default "band_brake").
        decimate: every `decimate`-th sample is fitted (1: all).
        delta_bic_threshold: a component is kept when it changes BIC by less than this
            (negative, default discovery's −10).
        band_tension: the tension (N) the slip forces are fitted at (default the first
            record's, the first at a tension above 0).
    Returns:
        `TensionDiscovery` (`as_dict()`: the discovery.json of `tribojax discover` given
        several records).
    """
    loops = [loops] if isinstance(loops, HysteresisLoop) else list(loops)
    tensions = _checked_tensions(loops, model)
    if band_tension is None:  # as `fit_history`: the first record's (the first at a tension)
        band_tension = next(float(lp.band_tension) for lp in loops if lp.band_tension > 0)
    kw = dict(decimate=decimate, band_tension=float(band_tension), throw=False)
    current = baseline = _fit_law(loops, model, "proportional", None, kw)
    first, cut = _first_part(loops)
    part = _fit_law(first, model, "proportional", None, kw)
    current_bic, base_each = _scores(current, loops)
    each, effects, candidates = base_each, [], []
    for name, law in TENSION_EFFECTS:
        if TENSION_LAWS[law] > len(tensions):
            break
        fit = _fit_law(loops, model, law, _values(current), kw)
        new_bic, new_each = _scores(fit, loops)
        new_part = _fit_law(first, model, law, _values(part), kw)
        row = _candidate_row(name, law, fit, new_bic - current_bic, model)
        before, after = _heldout_nrmse(part, loops, cut), _heldout_nrmse(new_part, loops, cut)
        reason = judged(row, before, after, (part, new_part), delta_bic_threshold)
        candidates.append(row)
        if reason:
            break
        current, current_bic, each, part = fit, new_bic, new_each, new_part
        effects.append(name)
    records = tuple(
        {
            "source": str(lp.source),
            "band_tension_N": float(lp.band_tension),
            "nrmse_baseline": float(b),
            "nrmse_final": float(e),
        }
        for lp, b, e in zip(loops, base_each, each)
    )
    settings = {
        "model": model,
        "decimate": decimate,
        "delta_bic_threshold": delta_bic_threshold,
        "tensions_N": tensions,
        "reference_tension_N": kw["band_tension"],
    }
    return TensionDiscovery(baseline, current, tuple(effects), tuple(candidates), records, settings)


def _checked_tensions(loops, model) -> list:
    """The records' distinct band tensions (N, sorted); ValueError naming what is missing."""
    if model not in HISTORY_MODELS:
        raise ValueError(f"model must be one of {sorted(HISTORY_MODELS)}, got {model!r}")
    missing = [str(lp.source) for lp in loops if lp.band_tension is None]
    if missing:
        raise ValueError(
            f"a tension discovery needs each record's band_tension; {missing[0]} has none "
            "(give it: band_tension=..., N; --band-tension)"
        )
    tensions = sorted({float(lp.band_tension) for lp in loops})
    if len(tensions) < 2:
        raise ValueError(
            f"a tension discovery needs records at two or more band tensions; these are all at "
            f"{tensions[0]:g} N"
        )
    return tensions


def _candidate_row(name, law, fit, delta_bic, model) -> dict:
    """A candidate's figures: its law, convergence, ΔBIC and the law's parameters (± s.e.)."""
    element = dict(HISTORY_MODELS[model])
    params = zip(fit.fit.names, fit.fit.values, fit.fit.std_errors)
    return {
        "name": name,
        "law": law,
        "converged": bool(fit.fit.converged),
        "delta_bic": float(delta_bic),
        "parameters": {n: [float(v), float(e)] for n, v, e in params if n not in element},
    }


def judged(row, before, after, parts, threshold) -> str:
    """`row` (a candidate's figures) with its held-out check (mean NRMSE of the last thirds,
    `before` and `after`, from the fits `parts` to the first two thirds) and whether it is
    kept; returns why not ("" when it is)."""
    row["heldout"] = {
        "share": HELDOUT_SHARE,
        "nrmse_before": float(before),
        "nrmse_after": float(after),
        "converged": [bool(p.fit.converged) for p in parts],
    }
    reason = _refusal(row, threshold)
    row.update(accepted=not reason, reason=reason)
    return reason


def _refusal(row, threshold) -> str:
    """Why a candidate is not kept ("" when it is)."""
    held = row["heldout"]
    if not row["converged"]:
        return "the fit did not converge"
    if not row["delta_bic"] < threshold:
        return f"dBIC not below {threshold:g}"
    if not all(held["converged"]):
        return "a fit to the first part of the records did not converge"
    if not held["nrmse_after"] < held["nrmse_before"]:
        return "no better on the samples held out"
    return ""
