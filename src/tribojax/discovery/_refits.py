"""Step 4 of discovery: refit the ranked candidates, accept those that lower BIC, choose one;
the starts of a candidate's refit, its further grid seeds, and a refit that only moved the
current model's own optimum."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._measures import bic, delta_bic, rms
from .._fit._noise import RHO_MAX, ar1_inflation, ar1_square_inflation, residual_rho
from .._model import MAX_STEPS, effect_strengths, fit_model, restarted_around
from .._parallel import in_parallel, speculatively
from ._fitting import _columns, _delta_bic
from ._verdict import BIC_TIE, HELDOUT_TIE

QUICK_STEPS = 16  # steps per start of a refit after a candidate of the round reached the noise
QUICK_MARGIN = 2.0  # ... continued only within this factor of that candidate's cost (`_refit`)


def _refit(baseline, state, design, name, y, scale, r, cache, target=None, floor=-np.inf):
    """Fit the model augmented by `design`: from one Gauss–Newton step of the augmented model
    (the step the score test looks along), and from the current fit with the new strengths at
    zero when that fails or ends above the current cost (the nested model's optimum is a point
    of the augmented model, so ending above it is a local minimum); then from each of the
    design's own `starts`; keep the lowest cost (the records behind each rule here:
    docs/discovery.md, "Why each rule is set where it is").

    `target`: the cost (RSS, units of `scale`) of a candidate that already reached the noise;
    each start then has `QUICK_STEPS` steps, and goes on only within `QUICK_MARGIN` of it. A
    start still above the current cost (or `QUICK_MARGIN` × `target`) after `PROBE_STEPS`
    steps is abandoned (`_abandon_above`).
    `floor`: the cost of a fit at the noise (`_noise_floor`); the Gauss–Newton start runs first,
    alone, and when it converges at or below the floor the other starts are not run (no start
    can lower it by more than the noise's own spread). A start stopped above the current cost
    is not restarted (`fit_model`'s `ceiling`). The kept refit, when it stalled below the current
    cost, is restarted around its stop as a record model's fit (`restarted_around`).
    """
    zero = np.concatenate([state.theta, np.zeros(design.k)])
    designs, names = state.designs + (design,), state.effects + (name,)
    budget = MAX_STEPS if target is None else QUICK_STEPS

    above = _abandon_above(state, target)

    def fit_from(x0, above=above, model=baseline):
        return lambda: fit_model(
            model,
            designs,
            x0,
            y,
            scale,
            names,
            max_steps=budget,
            ceiling=state.rss,
            abandon_above=above,
        )

    gauss_newton = []
    A = np.concatenate([state.jacobian, _columns(baseline, state, design, cache) / scale], axis=1)
    if np.all(np.isfinite(A)):
        step = np.linalg.lstsq(A, r, rcond=None)[0]
        p = state.theta.size
        gauss_newton.append(fit_from(np.concatenate([state.theta + step[:p], step[p:]])))
    starts = [
        fit_from(np.concatenate([state.theta, np.asarray(s0, dtype=float)])) for s0 in design.starts
    ]

    def at_noise(fit):
        return fit.converged and fit.rss <= min(floor, state.rss)

    # the Gauss–Newton start first, alone, then the design's starts side by side (`in_parallel`);
    # in quick mode, where every start is short, all of them side by side
    quick = target is not None
    fits = [] if quick else [f() for f in gauss_newton]
    if fits and at_noise(fits[0]):
        return fits[0]
    running = in_parallel([*gauss_newton, *starts] if quick else starts, wait=False)
    if quick and gauss_newton:
        fits, running = [running[0].result()], running[1:]
        if at_noise(fits[0]):
            return fits[0]
    # the zero start, when the Gauss–Newton start needs it, on this thread meanwhile (in quick
    # mode only when the current cost is within `QUICK_MARGIN` of the target: it begins there)
    near = target is None or state.rss <= QUICK_MARGIN * target
    if near and (not fits or not fits[0].converged or not fits[0].rss <= state.rss):
        fits.append(fit_from(zero, np.inf)())
    fits += [f.result() for f in running]
    good = [f for f in fits if f.converged and np.isfinite(f.rss)]
    ran_out = [f for f in fits if np.isfinite(f.rss) and f.steps >= budget and not f.converged]
    run = ran_out if target is None else [f for f in ran_out if f.rss <= QUICK_MARGIN * target]
    if not good and ran_out and not run:  # cut short: every start far above the target
        return dataclasses.replace(
            min(ran_out, key=lambda f: f.rss),
            message=f"not refitted to the end: after {QUICK_STEPS} steps its cost was above "
            f"{QUICK_MARGIN:g}x that of a candidate that reaches the noise",
        )
    if not good and target is None:
        # every start from the current fit stalled: once more from a start made afresh with the
        # effect in the model (`restart`; s3007: a drift the baseline read as slip)
        fresh = baseline.restart(designs)
        if fresh is not None and np.all(np.isfinite(fresh)):
            fits.append(fit_from(fresh)())
            good += [f for f in fits[-1:] if f.converged and np.isfinite(f.rss)]
            ran_out += [f for f in fits[-1:] if np.isfinite(f.rss) and not f.converged]
            run = ran_out
    if run and min(f.rss for f in run) < min((f.rss for f in good), default=np.inf):
        # a fit that ran out of steps while still descending, below every converged one (e.g.
        # an unidentified F_s walking to its bound), goes on from where it stopped, once
        fits.append(
            fit_model(
                baseline,
                designs,
                min(run, key=lambda f: f.rss).theta,
                y,
                scale,
                names,
                ceiling=state.rss,
            )
        )
        good += [f for f in fits[-1:] if f.converged and np.isfinite(f.rss)]
    if not good:
        return fits[-1]
    best = min(good, key=lambda f: f.rss)
    if target is not None:
        return best
    # stalled below the current cost: restarted around its stop, as a record model's fit
    # (`restarted_around`; s1018: a mode's refit stopped at 76 with 74 variances promised)
    return restarted_around(baseline, best, fit_from, ceiling=state.rss)


def _abandon_above(state, target) -> float:
    """The cost above which a refit start is abandoned after `PROBE_STEPS` steps (`fit_model`):
    the current model's (the zero start, which begins there, has none), and `QUICK_MARGIN` ×
    `target`, the cost of a candidate that reached the noise, when there is one."""
    return min(state.rss, np.inf if target is None else QUICK_MARGIN * target)


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


MAX_MOVES = 2  # times a refit may replace the current model by a better optimum of itself


def _moved_optimum(baseline, state, best, y, scale, threshold):
    """The current model refitted from `best`'s optimum (its new strengths dropped) when those
    strengths are all zero within 2 standard errors and dropping them costs no significant ΔBIC:
    the refit's gain came from moving the current model's own parameters to a better optimum,
    not from the effect (docs/discovery.md, "Noise model"). Else None."""
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


def refit_round(run, state, ranking, n_refit, threshold, by_name, base_ok) -> list:
    """Refit the `n_refit` best candidates of `ranking` whose p-value is below α/(number of
    candidates), and those of effects without a score gate (none when the baseline is already
    consistent with the noise, `base_ok`). Returns the accepted ones, (candidate, refit, added
    parameters, AR(1) inflation of its residual), those whose ΔBIC < `threshold`.

    In p-value order; a candidate with no fewer parameters than an earlier one that reaches the
    noise is not refitted, one with fewer is refitted with a step budget (`QUICK_STEPS`, see
    `_refit`); a candidate's further seeds are skipped once a refit reaches it. The run's noise
    model is sharpened by every refit's residual (`run.consistent`)."""
    cands, n, y = ranking.candidates, run.y.size, run.y
    level = run.alpha / len(cands)
    accepted, dk_explains, rss_explains, explains = [], np.inf, None, None
    refitted = []  # (candidate, its starts, refit, design) of every candidate refitted
    to_refit = [c for c in cands if c.p_value < level][:n_refit]
    to_refit += [c for c in cands if not c.gate and c not in to_refit]
    for c in to_refit[: 0 if base_ok else len(to_refit)]:
        d = c.design
        if d.k + d.n_nuisance >= dk_explains:
            # an earlier candidate with no more parameters brings the residual to the noise:
            # this one could not beat its ΔBIC by more than the noise allows
            c.refit_message = "not refitted: a candidate with fewer parameters explains"
            continue
        starts = (d, *c.seeds)  # several starts: the best grid points by score
        floor = _noise_floor(run, state, d)
        with speculatively(
            [
                lambda dd=dd: _refit(
                    run.baseline,
                    state,
                    dd,
                    c.name,
                    y,
                    run.scale,
                    ranking.residual,
                    ranking.cache,
                    rss_explains,
                    floor,
                )
                for dd in starts
            ]
        ) as refits:
            d, new = _best_start(run, starts, (fut.result() for fut in refits), n)
        refitted.append((c, starts, new, d))
        if _settle(run, state, c, d, new, threshold, by_name, accepted):
            dk_explains = min(dk_explains, d.k + d.n_nuisance)
            if rss_explains is None or new.rss < rss_explains:
                rss_explains, explains = new.rss, new
            if accepted and accepted[-1][1] is new:  # the likely choice: its held-out check
                run.prefetch(new)  # runs while the round goes on (`pick` reads it)
    for c, starts, new, d in refitted if explains is not None else ():
        if c.refit is not None and c.refit[0] is explains or d.k + d.n_nuisance >= dk_explains:
            continue
        again = _from_explaining(run, state, c, starts, explains, dk_explains)
        if again is not None and not (
            new.converged and _bic(again[1], again[0], n) >= _bic(new, d, n)
        ):
            accepted[:] = [a for a in accepted if a[0] is not c]
            c.refit, c.delta_bic, c.rmse_after, c.refit_message = None, None, None, None
            _settle(run, state, c, *again, threshold, by_name, accepted)
            c.refit_message = c.refit_message or _AGAIN
    return accepted


def _noise_floor(run, state, design) -> float:
    """The cost (RSS in units of the run's scale) below which a refit with `design` is at the
    noise: m noise variances plus one standard deviation of a sum of m AR(1) squares,
    σ²·(m + √(2m(1 + ρ²)/(1 − ρ²))), m = n − parameters (σ, ρ the run's noise model)."""
    m = run.y.size - state.theta.size - design.k
    rho = float(np.clip(run.noise.rho, 0.0, RHO_MAX))
    spread = np.sqrt(2.0 * m * ar1_square_inflation(rho))
    return float((run.noise.sigma / run.scale) ** 2 * (m + spread))


_AGAIN = "refitted again from the optimum of a candidate that reaches the noise"


def _best_start(run, starts, fits, n):
    """(design, refit) of a candidate's starts: the lowest BIC among converged refits (the
    first start when none converged); stops reading at the first that reaches the noise."""
    d, new = None, None
    for dd, f in zip(starts, fits):
        if (
            new is None
            or (f.converged and not _bic(f, dd, n) >= _bic(new, d, n))
            or not new.converged
        ):
            d, new = dd, f
        if new.converged and run.consistent(new):
            break  # at the noise: further starts cannot do better
    return d, new


def _settle(run, state, c, d, new, threshold, by_name, accepted) -> bool:
    """Record candidate `c`'s refit `new` of design `d` (its ΔBIC, RMS, refit; appended to
    `accepted` when ΔBIC < `threshold`). Returns whether it reaches the noise."""
    y, n = run.y, run.y.size
    usable = new.converged and np.isfinite(new.rss)
    why = by_name[c.name].reject(_strengths_of(run, new, c.name)) if usable else None
    if why or not usable:
        c.refit_message = why or new.message or "refit failed"
        return False
    c.refit = (new, d)
    rho1 = residual_rho(y - new.prediction)
    c.delta_bic = _delta_bic(new.rss, state.rss, n, d.k + d.n_nuisance, rho1)
    c.rmse_after = rms(y - new.prediction)
    if c.delta_bic < threshold:
        accepted.append((c, new, d.k + d.n_nuisance, ar1_inflation(rho1)))
    return run.consistent(new)


def _from_explaining(run, state, c, starts, explains, dk_explains):
    """A candidate other than the one that reached the noise at the lowest cost (refitted before
    it, or after it and cut short by the quick budget), refitted once more from that one's
    optimum of the current model's parameters, the candidate's strengths at zero (each of its
    designs, `QUICK_STEPS` steps): its own starts never saw that basin, and which candidate
    reached the noise first must not decide. Designs with fewer parameters than the explaining
    one only (`dk_explains`). Returns (design, refit), or None."""
    p = state.theta.size
    starts = [dd for dd in starts if dd.k + dd.n_nuisance < dk_explains]
    if not starts:
        return None
    x0 = [np.concatenate([explains.theta[:p], np.zeros(dd.k)]) for dd in starts]
    names = state.effects + (c.name,)
    above = _abandon_above(state, explains.rss)
    fits = in_parallel(
        [
            lambda dd=dd, x=x: fit_model(
                run.baseline,
                state.designs + (dd,),
                x,
                run.y,
                run.scale,
                names,
                max_steps=QUICK_STEPS,
                abandon_above=above,
            )
            for dd, x in zip(starts, x0)
        ]
    )
    d, new = _best_start(run, starts, fits, run.y.size)
    return (d, new) if new.converged and np.isfinite(new.rss) else None


def pick(run, state, accepted, threshold, may_move):
    """The accepted candidate to add, (candidate, refit, moved) — `moved` the current model
    refitted from the refit's optimum when the gain was its own (`_moved_optimum`, only while
    `may_move`), else None — or None when no accepted candidate generalises: by `choose`'s
    order, the first whose refit lowers the held-out excess (`_generalises`); a moved optimum
    needs no such check (it adds nothing). Held-out fits run for chosen candidates only."""
    accepted = list(accepted)
    while accepted:
        best_c, best = choose(accepted, state, run.y.size)
        moved = (
            _moved_optimum(run.baseline, state, best, run.y, run.scale, threshold)
            if may_move
            else None
        )
        if moved is not None or _generalises(run, state, best, best_c):
            return best_c, best, moved
        accepted = [a for a in accepted if a[0] is not best_c]
    return None


def _generalises(run, state, new, c) -> bool:
    """Does the refit `new` lower the held-out mean square of the current model `state` (an
    effect counts only if, fitted on one half of the record, it also lowers the misfit on the
    other)? The mean squares, not the excess beyond the noise (clipped at 0, so a misfit
    within the noise's mean square could never be lowered); lower by more than `HELDOUT_TIE`
    (relative), else a tie, which keeps the current model (fewer parameters). True when the
    current model's held-out residual is unavailable."""
    before, after = run.heldout_ms(state), run.heldout_ms(new)
    c.heldout_excess = run.heldout(new)
    if before is None or (after is not None and after < before * (1.0 - HELDOUT_TIE)):
        return True
    c.refit_message = (
        f"not added: held-out mean square {_g(after)} not below the current "
        f"model's {_g(before)} (fitted on one half, scored on the other)"
    )
    return False


def _g(x):
    return "(fit failed)" if x is None else f"{x:.3g}"


def _strengths_of(run, fit, name):
    return effect_strengths(fit)[name]["nuisance"]


def choose(accepted, state, n):
    """The accepted candidate to add: each was accepted on its own ΔBIC (AR(1) inflation of its
    own residual); the choice between them uses one inflation for all, that of the one with the
    lowest RSS (the error correlation estimated from the fullest model), recorded as
    `delta_bic_common`; candidates within `BIC_TIE` of the lowest are a tie, which goes to the
    fewer added parameters, then the name (never to the last bits). Otherwise a candidate that
    leaves a smooth misfit is charged more than one that leaves a rough one (docs/discovery.md).
    Returns (candidate, refit)."""
    c_common = min(accepted, key=lambda a: a[1].rss)[3]
    for c, new, dk, _ in accepted:
        c.delta_bic_common = delta_bic(new.rss, state.rss, n, dk, c_common)
    best = min(a[0].delta_bic_common for a in accepted)
    tied = [a for a in accepted if a[0].delta_bic_common <= best + BIC_TIE]
    return min(tied, key=lambda a: (a[2], a[0].name))[:2]  # a tie: fewer parameters, the name
