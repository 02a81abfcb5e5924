"""A saved model rebuilt on a record: its record model (baseline), θ, and each effect's design
at the saved nuisance values with the strengths that give the saved physical values.

An effect is rebuilt by name from the registry (`default_effects`; `tribojax.discovery` registers
the library's effects on import), so a model saved with effects rebuilds without hand work on
any record of the same kind. Among the effect's designs on the new record the one with the saved
fixed nuisance values (e.g. a drift's degree) is taken, the nearest seed of each fitted nuisance
value (a gap, a Stribeck velocity, a mode's frequency) is moved to the saved value through the
strength that shifts it, and every other strength is the saved physical value over the design's
unit.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ._curve_model import curve_baseline
from ._default_effects import default_effects
from ._fit import MAX_STEPS, fit_model, record_scale
from ._loop_model import loop_baseline
from ._saved import FittedModel, check_values
from ._slip import slip_baseline


@dataclasses.dataclass(frozen=True)
class RecordKind:
    """How a saved record model is rebuilt: the record kind it applies to, its baseline on a
    record (with the saved options), the sample axis (name, values) and the measured output
    and its unit, and the model's output in those units (a baseline may compare in a weighted
    form)."""

    record_kind: str
    build: object
    axis: object
    measured: object
    unit: object
    output: object = staticmethod(lambda base, y: y)


def _slip(record, options):
    alpha = options.get("alpha", 1.0)
    return slip_baseline(record, alpha=None if alpha == "free" else float(alpha))


RECORD_KINDS = {
    "slip": RecordKind(
        "slip_run",
        _slip,
        lambda b: ("time_s", np.asarray(b.t)),
        lambda b: np.asarray(b.slip),
        lambda b: "m",
    ),
    "loop": RecordKind(
        "loop",
        lambda rec, o: loop_baseline(
            rec, o.get("element", "jenkins"), initial=o.get("initial", "rest")
        ),
        lambda b: ("time_s", np.asarray(b.t)),
        lambda b: np.asarray(b.record.f),
        lambda b: "N",
    ),
    "curve": RecordKind(
        "friction_curve",
        lambda rec, o: curve_baseline(rec),
        lambda b: (f"velocity_{b.units[0]}", np.asarray(b.v)),
        lambda b: np.asarray(b.f),
        lambda b: b.units[1],
        lambda b, y: y / np.asarray(b.weight),
    ),
}


def rebuild(model: FittedModel, record):
    """(baseline, θ, designs, strengths) of `model` on `record` (a record of its kind)."""
    baseline = RECORD_KINDS[model.kind].build(record, model.options)
    return (baseline, *on_baseline(model, baseline))


def on_baseline(model: FittedModel, baseline):
    """(θ, designs, strengths) of `model` on a baseline of its kind (built on any record)."""
    at = model.origin or "model"
    if baseline.kind != model.kind:
        raise ValueError(f"{at}: a {model.kind} model, not a {baseline.kind} model")
    missing = [n for n in baseline.param_names if n not in model.parameters]
    if missing:
        raise ValueError(f"{at}: field 'parameters' lacks {missing} of the {model.kind} model")
    check_values(model, baseline.param_names, baseline.param_units, baseline.param_ranges(), at)
    theta = baseline.theta_of([model.parameters[n] for n in baseline.param_names])
    registry = {e.name: e for e in default_effects(baseline.kind)}
    designs, strengths = [], []
    for saved in model.effects:
        if saved.name not in registry:
            raise ValueError(
                f"{at}: effect {saved.name!r} is not a {model.kind} effect; known: "
                f"{sorted(registry)}"
            )
        d, s = _design(registry[saved.name], baseline, saved)
        for sn, su in zip(d.strength_names, d.strength_units):
            stated = model.units.get(f"{saved.name}.{sn}")
            if stated is not None and stated != su:
                raise ValueError(
                    f"{at}: field 'units.{saved.name}.{sn}' is {stated!r}; on this "
                    f"record the effect's {sn} is in {su!r}"
                )
        designs.append(d)
        strengths.extend(s)
    return theta, tuple(designs), np.asarray(strengths, dtype=float)


def fit_saved(model: FittedModel, baseline, *, max_steps=MAX_STEPS, sigma_known=None):
    """Fit `model` (its effects included, every parameter, strength and fitted nuisance free) on
    `baseline`'s record from the saved values, in the residual unit of `fit_record`
    (`record_scale`). `sigma_known`: default the record states its noise. Returns the
    `FitResult` of `fit_model` (why from the saved values: docs/fitting.md)."""
    theta, designs, s = on_baseline(model, baseline)
    known = bool(baseline.data().noise_std) if sigma_known is None else sigma_known
    return fit_model(
        baseline,
        designs,
        np.concatenate([theta, s]),
        None,
        record_scale(baseline),
        effects=tuple(e.name for e in model.effects),
        max_steps=max_steps,
        sigma_known=known,
    )


def _distance(a: float, b: float) -> float:
    if a != 0 and b != 0 and (a > 0) == (b > 0):
        return abs(math.log(a / b))
    return abs(a - b)


def _design(effect, baseline, saved):
    """The effect's design on `baseline` at the saved nuisance values and its strengths."""
    best, best_gap = None, math.inf
    for d in effect.designs(baseline):
        free = {name for _, name, _ in d.free}
        fixed = {k: v for k, v in d.nuisance.items() if k not in free}
        named = {n for i, n in enumerate(d.strength_names) if i not in {j for j, _, _ in d.free}}
        if set(d.nuisance) | free != set(saved.nuisance) or named != set(saved.strengths):
            continue
        if any(not math.isclose(saved.nuisance[k], v, rel_tol=1e-9) for k, v in fixed.items()):
            continue
        gap = sum(_distance(saved.nuisance[k], d.nuisance[k]) for k in free & set(d.nuisance))
        if gap < best_gap:
            best, best_gap = d, gap
    if best is None:
        raise ValueError(
            f"model: effect {saved.name!r} with strengths {sorted(saved.strengths)} "
            f"and nuisance {saved.nuisance} matches none of its designs on this "
            "record"
        )
    free = {i: (name, fn) for i, name, fn in best.free}
    s = []
    for i, name in enumerate(best.strength_names):
        unit = float(best.strength_scale[i])
        if i in free:
            nm, fn = free[i]
            s.append(_shift(lambda u, fn=fn, unit=unit: fn(u * unit), saved.nuisance[nm], nm))
        else:
            s.append(saved.strengths[name] / unit)
    return best, s


def _shift(fn, target: float, name: str) -> float:
    """u with fn(u) = target (fn monotone: a nuisance value as a function of its shift)."""
    g = lambda u: fn(u) - target  # noqa: E731
    for half in (1.0, 4.0, 16.0, 64.0):
        lo, hi = -half, half
        with np.errstate(over="ignore"):
            glo, ghi = g(lo), g(hi)
        if np.isfinite(glo) and np.isfinite(ghi) and glo * ghi <= 0:
            from scipy.optimize import brentq  # here: SciPy's import is a second of start-up

            return float(brentq(g, lo, hi, xtol=1e-15, rtol=1e-15))
    raise ValueError(f"model: nuisance {name} = {target:g} cannot be reached by this effect")
