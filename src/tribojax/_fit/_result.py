"""The outcome of a fit (`FitResult`, `FitError`, `thrown`) and its statistics at the optimum
(`fit_statistics`: covariance by the SVD of the Jacobian, the delta method, identifiability and
the noise verdict). A record model's fit adds its extras in `tribojax._model.RecordFit`."""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .._results import RESULTS, result_name
from ._noise import ALPHA, chi2_sf
from ._noise import noise_consistent as _noise_test

# A direction of θ whose singular value is below this fraction of the largest is reported as not
# identifiable (the Jacobian is numerically rank-deficient at the square root of float64's eps).
IDENTIFIABLE_RTOL = 1e-8


class FitError(RuntimeError):
    """A fit asked to throw (`throw=True`) did not succeed; `fit` holds its `FitResult` (the
    failure is a `RESULTS` value inside, raised only at the entry point, as in optimistix)."""

    def __init__(self, fit: FitResult):
        self.fit = fit
        super().__init__(f"the fit did not succeed ({result_name(fit.result)}): {fit.message}")


def thrown(fit, throw: bool):
    """`fit` itself, or `FitError` when `throw` and the fit did not succeed (the boundary)."""
    if throw and not fit.converged:
        raise FitError(fit)
    return fit


@dataclasses.dataclass(frozen=True)
class FitResult:
    """Outcome of a fit (NumPy arrays; physical coordinates unless stated).

    Attributes:
        names: parameter names.
        values: fitted parameters.
        std_errors: standard errors (delta method from θ).
        covariance, correlation: p×p matrices.
        theta: the unconstrained optimum.
        residuals: residuals at the optimum (as returned by the residual function).
        singular_values: of the Jacobian in θ, largest first (identifiability).
        converged: `result == RESULTS.successful` (derived from `result`; given alone, `result`
            becomes successful or `RESULTS.not_converged`).
        steps: solver steps taken.
        message: `RESULTS[result]` ("" on success), or a more specific text.
        fixed: constants held fixed in the fit (set by the caller, e.g. {"M": 1.0}).
        jacobian: ∂residuals/∂θ at the optimum, (n, p) (`least_squares_fit`; None elsewhere).
        result: the outcome, a `tribojax.RESULTS` member.
        reduced_chi2: RSS/(n − p) of the residuals (in units of the stated noise if known).
        noise_consistent: whether the residual is the stated noise (`tribojax._fit._noise.
            noise_consistent`: its χ² at level α/3, or a record model's full test, which also
            judges an estimated noise); when not, the standard errors are scaled by the
            residual. None when the noise scale was estimated and no record test applies.
        unidentifiable: the directions of θ that the data do not determine (relative singular
            value ≤ `IDENTIFIABLE_RTOL`), each {"direction": {name: component},
            "relative_singular_value": s_k/s_max}; `converged` says nothing about these.
        theta_covariance: covariance of θ itself (inf along undetermined directions).

    A record model's fit is a `tribojax._model.RecordFit`: this and the fitted model, its
    prediction and effects.
    """

    names: tuple[str, ...]
    values: np.ndarray
    std_errors: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    theta: np.ndarray
    residuals: np.ndarray
    singular_values: np.ndarray
    converged: bool | None = None
    steps: int = 0
    message: str | None = None
    fixed: dict = dataclasses.field(default_factory=dict)
    jacobian: np.ndarray | None = None
    result: RESULTS | None = None
    reduced_chi2: float | None = None
    noise_consistent: bool | None = None
    unidentifiable: tuple = ()
    theta_covariance: np.ndarray | None = None

    @property
    def rss(self) -> float:
        """Σ residuals² (in units of `scale`²); inf when a residual is not finite."""
        r = np.asarray(self.residuals, dtype=float)
        return float(r @ r) if np.all(np.isfinite(r)) else float("inf")

    def __post_init__(self):
        result = self.result
        if result is None:
            if self.converged is None:
                raise TypeError("FitResult needs `result` (a tribojax.RESULTS member) or converged")
            result = RESULTS.successful if self.converged else RESULTS.not_converged
        elif not isinstance(result, RESULTS):
            result = RESULTS.promote(result)
        ok = bool(result == RESULTS.successful)
        if self.converged is not None and bool(self.converged) != ok:
            raise ValueError(
                f"converged = {self.converged} contradicts result {result_name(result)!r}"
            )
        object.__setattr__(self, "result", result)
        object.__setattr__(self, "converged", ok)
        if self.message is None:
            object.__setattr__(self, "message", str(RESULTS[result]))

    def with_result(self, result, message: str | None = None) -> FitResult:
        """A copy with another outcome (`converged` and `message` follow it)."""
        return dataclasses.replace(self, result=result, converged=None, message=message)

    def as_dict(self) -> dict:
        """Summary as plain Python numbers (non-finite entries mark unidentifiable directions)."""
        return {
            "parameters": dict(zip(self.names, self.values.tolist())),
            "std_errors": dict(zip(self.names, self.std_errors.tolist())),
            "correlation": self.correlation.tolist(),
            "converged": self.converged,
            "steps": self.steps,
            "singular_values": self.singular_values.tolist(),
            "fixed": dict(self.fixed),
            "result": result_name(self.result),
            "reduced_chi2": self.reduced_chi2,
            "noise_consistent": self.noise_consistent,
            "identified": not self.unidentifiable,
            "unidentifiable": [dict(d) for d in self.unidentifiable],
        }


OVERSTATED = 0.5
"""A reduced χ² below this, and significantly so, contradicts a stated noise from below."""


def fit_statistics(
    theta,
    r,
    J,
    *,
    names,
    transform,
    sigma_known,
    result,
    steps,
    message=None,
    noise_consistent=None,
    result_type=None,
    **extra,
):
    """A FitResult from the optimum θ, its residuals r and Jacobian J = ∂r/∂θ.

    Covariance of θ: s²(JᵀJ)⁻¹ through the SVD of J (s² = RSS/(n − p), or 1 if `sigma_known`);
    directions with singular values ≤ 1e-14 of the largest get infinite variance. Mapped to the
    physical parameters `transform(θ)` by the delta method, T·cov·Tᵀ with T = ∂transform/∂θ
    (`transform`: a callable, None for the identity, or an object whose `value_and_jacobian(θ)`
    gives both, as the record models' fits pass: one compiled program instead of eager steps).
    With `sigma_known` and a χ² that `noise_consistent` rejects (or `noise_consistent` given
    False: a record model's full test) the stated noise is contradicted by the misfit:
    `noise_consistent` is False and s² = RSS/(n − p) is used instead of 1. A residual far below
    the stated noise (reduced χ² under `OVERSTATED` and in χ²'s lower α/3 tail: an overstated
    noise) also gives `noise_consistent` False, with the stated noise's (too large) errors kept.
    """
    theta = np.asarray(theta, dtype=np.float64)
    r, J = np.asarray(r, dtype=np.float64), np.asarray(J, dtype=np.float64)
    n, p = J.shape
    # a Jacobian that is not finite (a failed evaluation) determines nothing: infinite variances
    finite = np.all(np.isfinite(J))
    _, sv, vt = np.linalg.svd(J if finite else np.zeros_like(J), full_matrices=False)
    tiny = sv <= (sv[0] if sv.size else 0.0) * 1e-14  # (no parameters: nothing is tiny)
    chi2 = float(r @ r) / max(n - p, 1)
    consistent = noise_consistent
    if consistent is None and sigma_known:  # the χ² part of the one noise test
        consistent = _noise_test(r, 1.0, n_params=p)[0]
    # a residual far below the stated noise contradicts it too (its errors are too large); they
    # are kept, not scaled down by the residual (a noiseless record would get zero errors)
    overstated = bool(
        consistent
        and sigma_known
        and chi2 < OVERSTATED
        and n > p
        and 1.0 - chi2_sf(float(r @ r), n - p) < ALPHA / 3
    )
    scale2 = 1.0 if sigma_known and consistent else chi2
    consistent = False if overstated else consistent

    def delta(T):
        # T·V·S⁻¹ over the determined directions; a parameter that moves along an undetermined
        # one (singular value ~0) gets infinite variance (and no NaN from 0·inf); a component at
        # round-off level, |T·v| ≤ 1e-10·|T row|, is not a dependence
        A = (T @ vt[~tiny].T) / sv[~tiny][None, :]
        cov = scale2 * (A @ A.T)
        load = np.abs(T @ vt[tiny].T)
        with np.errstate(over="ignore"):  # a row of ~1e300 (a start far off): its norm is inf
            free = np.any(load > 1e-10 * np.linalg.norm(T, axis=1, keepdims=True), axis=1)
        cov[np.ix_(free, free)] = np.inf
        return cov

    if callable(getattr(transform, "value_and_jacobian", None)):  # one compiled program
        values, T = (np.asarray(v, dtype=np.float64) for v in transform.value_and_jacobian(theta))
    elif transform is None:  # the identity: no JAX operation
        values, T = theta.copy(), np.eye(theta.size)
    else:
        values = np.asarray(transform(jnp.asarray(theta)))
        T = np.asarray(jax.jacfwd(transform)(jnp.asarray(theta)))
    cov = delta(T)
    with np.errstate(invalid="ignore"):
        std = np.sqrt(np.diag(cov))
        corr = cov / np.outer(std, std)
    return (result_type or FitResult)(
        names=tuple(names),
        values=values,
        std_errors=std,
        covariance=cov,
        correlation=corr,
        theta=theta,
        residuals=r,
        singular_values=sv,
        steps=int(steps),
        message=message,
        jacobian=J,
        result=result,
        reduced_chi2=chi2,
        noise_consistent=consistent,
        unidentifiable=_singular_directions(sv, vt, names),
        theta_covariance=delta(np.eye(p)),
        **extra,
    )


def _singular_directions(sv, vt, names) -> tuple:
    """The directions of θ with singular values ≤ IDENTIFIABLE_RTOL of the largest."""
    top = sv[0] if sv.size else 0.0
    p = vt.shape[1]
    labels = list(names) if len(names) == p else [f"theta[{i}]" for i in range(p)]
    out = []
    for k in np.flatnonzero(sv <= top * IDENTIFIABLE_RTOL):
        v = vt[k] * np.sign(vt[k][np.argmax(np.abs(vt[k]))])  # largest component positive
        out.append(
            {
                "direction": dict(zip(labels, v.tolist())),
                "relative_singular_value": float(sv[k] / top) if top > 0 else 0.0,
            }
        )
    return tuple(out)
