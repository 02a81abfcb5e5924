"""The discovery workflow: fit the baseline, localise, rank named effects, add, refit, report.

The steps are typed: the run's context and noise model (`_Run`, `NoiseModel`), the ranked
candidates (`_candidates.rank` → `Candidate`), the refits and the choice (`_refits.refit_round`,
`choose`), the report (`_report.report` → `DiscoveryReport`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._noise import excess_rmse, find_regions, noise_consistent
from .._model import (
    ALPHA,
    AbstractBaseline,
    AbstractEffect,
    FittedModel,
    RecordData,
    default_effects,
    fit_record,
    fit_saved,
    heldout_residual,
    polish,
)
from .._parallel import in_background
from ._candidates import rank
from ._effect_sets import drop_redundant, pair_round
from ._refits import MAX_MOVES, pick, refit_round
from ._report import DiscoveryReport, report
from ._verdict import NoiseModel

DELTA_BIC_THRESHOLD = -10.0
"""An effect is accepted only below ΔBIC = −10 ("very strong" evidence, Kass & Raftery 1995)."""

_MOVED = (
    "not added: its strengths are zero within 2 standard errors; the current model "
    "refitted from this refit's optimum is kept"
)


@dataclasses.dataclass
class _Run:
    """What one discovery run tests against: the record, the baseline fit (`base_state`), its
    residual `r0`, flagged `regions` and noise test `base_test` (consistent, p-value), and the
    noise model, which refits sharpen (`consistent`)."""

    baseline: AbstractBaseline
    data: RecordData
    y: np.ndarray
    scale: float
    alpha: float
    n_windows: int
    base_state: object = None
    r0: np.ndarray = None
    regions: list = None
    base_test: tuple = None
    base_noise: tuple = None
    noise: NoiseModel = None
    _heldout: dict = dataclasses.field(default_factory=dict)
    _polished: dict = dataclasses.field(default_factory=dict)  # id → (state, polished state)

    def rebase(self, state):
        """Make `state` the baseline fit: its residual, noise model, regions and noise test."""
        b, data = self.baseline, self.data
        r = self.y - state.prediction
        ok, p, sigma, rho = b.noise_test(
            r, len(b.param_names), alpha=self.alpha, n_windows=self.n_windows
        )
        self.noise = NoiseModel(sigma, rho, b.noise_model(r)[0], not data.noise_std)
        self.regions = find_regions(
            r,
            data.x,
            data.segment,
            sigma,
            rho,
            n_windows=self.n_windows,
            alpha=self.alpha,
            segment_names=data.segment_names,
        )
        for g in self.regions:
            g.update(b.region_info(g))
        self.base_state, self.r0, self.base_test = state, r, (ok, p)
        self.base_noise = (sigma, rho)
        return state

    def prefetch(self, state):
        """Start `state`'s held-out residual in the background (`in_background`; read by
        `heldout`); each model's is computed once."""
        key = id(state)
        if key not in self._heldout:
            self._heldout[key] = (
                state,
                in_background(
                    lambda: heldout_residual(
                        self.baseline, state.designs, state.theta, self.y, self.scale, state.effects
                    )
                ),
            )
        return self._heldout[key][1]

    def heldout(self, state) -> float | None:
        """The held-out excess of `state`'s model (output units, against the current noise sd):
        `heldout_residual` with its effects' nuisance values fixed, from its fitted values;
        None when a fold's fit fails."""
        r = self.prefetch(state).result()
        return None if r is None else excess_rmse(r, self.noise.sigma)

    def heldout_ms(self, state) -> float | None:
        """The mean square of `state`'s held-out residual (output units²; None when a fold's
        fit fails): what the held-out gate compares, never clipped at the noise."""
        r = self.prefetch(state).result()
        return None if r is None else float(np.mean(np.square(r)))

    def polished(self, state):
        """`state` taken on to its minimum in residual variances (`polish`: a record without a
        stated noise, whose fits' stops count in a unit the signal inflates); the baseline fit
        and a state already polished are returned as they are."""
        if state is self.base_state:
            return state
        if id(state) not in self._polished:  # the pair held: its ids stay unique
            out = polish(self.baseline, state, self.y)
            self._polished[id(state)] = (state, out)
            self._polished[id(out)] = (out, out)
        return self._polished[id(state)][1]

    def consistent(self, state) -> bool:
        """The noise test that decides "none" and "explained" (a refit's residual sharpens the
        noise model first, `NoiseModel.sharpen`)."""
        if state is not self.base_state:
            self.noise.sharpen(self.baseline, state, self.y)
        n_par = len(self.baseline.param_names) + sum(d.k + d.n_nuisance for d in state.designs)
        return (
            self.baseline.noise_gate
            and noise_consistent(
                self.y - state.prediction,
                self.noise.sigma,
                self.noise.rho,
                self.data.segment,
                self.data.x,
                n_par,
                alpha=self.alpha,
                n_windows=self.n_windows,
                estimated=not self.data.noise_std,
            )[0]
        )


def discover(
    baseline: AbstractBaseline,
    effects: list[AbstractEffect] | None = None,
    *,
    max_effects: int = 3,
    n_refit: int = 4,
    n_starts: int = 1,
    delta_bic_threshold: float = DELTA_BIC_THRESHOLD,
    alpha: float = ALPHA,
    n_windows: int = 32,
    theta0=None,
    start: FittedModel | None = None,
) -> DiscoveryReport:
    """Find where `baseline` disagrees with its data, name the missing effects, add them.

    1. Fit the baseline (`fit_record`, the fit `tribojax fit` reports: the one residual,
       transforms and LM of the record's model, strengths padded to `K_MAX` so that every refit
       below reuses one compiled solve) from `baseline.starts()` in turn, as `fit_record` says.
    2. Regions: residual windows against the noise (sidecar sd, else estimated; AR(1) ρ).
    3. Rank each candidate effect by its Rao score statistic at the current fit (LM form
       n·‖P r‖²/‖r‖², χ²_k; over a grid of nuisance settings the design with the smallest
       log p-value, Bonferroni-corrected over the grid: the Davies problem of parameters not
       identified under the null), refined by the effect (`AbstractEffect.refine`; the p-value
       keeps the grid's factor, somewhat optimistic after refinement). `_candidates.rank`.
    4. Refit the `n_refit` best candidates with p-value below alpha/(number of candidates), and
       those of effects with `score_gate` False, from one Gauss–Newton step (from zero new
       strengths when that fails, then from the design's `starts`); a candidate qualifies if
       ΔBIC < `delta_bic_threshold` (AR(1)-inflated, nuisance counted). Of those, by the
       lowest ΔBIC at a common inflation (`_refits.refit_round`, `choose`, `pick`): a refit
       whose gain came from moving the current model's own optimum replaces the current model
       instead (at most `MAX_MOVES` times); else the first one that, fitted on one half of
       the record (`folds()`), lowers the current model's misfit on the other half
       (`_Run.heldout`, both ways) is added. Repeat until none qualifies, `max_effects` are
       in, or the model is consistent with the noise ("explained"). Every state carried
       forward, and the one reported, is first taken on to its minimum in residual variances
       where its residual unit is not a stated noise sd (`polish`). A round that adds nothing
       tries its best single refits jointly in pairs (`_effect_sets.pair_round`: two hidden effects
       whose single refits each leave the other's misfit). When the baseline itself
       is consistent with the noise the candidates are ranked, not refitted (verdict "none").
       A candidate refitted before another one reached the noise gets one more start from
       that one's optimum (`_refits.refit_round`). When the search ends with a model consistent
       with the noise, an effect added before the last one that no longer earns its place
       beside the others is dropped (`_effect_sets.drop_redundant`; settings["effects_dropped"]).
    5. Report (`_report.report`): the verdict, the excess misfit before and after, in-sample
       and held out ("explained" needs both), and where a misfit remains its regions, signal
       correlations and a flexible correction.

    Args:
        baseline: a concrete baseline holding the record (e.g. `slip_baseline(run)`).
        effects: candidate effects; default those of `default_effects(baseline.kind)` that
            apply to the record (`AbstractEffect.applies`). Add your own:
            `effects=[*default_effects("slip"), MyEffect()]`.
        n_starts: refit starts per candidate with a nuisance grid (at least the effect's
            `refit_starts`): the best grid point by score (refined), then the best ones a
            decade away in every nuisance value or of another form; the lowest BIC kept.
        theta0: one start θ for the baseline fit instead of `baseline.starts()`.
        start: a saved model of this kind (`tribojax.load_model`, e.g. a discovery on another
            record): its effects are refitted on this record from their saved values and the
            search continues from that model (the report's effects begin with them; "before"
            is still the baseline alone). When that refit fails, the search starts from the
            baseline (settings["start_model"] says so).
    Returns:
        DiscoveryReport (check `.converged`: False when the baseline fit failed).
    """
    effects = _checked(baseline, effects, max_effects, alpha)
    state = fit_record(baseline, None if theta0 is None else [theta0])  # step 1
    data = baseline.data()
    run = _Run(baseline, data, np.asarray(data.y, dtype=float), state.scale, alpha, n_windows)
    run.rebase(state)
    started = _from_saved(start, baseline, state)
    search = _Search(run, effects, max_effects, n_refit, n_starts, delta_bic_threshold)
    state, rounds = search.search(state if started is None or not started.converged else started)
    state, dropped = (
        drop_redundant(run, state, delta_bic_threshold) if state.converged else (state, [])
    )
    state = run.polished(state)
    settings = search.settings(dropped)
    if start is not None:
        settings["start_model"] = {
            "source": start.source,
            "effects": [e.name for e in start.effects],
            "refit": "none" if started is None else started.message or "converged",
        }
    return report(run, state, rounds, settings)  # step 5


def _from_saved(start, baseline, state):
    """The saved model `start` refitted on this record (None: none given, or the baseline fit
    failed)."""
    if start is None or not state.converged:
        return None
    return fit_saved(start, baseline, sigma_known=False)


@dataclasses.dataclass
class _Search:
    """Steps 2–4 of `discover`: rounds of ranking and refitting the candidates until none
    qualifies, `max_effects` are in, or the model is consistent with the noise."""

    run: _Run
    effects: list
    max_effects: int
    n_refit: int
    n_starts: int
    threshold: float

    def search(self, state):
        """(the final state, each round's public candidates)."""
        run, threshold = self.run, self.threshold
        by_name = {e.name: e for e in self.effects}
        base_ok = run.consistent(run.base_state)  # then candidates are ranked, none refitted
        moves, rounds = 0, []
        grids = {e.name: e.designs(run.baseline) for e in self.effects}
        while (
            state.converged and len(state.effects) < self.max_effects and not (rounds and base_ok)
        ):
            ranking = rank(
                run.baseline, self.effects, grids, state, run.y, run.scale, self.n_starts
            )
            if not ranking.candidates:
                break
            if not base_ok:  # the report and the first choice need the baseline's held-out
                run.prefetch(run.base_state)  # check: on the threads the first start leaves
            accepted = refit_round(run, state, ranking, self.n_refit, threshold, by_name, base_ok)
            picked = pick(run, state, accepted, threshold, moves < MAX_MOVES) if accepted else None
            if picked is not None:
                best_c, best, moved = picked
                if moved is not None:  # a better optimum of the current model
                    moves, best_c.refit_message, best = moves + 1, _MOVED, moved
            if picked is None and len(state.effects) + 2 <= self.max_effects:
                paired = pair_round(run, state, ranking, threshold, by_name)
                if paired is not None:  # two effects at once
                    rounds.append([c.public() for c in ranking.candidates])
                    state = run.polished(paired)
                    if run.consistent(state):
                        break
                    continue
            rounds.append([c.public() for c in ranking.candidates])
            if picked is None:
                break
            if best is not moved or state is not run.base_state:
                state = run.polished(best)
            else:  # a better optimum of the baseline itself
                state = run.rebase(moved)
                base_ok = run.consistent(state)
            if run.consistent(state):  # explained: nothing is left to name
                break
        return state, rounds

    def settings(self, dropped) -> dict:
        """The report's "settings": the criterion and the search's limits."""
        return {
            "criterion": "Rao score (chi2, Bonferroni over grid and candidates) then "
            "Delta BIC (AR(1)-inflated) below threshold and a lower held-out "
            "excess (two-fold)",
            "delta_bic_threshold": self.threshold,
            "alpha": self.run.alpha,
            "max_effects": self.max_effects,
            "n_refit": self.n_refit,
            "n_windows": self.run.n_windows,
            "candidates_offered": [e.name for e in self.effects],
            "effects_dropped": dropped,
        }


def _checked(baseline, effects, max_effects, alpha) -> list:
    if max_effects < 0:
        raise ValueError(f"max_effects = {max_effects} is outside the allowed range [0, inf)")
    if not 0 < alpha < 1:
        raise ValueError(f"alpha = {alpha:g} is outside the allowed range (0, 1)")
    if effects is None:  # the registered effects that apply to this record (`applies`)
        effects = [e for e in default_effects(baseline.kind) if e.applies(baseline)]
    effects = list(effects)
    for e in effects:
        if not isinstance(e, AbstractEffect):
            raise ValueError(f"effects: {e!r} is not an AbstractEffect")
        if e.kind != baseline.kind:
            raise ValueError(f"effect {e.name!r} is for {e.kind!r} records, not {baseline.kind!r}")
    names = [e.name for e in effects]
    if len(set(names)) != len(names):
        raise ValueError(f"effects: duplicate names in {names}")
    return effects
