"""A record model's fit (`RecordFit`: the engine's `FitResult` with the fitted model, its
prediction and effects), its residual unit (`record_scale`) and the map of its variables to
physical values (`_Physical`)."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .._export import cached_jit
from .._fit._noise import noise_estimate
from .._fit._result import FitResult
from ._base import AbstractBaseline


@dataclasses.dataclass(frozen=True)
class RecordFit(FitResult):
    """The fit of a record model (`fit_model`, `fit_record`, `fit_slip_run`, `fit_loop`'s loop
    model, `fit_saved`): the engine's `FitResult` and the record extras.

    Attributes (beyond `FitResult`'s):
        prediction: the model's samples at the optimum (output units).
        scale: the residual unit (output units; residuals = (prediction − data)/scale).
        model: the fitted record model (`AbstractBaseline`); effects: the names of the effects
            it carries; designs: their `EffectDesign`s.
        gain_left: the decrease of the cost that a Gauss–Newton step still predicts at the stop,
            in residual variances (a stationary stop with gain_left ≥ 1 is short of a minimum:
            `fit_record` then tries its next start).
    """

    prediction: np.ndarray | None = dataclasses.field(default=None, repr=False)
    scale: float | None = None
    model: object = dataclasses.field(default=None, repr=False)
    effects: tuple = ()
    designs: tuple = dataclasses.field(default=(), repr=False)
    gain_left: float | None = None


def record_scale(baseline) -> float:
    """The residual unit of a record model's fits (output units): the record's noise sd, else the
    first-difference estimate `noise_estimate` of its data, else their sd (else 1)."""
    data = baseline.data()
    y = np.asarray(data.y, dtype=float)
    scale = data.noise_std if data.noise_std else noise_estimate(y, data.segment)[0]
    return float(scale) if scale > 0 else float(np.std(y) or 1.0)


@dataclasses.dataclass(frozen=True)
class _Physical:
    """[θ_b, s] → [baseline.physical(θ_b), s·strength scale], the physical values of a record
    model's fit, with its Jacobian from one stored program (`fit_statistics`' delta method)."""

    baseline: AbstractBaseline
    scales: np.ndarray

    def value_and_jacobian(self, x):
        return _physical_and_jacobian(
            self.baseline, *(jnp.asarray(v, dtype=jnp.float64) for v in (self.scales, x))
        )


@cached_jit
def _physical_and_jacobian(baseline, scales, x):
    p = len(baseline.param_names)
    transform = lambda x: jnp.concatenate([baseline.physical(x[:p]), x[p:] * scales])  # noqa: E731
    return transform(x), jax.jacfwd(transform)(x)
