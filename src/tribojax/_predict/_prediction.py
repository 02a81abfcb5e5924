"""Predict a record with a fitted model: `load_model` (fit.json, discovery.json or a bare saved
model), `predict(model, record)` → `Prediction` (prediction.json, prediction.csv)."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np

from .._fit._measures import nrmse, rms
from .._fit._result import FitResult, thrown
from .._io._record import extent_of
from .._model import (
    MAX_STEPS,
    RECORD_KINDS,
    FittedModel,
    SavedEffect,
    check_values,
    evaluate,
    fit_saved,
    rebuild,
    saved_record_model,
)
from .._model._history_fit import HistoryFit
from .._model._history_model import HISTORY_MODELS, HISTORY_UNITS, history_force, law_spec
from .._tables import read_json
from ..discovery import DiscoveryReport

SAVED_KEY = "fitted_model"
"""The key of the saved model in fit.json and discovery.json."""


class ExtrapolationWarning(UserWarning):
    """`predict` on a record whose conditions lie beyond the model's fitted range (`beyond`);
    the same entries are in `Prediction.extrapolation`."""


@dataclasses.dataclass(frozen=True)
class Prediction:
    """A fitted model evaluated on a record: the sample axis `x` (named `x_name`, e.g. time_s),
    `measured` and `predicted` (output `unit`), their NRMSE = rms(predicted − measured) /
    std(measured) and rms error, the `model` and the `record` (its source); `extrapolation`:
    the record's conditions beyond the model's `fitted_range` (`beyond`; [] none, None when the
    model saved no range)."""

    model: FittedModel
    record: str
    x_name: str
    x: np.ndarray = dataclasses.field(repr=False)
    measured: np.ndarray = dataclasses.field(repr=False)
    predicted: np.ndarray = dataclasses.field(repr=False)
    unit: str
    nrmse: float
    rms_error: float
    extrapolation: list | None = None

    def columns(self) -> tuple[str, str, str]:
        """The CSV header: the axis, measured_<unit>, predicted_<unit>."""
        u = self.unit.replace(" ", "_").replace("/", "_per_")
        return (self.x_name, f"measured_{u}", f"predicted_{u}")

    def as_dict(self) -> dict:
        """The prediction.json contract: "nrmse", "model", "record" (plus extra keys)."""
        return {
            "nrmse": self.nrmse,
            "model": self.model.as_dict(),
            "record": self.record,
            "rms_error": self.rms_error,
            "unit": self.unit,
            "n_data": int(self.x.size),
            "extrapolation": self.extrapolation,
            "columns": list(self.columns()),
            "what": "nrmse = rms(predicted - measured) / std(measured)",
        }


def fitted_model(result, source: str = "", records=()) -> FittedModel:
    """The `FittedModel` of a fit: a record-model `FitResult` (`fit_slip_run`, `fit_loop(model=
    "history")`, `fit_record`), a steady-law fit of both directions (`fit_steady_curve`: the
    curve model with its `stribeck` and `asymmetry` effects), a `HistoryFit` (`fit_history`) or
    a `DiscoveryReport` (its final model: the baseline and the effects discovery added).
    `records`: the records it was fitted on; their conditions are saved as the model's
    `fitted_range`, which `predict` compares a record with (none given: no range is saved and
    `predict` cannot say when it extrapolates)."""
    model = _fitted_model(result, source)
    return dataclasses.replace(model, fitted_range=extent_of(records)) if records else model


def _fitted_model(result, source) -> FittedModel:
    if isinstance(result, DiscoveryReport):
        if result.fitted is None:
            raise ValueError("the discovery's baseline fit failed: it has no model to save")
        return dataclasses.replace(result.fitted, source=source or result.fitted.source)
    if isinstance(result, HistoryFit):
        names = list(result.names)  # the element's, f0, then any tension law's
        params = dict(zip(names, result.values.tolist()))
        return FittedModel(
            "history",
            params,
            {n: HISTORY_UNITS[n] for n in names},
            {
                "element": result.model,
                "decimate": result.decimate,
                **({} if result.band_tension is None else {"band_tension_N": result.band_tension}),
            },
            source=source,
        )
    if isinstance(result, FitResult) and result.fixed.get("direction") == "both":
        return _steady_law(result, source)
    if isinstance(result, FitResult):
        return saved_record_model(result, source)
    raise ValueError(
        f"fitted_model takes a FitResult, HistoryFit or DiscoveryReport, got "
        f"{type(result).__name__}"
    )


def _steady_law(fit, source) -> FittedModel:
    """The LuGre steady law with asymmetry (`fit_steady_curve`, both directions) as the curve
    model: Coulomb + viscous (F_c, σ2) with the `stribeck` (F_s − F_c; v_s, β) and `asymmetry`
    (T0) effects: the same law term by term (`discovery.curve_baseline`)."""
    p = dict(zip(fit.names, np.asarray(fit.values, float).tolist()))
    fu, vu = fit.fixed["friction_unit"], fit.fixed["velocity_unit"]
    effects = (
        SavedEffect(
            "stribeck", {"F_s_minus_F_c": p["F_s"] - p["F_c"]}, {"v_s": p["v_s"], "beta": p["beta"]}
        ),
        SavedEffect("asymmetry", {"T0": p["T0"]}),
    )
    units = {
        "F_c": fu,
        "sigma2": f"{fu} per {vu}",
        "stribeck.F_s_minus_F_c": fu,
        "asymmetry.T0": fu,
    }
    return FittedModel(
        "curve", {"F_c": p["F_c"], "sigma2": p["sigma2"]}, units, {}, effects, source
    )


def load_model(path) -> FittedModel:
    """The model saved in `path`: a fit.json or discovery.json (its "fitted_model") or a saved
    model itself. ValueError naming the file and the field that is missing or wrong."""
    path = Path(path)
    d, _ = read_json(path)  # DataFileError naming the file
    saved, where = d, str(path)
    if isinstance(d, dict) and "format" not in d:
        if SAVED_KEY in d and d[SAVED_KEY] is None:
            why = d.get("not_a_result") or d.get("message") or "the fit did not succeed"
            raise ValueError(f"{path}: field '{SAVED_KEY}' is null: the fit saved no model ({why})")
        if d.get(SAVED_KEY) is None:
            raise ValueError(
                f"{path}: no field '{SAVED_KEY}' (written by `tribojax fit` or "
                "`discover` of this version for a slip run, loop, history or "
                "friction curve; wu2015's steady-loop fit saves none)"
            )
        saved, where = d[SAVED_KEY], f"{path}: {SAVED_KEY}"
    model = FittedModel.from_dict(saved, where)
    if model.kind == "history":
        _check_history(model, where)
    return model


def predict(model: FittedModel, record, *, initial: str | None = None) -> Prediction:
    """Evaluate `model` on `record`, a record of its kind it may never have seen (a slip run for
    a slip model, a loop or history for a loop or history model, a friction curve for a curve
    model): the record's model rebuilt with the saved parameters and effects (`_rebuild`),
    nothing refitted. A loop model is compared from the record's first reversal on (as it is
    fitted); a history model from rest at the first sample (every `decimate`-th sample of the
    fit), or with `initial="measured"` from the state that carries the record's first measured
    force (Jenkins and band-brake history models; loop models: `loaded_state`). `initial=None`:
    as the model was fitted (rest, or "measured" for a loop model fitted from a loaded start).
    ValueError when the record is of another kind."""
    if not isinstance(model, FittedModel):
        raise ValueError(
            f"model must be a FittedModel (tribojax.load_model), got {type(model).__name__}"
        )
    source = str(getattr(record, "source", ""))
    need = "loop" if model.kind == "history" else RECORD_KINDS[model.kind].record_kind
    _check_kind(model, record, need, "predicts")
    if initial not in (None, "rest", "measured"):
        raise ValueError(f"initial = {initial!r}: one of [None, 'rest', 'measured'] expected")
    if model.kind == "history":
        x_name, unit = "time_s", "N"
        x, measured, predicted = _history(model, record, initial or "rest")
    elif initial == "measured" and model.kind != "loop":
        raise ValueError(
            f"initial = {initial!r}: a {model.kind} model starts as its fit did; "
            "'measured' is for loop and history models"
        )
    else:
        if model.kind == "loop" and initial is not None:
            model = dataclasses.replace(model, options={**model.options, "initial": initial})
        rk = RECORD_KINDS[model.kind]
        baseline, theta, designs, s = rebuild(model, record)
        x_name, x = rk.axis(baseline)
        measured, unit = rk.measured(baseline), rk.unit(baseline)
        predicted = rk.output(baseline, evaluate(baseline, theta, designs, s))
    err = predicted - measured
    far = beyond(model.fitted_range, record.extent()) if model.fitted_range else None
    for d in far or ():
        warnings.warn(describe_beyond(d), ExtrapolationWarning, stacklevel=2)
    return Prediction(
        model,
        source,
        x_name,
        np.asarray(x),
        measured,
        predicted,
        unit,
        nrmse(err, measured),
        rms(err),
        far,
    )


EXTRAPOLATION_MARGIN = 1.25
"""A record's condition is beyond a model's fitted range when it lies more than this factor
outside it (above max × 1.25 or below min / 1.25): a prediction there extrapolates."""


def beyond(fitted_range: dict, extent: dict, margin: float = EXTRAPOLATION_MARGIN) -> list:
    """The conditions of a record (`extent`, `AbstractRecord.extent`) outside a model's
    `fitted_range` by more than `margin`: [{"quantity", "record_min", "record_max",
    "fitted_min", "fitted_max", "unit"}]; a quantity either lacks, or in other units, is
    skipped."""
    out = []
    for name, (lo, hi, unit) in extent.items():
        r = fitted_range.get(name)
        if r is None or r["unit"] != unit:
            continue
        if hi > r["max"] * margin or lo < r["min"] / margin:
            out.append(
                {
                    "quantity": name,
                    "record_min": float(lo),
                    "record_max": float(hi),
                    "fitted_min": r["min"],
                    "fitted_max": r["max"],
                    "unit": unit,
                }
            )
    return out


def describe_beyond(d: dict) -> str:
    """One line for an entry of `beyond`."""

    def span(lo, hi):
        return f"{lo:.3g}" if lo == hi else f"{lo:.3g} to {hi:.3g}"

    return (
        f"extrapolation: the record's {d['quantity'].replace('_', ' ')} "
        f"({span(d['record_min'], d['record_max'])} {d['unit']}) lies outside the fitted "
        f"range ({span(d['fitted_min'], d['fitted_max'])} {d['unit']})"
    )


def refit(model: FittedModel, record, *, max_steps: int = MAX_STEPS, throw: bool = True):
    """Fit a saved record model, effects included, to `record`, from its saved values: the model a
    discovery found on one record refitted on another (its parameters, the effects' strengths and
    their fitted nuisance values, e.g. a clearance's gap, all free). The residual unit and the
    statistics are those of `fit_record` (the record's noise sd, else the first-difference
    estimate). Returns the `FitResult` of `fit_model` (`fitted_model(result)` saves it);
    it raises `FitError` when the fit fails, unless `throw=False`."""
    if model.kind not in RECORD_KINDS:
        raise ValueError(
            f"refit takes a record model (slip, loop, curve), not a {model.kind!r} "
            "model (a history fit: tribojax.fit_history)"
        )
    _check_kind(model, record, RECORD_KINDS[model.kind].record_kind, "fits")
    baseline = RECORD_KINDS[model.kind].build(record, model.options)
    return thrown(fit_saved(model, baseline, max_steps=max_steps), throw)


def _check_kind(model, record, need, verb):
    kind = getattr(record, "kind", type(record).__name__)
    if kind != need:
        raise ValueError(
            f"{getattr(record, 'source', '') or 'record'}: a {kind} record; the "
            f"{model.kind} model {verb} {need} records"
        )


def _check_history(model, where) -> list:
    """The parameter names of a saved history model (the element's, f0, then the tension
    law's it has: `law_spec`); ValueError naming `where` and the field (the element, a missing
    parameter, a band tension that is not > 0, or < 0 with a tension law)."""
    element = model.options.get("element")
    if element not in HISTORY_MODELS:
        raise ValueError(
            f"{where}: field 'options.element' is {element!r}; one of "
            f"{sorted(HISTORY_MODELS)} expected"
        )
    spec = HISTORY_MODELS[element]
    spec += tuple(kv for kv in law_spec(element, 3) if kv[0] in model.parameters)
    names = [n for n, _ in spec]
    missing = [n for n in names[: len(HISTORY_MODELS[element])] if n not in model.parameters]
    if missing:
        raise ValueError(f"{where}: field 'parameters' lacks {missing} of the {element} model")
    check_values(
        model,
        names,
        [HISTORY_UNITS[n] for n in names],
        [(0.0, np.inf) if positive else (-np.inf, np.inf) for _, positive in spec],
        where,
    )
    tension = model.options.get("band_tension_N")
    law = len(spec) > len(HISTORY_MODELS[element])
    if tension is not None and not (
        isinstance(tension, int | float) and (tension >= 0 if law else tension > 0)
    ):
        raise ValueError(
            f"{where}: field 'options.band_tension_N' is {tension!r}; a tension "
            f"{'>= 0' if law else '> 0'} (N) expected"
        )
    return names


def _history(model, loop, initial):
    names = _check_history(model, "model")
    dec = int(model.options.get("decimate", 1))
    values = [model.parameters[n] for n in names]
    tension = model.options.get("band_tension_N")
    element = model.options["element"]
    law = names[len(HISTORY_MODELS[element]) :]
    force, _ = history_force(element, values, loop, dec, tension, initial, law)
    return np.asarray(loop.t[::dec]), np.asarray(loop.f[::dec]), force
