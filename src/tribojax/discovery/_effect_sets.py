"""Discovery steps that change more than one effect at a time: two effects added together when
no single one qualifies (`pair_round`), and backward elimination of an effect that no longer
earns its place once the search ends at the noise (`drop_redundant`)."""

from __future__ import annotations

import numpy as np

from .._fit._noise import residual_rho
from .._model import K_MAX, fit_model
from .._parallel import in_parallel
from ._fitting import _delta_bic
from ._refits import _generalises, _strengths_of


def drop_redundant(run, state, threshold):
    """Backward elimination after the forward search, for a model consistent with the noise: an
    effect added before the last one that no longer earns its place beside the others (ΔBIC of
    keeping it ≥ `threshold` against the model refitted without it, from the current optimum)
    is dropped, the cheapest first, while the model stays consistent with the noise. Not done
    where a misfit is left: the residual is then correlated by it, and the AR(1) inflation of
    the ΔBIC drops real effects (the records behind both: docs/discovery.md, "More rules of
    the search"). Returns (state, names dropped)."""
    dropped, n, p = [], run.y.size, len(run.baseline.param_names)
    while len(state.effects) >= 2 and run.consistent(state):
        ends = p + np.cumsum([0] + [d.k for d in state.designs])
        keeps = [
            [j for j in range(len(state.effects)) if j != i] for i in range(len(state.effects) - 1)
        ]

        def without(keep):
            x0 = np.concatenate(
                [state.theta[:p], *(state.theta[ends[j] : ends[j + 1]] for j in keep)]
            )
            return fit_model(
                run.baseline,
                tuple(state.designs[j] for j in keep),
                x0,
                run.y,
                run.scale,
                tuple(state.effects[j] for j in keep),
            )

        fits = in_parallel([lambda keep=keep: without(keep) for keep in keeps])
        rho, best = residual_rho(run.y - state.prediction), None
        for i, f in enumerate(fits):
            d = state.designs[i]
            if (
                not (f.converged and np.isfinite(f.rss))
                or _delta_bic(state.rss, f.rss, n, d.k + d.n_nuisance, rho) < threshold
            ):
                continue  # it earns its place
            if run.consistent(f) and (best is None or f.rss < best[1].rss):
                best = (i, f)
        if best is None:
            break
        dropped.append(state.effects[best[0]])
        state = best[1]
    return state, dropped


PAIR_CANDIDATES = 3  # single refits, lowest cost first, combined in pairs by `pair_round`


def pair_round(run, state, ranking, threshold, by_name):
    """Two effects at once, tried when no single candidate was added (why:
    docs/discovery.md, "Two effects at once"). The `PAIR_CANDIDATES` usable single refits of this
    round with the lowest cost are combined in pairs, each fitted jointly from the better one's
    optimum with both effects' strengths. A pair qualifies when its ΔBIC against the current
    model is below `threshold` and each of its effects earns its place against the other's
    single refit (ΔBIC below `threshold` at the pair's own AR(1) inflation); of those, by ΔBIC,
    the first that lowers the held-out excess (`_generalises`) is returned as its refit, else
    None."""
    y, n, p = run.y, run.y.size, state.theta.size
    done = sorted(
        (c for c in ranking.candidates if c.refit is not None and c.refit[0].rss < state.rss),
        key=lambda c: c.refit[0].rss,
    )[:PAIR_CANDIDATES]
    room = K_MAX - sum(d.k for d in state.designs)
    pairs = [
        (a, b)
        for i, a in enumerate(done)
        for b in done[i + 1 :]
        if a.refit[1].k + b.refit[1].k <= room
    ]

    def joint(a, b):
        (fa, da), (fb, db) = a.refit, b.refit
        x0 = np.concatenate([fa.theta, fb.theta[p:]])
        return fit_model(
            run.baseline,
            state.designs + (da, db),
            x0,
            y,
            run.scale,
            state.effects + (a.name, b.name),
        )

    qualified = []
    for (a, b), f in zip(pairs, in_parallel([lambda a=a, b=b: joint(a, b) for a, b in pairs])):
        if not (f.converged and np.isfinite(f.rss)) or any(
            by_name[c.name].reject(_strengths_of(run, f, c.name)) for c in (a, b)
        ):
            continue
        rho = residual_rho(y - f.prediction)
        dk = [c.refit[1].k + c.refit[1].n_nuisance for c in (a, b)]
        dbic = _delta_bic(f.rss, state.rss, n, sum(dk), rho)
        each = (
            _delta_bic(f.rss, a.refit[0].rss, n, dk[1], rho) < threshold
            and _delta_bic(f.rss, b.refit[0].rss, n, dk[0], rho) < threshold
        )
        if dbic < threshold and each:
            qualified.append((dbic, a, b, f))
    for dbic, a, b, f in sorted(qualified, key=lambda q: q[0]):
        if _generalises(run, state, f, a):
            for c, other in ((a, b), (b, a)):
                c.refit_message = f"added with {other.name} as a pair: ΔBIC {dbic:.1f}"
                c.heldout_excess = a.heldout_excess
            return f
    return None
