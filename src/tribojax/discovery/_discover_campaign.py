"""Discovery over two or more test campaigns of one device: which of its parameters moved.

A history model (default the band brake) is fitted to every record of every campaign with one
parameter set (the baseline). Then families of its parameters (`CAMPAIGN_EFFECTS`: the slip
forces, the clearances, ...) are tried as effects: with a family freed, each campaign's records
are fitted with that family free and every other parameter held at the shared fit's values
(`fit_history(..., fixed=...)`: a campaign calibrated from another, docs/data.md). The family
that lowers BIC most is kept when it lowers BIC by more than the threshold and, fitted the same
way to the first two thirds of every record, predicts their last third better than the model
without it; the search goes on with the kept families freed together until none qualifies.

The shared parameters are not refitted with a family freed (a block step, not the joint
optimum), so a family's ΔBIC is at most what the joint fit would gain: a family kept is
demanded at least that much.
"""

from __future__ import annotations

import dataclasses

from .._fit._measures import bic
from .._model._history_fit import fit_history
from .._model._history_model import HISTORY_MODELS
from ._discover import DELTA_BIC_THRESHOLD
from ._discover_tension import (
    _first_part,
    _heldout_nrmse,
    candidate_lines,
    judged,
    misfit,
    report_dict,
    verdict_of,
)

_ELASTIC = (
    ("campaign_slip_force", ("mu_N",)),
    ("campaign_stiffness", ("K_d",)),
    ("campaign_offset", ("f0",)),
)
CAMPAIGN_EFFECTS = {
    "band_brake": (
        ("campaign_slip_force", ("F_pos", "F_neg")),
        ("campaign_clearance", ("gap_pos", "gap_neg")),
        ("campaign_engagement", ("A_pos", "A_neg", "beta_pos", "beta_neg")),
        ("campaign_drag", ("k_gap",)),
        ("campaign_offset", ("f0",)),
    ),
    "jenkins": _ELASTIC,
    "mindlin": _ELASTIC,
    "lugre": (
        ("campaign_slip_force", ("F_c", "F_s")),
        ("campaign_stiffness", ("sigma0",)),
        ("campaign_stribeck", ("v_s",)),
        ("campaign_offset", ("f0",)),
    ),
    "bouc_wen": (
        ("campaign_slip_force", ("F_y",)),
        ("campaign_stiffness", ("K",)),
        ("campaign_shape", ("n",)),
        ("campaign_offset", ("f0",)),
    ),
}
"""Per history model: (effect name, the parameters it frees per campaign), in trial order."""


@dataclasses.dataclass(frozen=True)
class CampaignDiscovery:
    """The result of `discover_campaigns`: the shared fit (`baseline`, a `HistoryFit`), the final
    joint fit (`joint`: the moved parameters fitted per campaign) and each campaign's view of it
    (`final`, {campaign: HistoryFit}), the effects kept, each round's figures (`candidates`),
    the records and the settings."""

    baseline: object
    joint: object
    final: dict
    effects: tuple
    candidates: tuple
    records: tuple
    settings: dict

    @property
    def moved(self) -> tuple:
        """The parameters fitted per campaign (those of the kept effects)."""
        families = dict(CAMPAIGN_EFFECTS[self.settings["model"]])
        return tuple(n for e in self.effects for n in families[e])

    @property
    def converged(self) -> bool:
        """Whether the final joint fit converged."""
        return bool(self.joint.fit.converged)

    @property
    def verdict(self) -> str:
        """As `TensionDiscovery.verdict`, from the final joint fit's noise test."""
        return verdict_of(self.effects, bool(self.joint.fit.noise_consistent))

    def shifts(self) -> dict:
        """{campaign: {parameter: [value, standard error]}} of the moved parameters."""
        got = dict(zip(self.joint.fit.names, zip(self.joint.fit.values, self.joint.fit.std_errors)))
        out, first = {}, next(iter(self.final))
        for k in self.final:
            keys = {n: n if k == first else f"{n}@{k}" for n in self.moved}
            out[k] = {n: [float(got[m][0]), float(got[m][1])] for n, m in keys.items()}
        return out

    def as_dict(self) -> dict:
        """discovery.json's dictionary for several campaigns ("final_fit": the joint fit)."""
        return report_dict(
            "campaign", self, self.joint, moved=list(self.moved), shifts=self.shifts()
        )

    def summary(self) -> str:
        """The lines to print: each round's best family, the verdict and what moved."""
        lines = [f"baseline: {self.settings['model']}, one parameter set for every campaign"]
        lines += candidate_lines(self.candidates)
        lines.append(f"verdict: {self.verdict}; effects {list(self.effects) or 'none'}")
        for campaign, values in self.shifts().items():
            shown = ", ".join(f"{n} {v:.4g} ± {e:.2g}" for n, (v, e) in values.items())
            lines.append(f"  {campaign}: {shown}")
        return "\n".join(lines)


def discover_campaigns(
    campaigns,
    model: str = "band_brake",
    *,
    decimate: int = 1,
    delta_bic_threshold: float = DELTA_BIC_THRESHOLD,
) -> CampaignDiscovery:
    """Which parameter families of `model` moved between test campaigns of one device (module
    docstring).

    Args:
        campaigns: {campaign name: sequence of `HysteresisLoop`s}, two or more campaigns; the
            first campaign's values are the shared ones.
        model: the history element (`fit_history`'s models; default "band_brake").
        decimate: every `decimate`-th sample is fitted (1: all).
        delta_bic_threshold: a family is kept when it changes BIC by less than this (negative,
            default discovery's −10).
    Returns:
        `CampaignDiscovery` (`summary()`, `as_dict()`, `shifts()`).
    """
    groups = _checked(campaigns, model)
    cut = {k: _first_part(g) for k, g in groups.items()}
    firsts = {k: c[0] for k, c in cut.items()}
    kw = dict(decimate=decimate, throw=False)
    current = baseline = _joint(groups, model, (), None, kw)
    part = _joint(firsts, model, (), None, kw)
    current_bic, base_each = _scores(current, groups)
    each, effects, candidates = base_each, [], []
    families, freed = dict(CAMPAIGN_EFFECTS[model]), ()
    remaining = list(families)
    while remaining:
        trials = []
        for name in remaining:
            fit = _joint(groups, model, freed + families[name], current, kw)
            trials.append((_scores(fit, groups)[0] - current_bic, name, fit))
        delta, name, fit = min(trials, key=lambda t: t[0])  # the first on an exact tie
        new_part = _joint(firsts, model, freed + families[name], part, kw)
        row = {
            "name": name,
            "parameters": list(freed + families[name]),
            "converged": bool(fit.fit.converged),
            "delta_bic": float(delta),
            "others_delta_bic": {t[1]: float(t[0]) for t in trials if t[1] != name},
        }
        before, after = _heldout(part, groups, cut), _heldout(new_part, groups, cut)
        reason = judged(row, before, after, (part, new_part), delta_bic_threshold)
        candidates.append(row)
        if reason:
            break
        current, part, current_bic = fit, new_part, current_bic + delta
        each = _scores(fit, groups)[1]
        effects.append(name)
        freed = freed + families[name]
        remaining.remove(name)
    sources = [(k, lp) for k, g in groups.items() for lp in g]
    records = tuple(
        {"source": str(lp.source), "campaign": k, "nrmse_baseline": b, "nrmse_final": e}
        for (k, lp), b, e in zip(sources, base_each, each)
    )
    settings = {"model": model, "decimate": decimate, "delta_bic_threshold": delta_bic_threshold}
    final = {k: current.for_campaign(k) for k in groups}
    return CampaignDiscovery(
        baseline, current, final, tuple(effects), tuple(candidates), records, settings
    )


def _checked(campaigns, model) -> dict:
    """{name: list of records}; ValueError naming what is wrong."""
    if model not in CAMPAIGN_EFFECTS:
        raise ValueError(f"model must be one of {sorted(HISTORY_MODELS)}, got {model!r}")
    groups = {str(k): list(v) for k, v in dict(campaigns).items()}
    if len(groups) < 2 or not all(groups.values()):
        sizes = {k: len(v) for k, v in groups.items()}
        raise ValueError(f"campaigns needs two or more campaigns with records each, got {sizes}")
    return groups


def _joint(groups, model, freed, start, kw):
    """`fit_history` of every campaign's records together, the parameters `freed` fitted per
    campaign, started from `start`'s values (a `HistoryFit`; None: the default start)."""
    loops = [lp for g in groups.values() for lp in g]
    labels = [k for k, g in groups.items() for _ in g]
    values = None if start is None else dict(zip(start.fit.names, start.fit.values.tolist()))
    return fit_history(loops, model, start=values, campaigns=labels, per_campaign=freed, **kw)


def _scores(fit, groups) -> tuple:
    """(BIC, NRMSE of each record) of a joint fit, each campaign's records under its values."""
    rss, n, each = 0.0, 0, []
    for k, g in groups.items():
        r, m, e = misfit(fit.for_campaign(k), g)
        rss, n, each = rss + r, n + m, each + e
    return bic(rss, n, len(fit.fit.names)), each


def _heldout(fit, groups, cut) -> float:
    """Mean NRMSE over every record of its last third, predicted by the joint fit to the first
    two thirds (its campaign's values)."""
    total = sum(
        _heldout_nrmse(fit.for_campaign(k), g, cut[k][1]) * len(g) for k, g in groups.items()
    )
    return float(total / sum(len(g) for g in groups.values()))
