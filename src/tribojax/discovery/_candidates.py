"""Step 3 of discovery: each candidate effect's best design at the current fit, ranked by its Rao
score test."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._noise import chi2_logsf, chi2_sf
from .._model import K_MAX, EffectDesign
from ._fitting import _columns, _score, prefetch_columns
from ._refits import _seeds


@dataclasses.dataclass(eq=False)
class Candidate:
    """One effect at its best design for the current fit, and what its refit gave.

    score: Rao (LM) statistic of `design`'s columns (χ²_dof under the null); p_value: its
    p-value Bonferroni-corrected over the effect's `grid_points`; seeds: further designs the
    refit starts from; gate: the effect's `score_gate`. Filled by the refit step: delta_bic
    (None: not refitted), rmse_after (output units), delta_bic_common, refit_message,
    heldout_excess (the refit's held-out excess, output units, when its ΔBIC qualified);
    refit: (refit, design) of a usable refit, for the pair step (`_refits.pair_round`).
    """

    name: str
    score: float
    dof: int
    p_value: float
    grid_points: int
    design: EffectDesign
    seeds: list
    gate: bool
    delta_bic: float | None = None
    rmse_after: float | None = None
    delta_bic_common: float | None = None
    refit_message: str | None = None
    heldout_excess: float | None = None
    refit: tuple | None = None

    def public(self) -> dict:
        """The candidate as discovery.json lists it."""
        out = {
            "name": self.name,
            "score": self.score,
            "dof": self.dof,
            "p_value": self.p_value,
            "grid_points": self.grid_points,
            "nuisance": {k: float(v) for k, v in self.design.nuisance.items()},
            "delta_bic": self.delta_bic,
        }
        for key in ("rmse_after", "delta_bic_common", "refit_message", "heldout_excess"):
            if getattr(self, key) is not None:
                out[key] = getattr(self, key)
        return out


@dataclasses.dataclass(frozen=True)
class Ranking:
    """The candidates of one round, best first (p-value, then score), with the scaled residual
    r = (y − model)/scale they were scored on and the knob Jacobians computed for them."""

    candidates: list
    residual: np.ndarray
    cache: dict


# relative, on the log p-value: designs scored closer than this are a tie (moving every sample by
# 1e-3 of its noise moves a score S of dof columns by about 2·√(S·dof)·1e-3, e.g. 0.07 at S = 560)
SCORE_TIE = 1e-3


def _tie_first(scored):
    """`scored` (sorted best first) with the design that wins a tie first: among the designs
    whose log p-value is within `SCORE_TIE` (relative) of the best, the one with the fewest
    parameters (strengths + nuisance), then the earliest on the grid (s2035: two microslip
    designs scored 562.53 both, and which came first decided the refit)."""
    best = scored[0][0]
    tied = [z for z in scored if z[0] <= best * (1.0 - SCORE_TIE)]
    first = min(tied, key=lambda z: (z[4].k + z[4].n_nuisance, z[2]))
    return [first, *(z for z in scored if z is not first)]


def rank(baseline, effects, grids, state, y, scale, n_starts) -> Ranking:
    """Score every effect not yet in `state` at its grid designs that fit in `K_MAX`: the design
    with the smallest log p-value (`chi2_logsf`: p underflows to 0 for a strong effect; a tie
    within `SCORE_TIE` goes to `_tie_first`), refined
    by the effect (`refine`), with its further refit seeds (`_seeds`), refined likewise."""
    r = (y - state.prediction) / scale
    J_cur = state.jacobian
    cache: dict = {}
    room = K_MAX - sum(d.k for d in state.designs)
    fits = {
        e.name: [d for d in grids[e.name] if d.k <= room]
        for e in effects
        if e.name not in state.effects
    }
    prefetch_columns(baseline, state, [d for grid in fits.values() for d in grid], cache)

    def score_of(d):
        return _score(r, J_cur, _columns(baseline, state, d, cache) / scale)

    cands = []
    for e in effects:
        grid = fits.get(e.name)
        if not grid:
            continue
        scored = []
        for d in grid:
            S, dof = score_of(d)
            scored.append((chi2_logsf(S, dof) if dof else 0.0, -S, len(scored), dof, d))
        scored = _tie_first(sorted(scored, key=lambda z: z[:3]))
        S, dof, d = -scored[0][1], scored[0][3], scored[0][4]
        pv = chi2_sf(S, dof) if dof else 1.0
        seeds = _seeds(scored, max(n_starts, e.refit_starts))
        if dof:
            # the seeds too: a raw grid seed starts its refit too far off (docs/discovery.md)
            seeds = [e.refine(baseline, sd, lambda dd: score_of(dd)[0]) for sd in seeds]
            d = e.refine(baseline, d, lambda dd: score_of(dd)[0])
            S2, dof2 = score_of(d)
            if S2 > S and dof2 == dof:
                S, pv = S2, chi2_sf(S2, dof)
        cands.append(
            Candidate(e.name, S, dof, min(1.0, pv * len(grid)), len(grid), d, seeds, e.score_gate)
        )
    cands.sort(key=lambda c: (c.p_value, -c.score))
    return Ranking(cands, r, cache)
