"""A fit of a record as fit.json states it (`FitReport`): the engine's result with the record,
the residuals on the fitted samples, the noise the standard errors stand on, and the saved model
that `tribojax predict` takes. `tribojax fit` writes `FitReport.as_dict()`; a Python user gets
the same dictionary from the same fit."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._measures import nrmse, rms
from .._fit._result import FitResult
from .._model import RECORD_KINDS, RecordFit
from ._prediction import SAVED_KEY, fitted_model


@dataclasses.dataclass(frozen=True)
class FitReport:
    """A fit of `record` (its kind and source) as fit.json states it.

    Attributes:
        fit: the engine's `FitResult` (a `RecordFit` for a record model; a history fit's `.fit`).
        record: the record fitted (its `kind` and `source`; several records: the first).
        model: what was fitted, in words (fit.json "model").
        residuals: model − data on the `n_data` fitted samples, in `unit`.
        measured: the data on those samples (the NRMSE's denominator is their sd).
        unit: the residuals' unit (fit.json "residual_unit").
        sigma: the noise sd the standard errors stand on, as stated; None when none is stated
            (then the residual's, sqrt(RSS/(n_data − parameters)), what `discover` reports as
            its estimated noise within the estimators' difference).
        sigma_source: where `sigma` comes from, in words.
        saved: the model `predict` takes (None: the fit did not converge, or it is not a model
            that can be saved).
        extra: further fit.json entries of this record kind (they may replace "nrmse").
    """

    fit: FitResult
    record: object
    model: str
    residuals: np.ndarray = dataclasses.field(repr=False)
    measured: np.ndarray = dataclasses.field(repr=False)
    unit: str
    sigma: float | None = None
    sigma_source: str = "estimated from the residuals"
    saved: object = None
    extra: dict = dataclasses.field(default_factory=dict)

    @classmethod
    def of_record_model(cls, fit: RecordFit, record, model: str, **extra) -> FitReport:
        """The report of a record model's fit (`fit_record`, `fit_saved`, `refit`): residuals in
        the model's output unit (a curve's weighted friction), the record's stated noise, the
        saved model with its effects when the fit converged."""
        base = fit.model
        kind = RECORD_KINDS[base.kind]
        data = base.data()
        measured = np.asarray(data.y)
        saved = fitted_model(fit, str(record.source), [record])
        if saved.effects:
            model += f" with {', '.join(e.name for e in saved.effects)}"
        return cls(
            fit,
            record,
            model,
            fit.prediction - measured,
            measured,
            kind.unit(base),
            data.noise_std or None,
            "the record's noise sd" if data.noise_std else "estimated from the residuals",
            saved if fit.converged else None,
            extra,
        )

    @property
    def n_data(self) -> int:
        return int(np.asarray(self.residuals).size)

    @property
    def noise_sd(self) -> float:
        """fit.json "sigma": `sigma`, else sqrt(RSS/(n_data − parameters))."""
        if self.sigma is not None:
            return float(self.sigma)
        r = np.asarray(self.residuals, dtype=float)
        return float(np.sqrt(np.sum(r**2) / max(self.n_data - len(self.fit.names), 1)))

    def as_dict(self) -> dict:
        """The fit.json contract: the fit's summary (`FitResult.as_dict`), "kind", "source",
        "fitted", "n_data", "rms_residual", "residual_unit", "sigma", "sigma_source", "message",
        "model", "nrmse", "fitted_model" and, when the noise verdict contradicts the stated
        noise, "uncertainty_model"; then `extra`."""
        fit, how = self.fit, self.sigma_source
        d = fit.as_dict()
        d.update(
            kind=self.record.kind,
            source=str(self.record.source),
            fitted=list(fit.names),
            n_data=self.n_data,
            rms_residual=rms(self.residuals),
            residual_unit=self.unit,
            sigma=self.noise_sd,
            sigma_source=how,
            message=fit.message,
        )
        if fit.noise_consistent is False and fit.reduced_chi2 < 1.0:
            d["uncertainty_model"] = (
                f"the residuals are far below the stated noise ({how}; reduced chi2 = "
                f"{fit.reduced_chi2:.4g}): the standard errors, from the stated noise, are too "
                "large"
            )
        elif fit.noise_consistent is False:
            d["uncertainty_model"] = (
                f"the stated noise ({how}) is contradicted by the residuals (reduced chi2 = "
                f"{fit.reduced_chi2:.4g}): standard errors are scaled by sqrt(reduced chi2)"
            )
        d.update(
            model=self.model,
            nrmse=nrmse(self.residuals, self.measured),
            **{SAVED_KEY: None if self.saved is None else self.saved.as_dict()},
        )
        d.update(self.extra)
        return d


def saved_if_converged(result, source: str, records):
    """`fitted_model(result, source, records)` when the fit converged, else None."""
    fit = getattr(result, "fit", result)
    return fitted_model(result, source, records) if fit.converged else None
