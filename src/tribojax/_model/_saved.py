"""A fitted model as a value (`FittedModel`): what `tribojax fit` and `tribojax discover` save
("fitted_model" in fit.json and discovery.json) and `tribojax predict` loads. Its values are
physical (units in `units`), never one record's θ or unit-scaled strengths, so the model
rebuilds on another record of the same kind.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

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
    (the record it was fitted to). `as_dict()` is the saved form, `from_dict` reads it back."""

    kind: str
    parameters: dict
    units: dict
    options: dict = dataclasses.field(default_factory=dict)
    effects: tuple = ()
    source: str = ""

    def as_dict(self) -> dict:
        return {
            "format": MODEL_FORMAT,
            "kind": self.kind,
            "options": dict(self.options),
            "parameters": dict(self.parameters),
            "units": dict(self.units),
            "effects": [dataclasses.asdict(e) for e in self.effects],
            "source": self.source,
        }

    @classmethod
    def from_dict(cls, d, where: str = "model") -> FittedModel:
        """The model saved as `d` (`as_dict`); ValueError naming `where` and the field that is
        missing, of another version or not a finite number."""
        if not isinstance(d, dict):
            raise ValueError(f"{where}: expected a JSON object, got {type(d).__name__}")
        fmt = d.get("format")
        if fmt != MODEL_FORMAT:
            raise ValueError(f"{where}: field 'format' is {fmt!r}; this tribojax reads "
                             f"{MODEL_FORMAT!r} (save the model again with this version)")
        kind = d.get("kind")
        if kind not in KINDS:
            raise ValueError(f"{where}: field 'kind' is {kind!r}; one of {list(KINDS)} expected")
        params = _numbers(d.get("parameters"), f"{where}: field 'parameters'")
        effects = []
        for i, e in enumerate(d.get("effects") or []):
            at = f"{where}: field 'effects[{i}]'"
            if not isinstance(e, dict) or not isinstance(e.get("name"), str):
                raise ValueError(f"{at}: expected an object with a 'name'")
            effects.append(SavedEffect(e["name"], _numbers(e.get("strengths", {}), at),
                                       _numbers(e.get("nuisance", {}), at)))  # fmt: skip
        options = d.get("options") or {}
        if not isinstance(options, dict):
            raise ValueError(f"{where}: field 'options' must be an object")
        units, source = dict(d.get("units") or {}), str(d.get("source", ""))
        return cls(kind, params, units, dict(options), tuple(effects), source)


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


def fitted_model(fit, source: str = "") -> FittedModel:
    """The `FittedModel` of a record-model fit (`fit_record`, `fit_slip_run`, `fit_loop(model=
    "history")`, or a discovery state): its baseline's kind and options, physical parameters
    and effects."""
    base = fit.model
    if base is None:
        raise ValueError("fitted_model needs the fit of a record model (FitResult.model is None: "
                         "a fit of another model, e.g. fit_loop(model='steady'))")
    p = len(base.param_names)
    params = dict(zip(base.param_names, np.asarray(fit.values[:p], float).tolist()))
    units = dict(zip(base.param_names, base.param_units))
    effects, strengths = [], effect_strengths(fit)
    for name in fit.effects:
        st = dict(strengths[name])
        nuisance = st.pop("nuisance")
        effects.append(SavedEffect(name, {k: v["value"] for k, v in st.items()}, nuisance))
        units.update({f"{name}.{k}": v["unit"] for k, v in st.items()})
    return FittedModel(base.kind, params, units, base.options(), tuple(effects), str(source))
