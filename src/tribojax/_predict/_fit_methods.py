"""One entry point to fit a record, the method passed as a value (as `optimistix.least_squares`
takes its solver): `tj.fit(record)` fits the record's own model, as `tribojax fit RECORD` and
`discover`'s baseline do; `tj.fit(record, tj.SteadyLaw())` a friction curve's steady law, and
so on. The older names (`fit_slip_run`, `fit_loop`, `fit_history`, `fit_steady_curve`,
`fit_transient`, `refit`) are the methods' implementations and stay as documented shortcuts.

Every method is a frozen dataclass with `fit(record, *, start, max_steps, throw)`; a user's
own method needs nothing else.
"""

from __future__ import annotations

import abc
import dataclasses

from .._fit._result import FitResult, thrown
from .._limits import MAX_STEPS
from .._model import (
    FittedModel,
    curve_baseline,
    fit_loop,
    fit_record,
    fit_slip_run,
)
from .._model._history_fit import fit_history
from .._model._steady_law import fit_steady_curve, fit_transient
from ._prediction import refit


class FitMethod(abc.ABC):
    """How `fit` fits a record: a value whose `fit` method does it."""

    @abc.abstractmethod
    def fit(self, record, *, start=None, max_steps=None, throw=True):
        """The fit of `record` (a `RecordFit`, `FitResult` or `HistoryFit`)."""


@dataclasses.dataclass(frozen=True)
class RecordModel(FitMethod):
    """The record's own model, alone (no effects): what `tribojax fit RECORD` with no options and
    `discover`'s baseline fit. A slip run: the pre-slip LuGre model with the bristle exponent
    held at `alpha` (None: fitted; `fit_slip_run`); a loop: the `element` (jenkins or mindlin)
    driven through the loop (`fit_loop(model="history")`); a friction curve: Coulomb + viscous
    friction (`curve_baseline`, `fit_record`; no start values: its start is the linear fit)."""

    alpha: float | None = 1.0
    element: str = "jenkins"

    def fit(self, record, *, start=None, max_steps=None, throw=True, progress=None):
        steps = MAX_STEPS if max_steps is None else max_steps
        kind = getattr(record, "kind", type(record).__name__)
        if kind == "slip_run":
            return fit_slip_run(
                record,
                alpha=self.alpha,
                start=start,
                max_steps=steps,
                progress=progress,
                throw=throw,
            )
        if kind == "loop":
            return fit_loop(
                record, self.element, model="history", start=start, max_steps=steps, throw=throw
            )
        if kind == "friction_curve":
            if start:
                raise ValueError(
                    "start does not apply to a friction curve's record model (its start is the "
                    "linear least-squares fit)"
                )
            return thrown(fit_record(curve_baseline(record), max_steps=steps), throw)
        raise ValueError(
            f"a record model fits a slip run, a loop or a friction curve, not {kind!r} "
            "(a friction transient: tj.fit(transient, tj.Transient(steady)))"
        )


@dataclasses.dataclass(frozen=True)
class SteadyLoop(FitMethod):
    """wu2015's steady loop (Eq 1 Jenkins, Eq 2 Mindlin) at the loop's amplitude
    (`fit_loop(model="steady")`): a periodic loop only."""

    element: str = "jenkins"

    def fit(self, record, *, start=None, max_steps=None, throw=True):
        return fit_loop(
            record, self.element, model="steady", start=start, max_steps=max_steps, throw=throw
        )


@dataclasses.dataclass(frozen=True)
class History(FitMethod):
    """A friction element (+ a force offset) driven through the measured displacement history of
    one loop or several fitted together (`fit_history`): jenkins, mindlin, lugre, bouc_wen or
    band_brake, on every `decimate`-th sample; `n_starts`: Bouc–Wen's starts of n (None: the
    default one); `tension_law`: how the slip forces follow the band tension; `fixed`: (name,
    value) pairs held; `band_tension`: the tension (N) the slip forces are fitted at
    (`fit_history`)."""

    element: str = "jenkins"
    decimate: int = 1
    mixed_scales: bool = False
    n_starts: tuple[float, ...] | None = None
    tension_law: str = "auto"
    fixed: tuple[tuple[str, float], ...] = ()
    band_tension: float | None = None

    def fit(self, record, *, start=None, max_steps=None, throw=True):
        kw = {} if max_steps is None else {"max_steps": max_steps}
        if self.n_starts is not None and self.element == "bouc_wen":
            kw["n_starts"] = self.n_starts
        return fit_history(
            record,
            self.element,
            start=start,
            decimate=self.decimate,
            mixed_scales=self.mixed_scales,
            tension_law=self.tension_law,
            fixed=dict(self.fixed) or None,
            band_tension=self.band_tension,
            throw=throw,
            **kw,
        )


@dataclasses.dataclass(frozen=True)
class SteadyLaw(FitMethod):
    """The LuGre steady law of a friction curve (`fit_steady_curve`): `direction` +1 or −1 for
    the points of that velocity sign, None for both with the asymmetry T0."""

    direction: int | None = None

    def fit(self, record, *, start=None, max_steps=None, throw=True):
        if start:
            raise ValueError("start does not apply to the steady law (its start is from the data)")
        steps = {} if max_steps is None else {"max_steps": max_steps}
        return fit_steady_curve(record, direction=self.direction, throw=throw, **steps)


@dataclasses.dataclass(frozen=True)
class Transient(FitMethod):
    """LuGre's σ0 and σ1 from a friction transient, the steady law `steady` (a `SteadyLaw` fit)
    held (`fit_transient`); `sigma`: the friction noise (None: from the record)."""

    steady: FitResult
    sigma: float | None = None

    def fit(self, record, *, start=None, max_steps=None, throw=True):
        kw = {} if max_steps is None else {"max_steps": max_steps}
        if start is not None:
            kw["start"] = start
        return fit_transient(record, self.steady, sigma=self.sigma, throw=throw, **kw)


@dataclasses.dataclass(frozen=True)
class Saved(FitMethod):
    """A saved record model with its effects (`FittedModel`, e.g. from a discovery) refitted on
    the record from its saved values (`refit`)."""

    model: FittedModel

    def fit(self, record, *, start=None, max_steps=None, throw=True):
        if start:
            raise ValueError("start does not apply to a saved model (its values are the start)")
        steps = MAX_STEPS if max_steps is None else max_steps
        return refit(self.model, record, max_steps=steps, throw=throw)


def fit(record, method: FitMethod | None = None, *, start=None, max_steps=None, throw=True):
    """Fit `record` by `method` (default `RecordModel()`: the record's own model, as `tribojax
    fit RECORD` and `discover`'s baseline). `start`: start values by name where the method takes
    them; `max_steps`: the solver's step budget (None: the method's default); `throw`: raise
    `FitError` when the fit does not succeed (False: return it with `result` saying why)."""
    method = RecordModel() if method is None else method
    if not isinstance(method, FitMethod):
        raise ValueError(
            f"method must be a tribojax fit method (RecordModel, SteadyLoop, History, "
            f"SteadyLaw, Transient, Saved), got {type(method).__name__}"
        )
    return method.fit(record, start=start, max_steps=max_steps, throw=throw)
