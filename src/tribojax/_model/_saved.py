"""A fitted model as a value (`FittedModel`): what `tribojax fit` and `tribojax discover` save
("fitted_model" in fit.json and discovery.json) and `tribojax predict` loads. Its values are
physical (units in `units`), never one record's θ or unit-scaled strengths, so the model
rebuilds on another record of the same kind.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .._io._record import extent_of
from .._limits import PARAMETER_LIMIT

MODEL_FORMAT = "tribojax.fitted_model/1"
"""The version of the saved-model layout; a file of another version is refused by name."""

KINDS = ("slip", "loop", "curve", "history")
"""Saved model kinds: the record models (`slip`, `loop`, `curve`: the baselines `fit` and
`discover` share) and `history` (a friction element driven through a displacement history,
`tribojax.fit_history`)."""


@dataclasses.dataclass(frozen=True)
class SavedEffect:
    """One effect of a fitted model: `name` (the registered effect name), `strengths` (physical
    values by strength name), `nuisance` (its fitted nuisance values by name)."""

    name: str
    strengths: dict
    nuisance: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class FittedModel:
    """A fitted model: `kind` (one of `KINDS`), `options` (how its model is built on a record,
    e.g. {"alpha": 1.0} for a slip run, {"element": "jenkins"} for a loop), `parameters` and their
    `units` (physical), `effects` (`SavedEffect`s in the order they were added) and `source`
    (the record it was fitted to), `fitted_range` (the conditions of the records it was fitted
    on, {quantity: {"min", "max", "unit"}}, `extent_of`; empty when not known). `as_dict()` is
    the saved form, `from_dict` reads it back; `origin` (not saved) is where it was read from,
    named by the errors it meets."""

    kind: str
    parameters: dict
    units: dict
    options: dict = dataclasses.field(default_factory=dict)
    effects: tuple = ()
    source: str = ""
    fitted_range: dict = dataclasses.field(default_factory=dict)
    origin: str = dataclasses.field(default="", compare=False, repr=False)

    def as_dict(self) -> dict:
        return {
            "format": MODEL_FORMAT,
            "kind": self.kind,
            "options": dict(self.options),
            "parameters": dict(self.parameters),
            "units": dict(self.units),
            "effects": [dataclasses.asdict(e) for e in self.effects],
            "source": self.source,
            "fitted_range": {k: dict(v) for k, v in self.fitted_range.items()},
        }

    @classmethod
    def from_dict(cls, d, where: str = "model") -> FittedModel:
        """The model saved as `d` (`as_dict`); ValueError naming `where` and the field that is
        missing, of another version or not a finite number."""
        if not isinstance(d, dict):
            raise ValueError(f"{where}: expected a JSON object, got {type(d).__name__}")
        fmt = d.get("format")
        if fmt != MODEL_FORMAT:
            raise ValueError(
                f"{where}: field 'format' is {fmt!r}; this tribojax reads "
                f"{MODEL_FORMAT!r} (save the model again with this version)"
            )
        kind = d.get("kind")
        if kind not in KINDS:
            raise ValueError(f"{where}: field 'kind' is {kind!r}; one of {list(KINDS)} expected")
        params = _numbers(d.get("parameters"), f"{where}: field 'parameters'")
        effects = []
        for i, e in enumerate(d.get("effects") or []):
            at = f"{where}: field 'effects[{i}]'"
            if not isinstance(e, dict) or not isinstance(e.get("name"), str):
                raise ValueError(f"{at}: expected an object with a 'name'")
            effects.append(
                SavedEffect(
                    e["name"],
                    _numbers(e.get("strengths", {}), at),
                    _numbers(e.get("nuisance", {}), at),
                )
            )
        options = d.get("options") or {}
        if not isinstance(options, dict):
            raise ValueError(f"{where}: field 'options' must be an object")
        units, source = dict(d.get("units") or {}), str(d.get("source", ""))
        ranges = d.get("fitted_range") or {}
        if not isinstance(ranges, dict):
            raise ValueError(f"{where}: field 'fitted_range' must be an object")
        fitted = {}
        for name, r in ranges.items():
            at = f"{where}: field 'fitted_range.{name}'"
            if not isinstance(r, dict) or not isinstance(r.get("unit"), str):
                raise ValueError(f"{at}: expected an object with 'min', 'max' and 'unit'")
            lims = _numbers({k: r.get(k) for k in ("min", "max")}, at)
            fitted[str(name)] = {**lims, "unit": r["unit"]}
        return cls(kind, params, units, dict(options), tuple(effects), source, fitted, where)


def check_values(model: FittedModel, names, units, ranges, where: str = "model") -> None:
    """Refuse a saved model whose parameter `names` lie outside their open `ranges` (lo, hi) or
    beyond ±`PARAMETER_LIMIT`, or whose stated units differ from `units` (the model's on this
    record); likewise every effect strength's magnitude. ValueError naming the field, its value
    and the allowed range."""
    for name, unit, (lo, hi) in zip(names, units, ranges):
        v, top = model.parameters[name], min(hi, PARAMETER_LIMIT)
        if not (lo < v < hi and abs(v) <= PARAMETER_LIMIT):
            shown = f"{v:g} {unit}".rstrip()
            low = f"{lo:g}" if lo > -PARAMETER_LIMIT else f"{-PARAMETER_LIMIT:g}"
            raise ValueError(
                f"{where}: field 'parameters.{name}' = {shown} is outside the "
                f"allowed range ({low}, {top:g}{')' if hi <= top else ']'}"
            )
        stated = model.units.get(name)
        if stated is not None and stated != unit:
            raise ValueError(
                f"{where}: field 'units.{name}' is {stated!r}; the {model.kind} "
                f"model on this record has {name} in {unit!r}"
            )
    for e in model.effects:
        for k, v in {**e.strengths, **e.nuisance}.items():
            if abs(v) > PARAMETER_LIMIT:
                raise ValueError(
                    f"{where}: effect {e.name!r}: {k} = {v:g} is outside the "
                    f"allowed range [{-PARAMETER_LIMIT:g}, {PARAMETER_LIMIT:g}]"
                )


def _numbers(d, where) -> dict:
    if not isinstance(d, dict):
        raise ValueError(f"{where}: expected an object of numbers")
    out = {}
    for k, v in d.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{where}: {k!r} = {v!r} is not a finite number")
        out[str(k)] = float(v)
    return out


def effect_strengths(fit) -> dict:
    """Per effect of a record-model fit (`fit_model`'s `FitResult`): {strength name: {"value",
    "std_error", "unit"}} (physical) and "nuisance" (its values; a strength that shifts a
    nuisance value reports the fitted value there). The "strengths" of discovery.json."""
    p = len(fit.model.param_names)
    out, j = {}, 0
    for name, d in zip(fit.effects, fit.designs):
        entry = {}
        nuisance = {k: float(v) for k, v in d.nuisance.items()}
        free = {i: (nm, fn) for i, nm, fn in d.free}
        for i, (sn, su) in enumerate(zip(d.strength_names, d.strength_units)):
            s = fit.theta[p + j + i]
            var = fit.theta_covariance[p + j + i, p + j + i]
            if i in free:  # a fitted nuisance value (the grid point seeded it)
                nuisance[free[i][0]] = float(free[i][1](s * d.strength_scale[i]))
                continue
            entry[sn] = {
                "value": float(s * d.strength_scale[i]),
                "std_error": float(np.sqrt(max(var, 0.0)) * abs(d.strength_scale[i])),
                "unit": su,
            }
        entry["nuisance"] = nuisance
        out[name] = entry
        j += d.k
    return out


def saved_record_model(fit, source: str = "", records=()) -> FittedModel:
    """The `FittedModel` of a record-model fit (`fit_record`, `fit_slip_run`, `fit_loop(model=
    "history")`, or a discovery state): its baseline's kind and options, physical parameters
    and effects, and the conditions of the fitted `records` (`fitted_range`)."""
    base = getattr(fit, "model", None)
    if base is None:
        raise ValueError(
            "a saved model needs the fit of a record model (a RecordFit; got a "
            f"{type(fit).__name__} of another model, e.g. fit_loop(model='steady'))"
        )
    p = len(base.param_names)
    params = dict(zip(base.param_names, np.asarray(fit.values[:p], float).tolist()))
    units = dict(zip(base.param_names, base.param_units))
    effects, strengths = [], effect_strengths(fit)
    for name in fit.effects:
        st = dict(strengths[name])
        nuisance = st.pop("nuisance")
        effects.append(SavedEffect(name, {k: v["value"] for k, v in st.items()}, nuisance))
        units.update({f"{name}.{k}": v["unit"] for k, v in st.items()})
    return FittedModel(
        base.kind, params, units, base.options(), tuple(effects), str(source), extent_of(records)
    )
