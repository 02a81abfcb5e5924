"""wang2022's measured Tables 4–7 as the chain fit sees them (`measured_slips`, the acceptance
metric `rms_relative`, the symmetric bound) and a full-chain fit's result (`ChainFit`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._measures import rms
from .._fit._result import FitResult
from .._results import RESULTS, result_name
from .._tables import wang2022_table

TABLES = (4, 5, 6, 7)
SAME_OPTIMUM = 0.1  # converged fits of one misfit agree when every parameter is within 0.1 s.e.


def measured_slips() -> np.ndarray:
    """Measured [T4, T5, T6, T7] (nm) of wang2022 Tables 4–7, shape (6, 4) (rows: Table 3's)."""
    return np.stack([wang2022_table(n)["measured_nm"] for n in TABLES], axis=1)


def paper_theory_slips() -> np.ndarray:
    """The paper's theoretical [T4, T5, T6, T7] (nm), shape (6, 4)."""
    return np.stack([wang2022_table(n)["theory_nm"] for n in TABLES], axis=1)


def rms_relative(model, measured, keep=None) -> float:
    """√mean((model/measured − 1)²) over all cells (or those where `keep` is True): the
    acceptance metric."""
    r = np.asarray(model, dtype=float) / np.asarray(measured, dtype=float) - 1.0
    return rms(r if keep is None else r[np.asarray(keep, dtype=bool)])


def symmetric_bound(measured=None) -> dict:
    """Best RMS relative residual that any model with T6 = −T4 and T7 = −T5 can reach.

    For a measured pair (a, b) and model (x, −x) the relative squared error (x/a − 1)² +
    (x/b + 1)² is least at x* = (1/a − 1/b)/(1/a² + 1/b²). Returns the bound over the 24 cells
    and the per-pair optimum (nm). The chain is symmetric to ~1e-3 (|T4 + T6|/|T4|), so this
    bounds what it can reach.
    """
    m = measured_slips() if measured is None else np.asarray(measured, dtype=float)
    model = np.empty_like(m)
    for i, j in ((0, 2), (1, 3)):
        a, b = m[:, i], m[:, j]
        x = (1 / a - 1 / b) / (1 / a**2 + 1 / b**2)
        model[:, i], model[:, j] = x, -x
    return {"rms_relative_residual": rms_relative(model, m), "best_symmetric_nm": model.tolist()}


# --- the fit -----------------------------------------------------------------------------------


class ChainFitError(RuntimeError):
    """The full-chain fit could not be carried out (names the trial point and the cause)."""


@dataclasses.dataclass(frozen=True)
class ChainFit:
    """A full-chain fit: the `FitResult` (free parameters) plus the chain's view of it.

    Attributes:
        fit: FitResult over the free parameters (θ statistics, covariance by the delta method).
        parameters: all five physical parameters (free and fixed), dict.
        free: names of the free parameters.
        model_nm, target_nm: (n, 4) phase slips at the optimum (NaN: not evaluated), the data.
        scaled_singular_values, scaled_right_vectors: SVD of the Jacobian of the residuals with
            respect to log p (elasticities); rows of the right vectors are parameter combinations,
            largest singular value first.
        wall_s: wall time of the fit (s). evaluations: residual evaluations (incl. Jacobians),
            counted when progress is shown; else LM steps + 1 (one evaluation per trial point:
            the count itself is a host callback, which would keep the fit out of the cache).
        start: the physical start.
        gauss_newton_step: the Gauss–Newton step left at the end, max |δp|/std error (module
            docstring, Convergence).
        restarts: when the fit from `start` stopped short of an optimum, the fits from the
            `RESTART_SIGNS` starts around it (each {"start", "converged", "rms_relative_residual",
            "parameters"}); the one kept has the lowest misfit (a converged one first).
        spread: per free parameter, the largest distance (in standard errors of the kept fit)
            to another converged fit of the same misfit (`identified`).
    """

    fit: FitResult
    parameters: dict
    free: tuple
    model_nm: np.ndarray
    target_nm: np.ndarray
    scaled_singular_values: np.ndarray
    scaled_right_vectors: np.ndarray
    wall_s: float
    evaluations: int
    start: dict
    gauss_newton_step: float = float("nan")
    restarts: tuple = ()
    spread: dict = dataclasses.field(default_factory=dict)

    @property
    def identified(self) -> bool:
        """False when the data leave a direction undetermined (`fit.unidentifiable`) or when
        converged starts reach the same misfit (RMS within `SAME_MISFIT`) at parameters more
        than `SAME_OPTIMUM` standard errors apart (`spread`): a ridge."""
        return not self.fit.unidentifiable and all(v <= SAME_OPTIMUM for v in self.spread.values())

    @property
    def converged(self) -> bool:
        return self.fit.converged

    @property
    def result(self) -> RESULTS:
        """The outcome (`tribojax.RESULTS`), that of `fit`."""
        return self.fit.result

    @property
    def rms_relative_residual(self) -> float:
        return rms_relative(self.model_nm, self.target_nm)

    def combinations(self, tol=1e-3) -> list[dict]:
        """Parameter combinations (in log p) the data determine, best first; `determined` is
        False for singular values below `tol` × the largest."""
        sv = self.scaled_singular_values
        return [
            {
                "singular_value": float(s),
                "determined": bool(s > tol * sv[0]),
                "log_combination": {
                    k: float(c) for k, c in sorted(zip(self.free, v), key=lambda t: -abs(t[1]))
                },
            }
            for s, v in zip(sv, self.scaled_right_vectors)
        ]

    def as_dict(self) -> dict:
        """JSON-ready report (the `fit_measured` block of reproduction.json)."""
        f = self.fit
        resid = self.model_nm / self.target_nm - 1.0
        vac = wang2022_table(3)["vacuum_kPa"]
        cells = [
            {
                "table": n,
                "vacuum_kPa": float(vac[i]) if self.target_nm.shape[0] == len(vac) else i,
                "measured_nm": float(self.target_nm[i, j]),
                "model_nm": float(self.model_nm[i, j]),
                "rel_residual": float(resid[i, j]),
            }
            for i in range(self.target_nm.shape[0])
            for j, n in enumerate(TABLES)
        ]
        return {
            "parameters": dict(self.parameters),
            "free_parameters": list(self.free),
            "std_errors": dict(zip(f.names, f.std_errors.tolist())),
            "correlation": f.correlation.tolist(),
            "rms_relative_residual": self.rms_relative_residual,
            "converged": f.converged,
            "message": f.message,
            "result": result_name(f.result),
            "steps": f.steps,
            "residual_evaluations": self.evaluations,
            "gauss_newton_step_over_std_error": self.gauss_newton_step,
            "wall_s": self.wall_s,
            "relative_scatter": float(
                np.sqrt(np.sum(f.residuals**2) / max(f.residuals.size - len(f.names), 1))
            ),
            "singular_values_theta": f.singular_values.tolist(),
            "scaled_singular_values": self.scaled_singular_values.tolist(),
            "identifiability": self.combinations(),
            "cells": cells,
            "start": dict(self.start),
            "identified": self.identified,
            "restarts": list(self.restarts),
            "spread_over_std_error": dict(self.spread),
            "fixed": {k: v for k, v in self.parameters.items() if k not in self.free},
        }
