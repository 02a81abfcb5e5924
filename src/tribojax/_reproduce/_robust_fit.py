"""Robust full-chain fit of wang2022's measured slips: Student-t noise by maximum likelihood.

Noise model. Each measured phase slip y_i of Tables 4–7 is its model value with a Student-t
error of ν degrees of freedom (ν = ∞: Gaussian) and scale s, in one of three shapes:

    relative   ln|y_i| = ln|model_i| + s·e_i      a percentage error; r_i = ln|y_i/model_i|
    absolute   y_i = model_i + s·e_i (nm)         a resolution; r_i = y_i − model_i
    mixed      y_i = model_i + s·σ_i·e_i          σ_i = √(y_i² + c²): relative above the floor
                                                  c (nm), absolute below; r_i = (y_i − model_i)/σ_i

The log-likelihood ℓ of the slips (a density in nm) is the Student-t one of
`tribojax._reproduce._student_t` (Lange, Little & Taylor 1989, Eq 1) with σ_i = |y_i| for the
relative shape (the Jacobian of the logarithm), 1 nm for the absolute one. The relative and
absolute densities are proper; the mixed one takes σ_i at the measured values, which for ν < ∞
leaves tails ∝ 1/|y| that do not normalise (its ℓ is then only indicative).

Fit. For fixed ν, ℓ is maximised over θ and s by `student_t_ml` (θ by
`fit_measured_slips(student_t=(ν, s))`: the one engine, the one compiled solve), which reaches
EM's fixed point. The reported chain is the least-squares fit weighted by the EM weights u at
the optimum (it stays put there), whose Jacobian gives the standard errors s²(JᵀUJ)⁻¹.

Outliers. A cell is flagged when its `standardized_residuals` z_i (leverage from √u·J, scale
`core_scale`, not the t scale s, which is smaller than the Gaussian core's standard deviation for
small ν) exceeds `flag_threshold`, the Bonferroni 5 % point over the n cells (3.08 for 24 cells).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy import stats

from .._fit._measures import bic
from .._results import RESULTS, result_name
from .._tables import wang2022_table
from ._chain_fit import fit_measured_slips
from ._chain_result import TABLES, ChainFit, measured_slips, paper_theory_slips, rms_relative
from ._student_t import _lin_resid, _log_resid, student_t_loglik, student_t_ml, t_scale

NOISE_MODELS = ("relative", "absolute", "mixed")
"""Noise shapes of `robust_fit_measured_slips`: relative (on ln|T|), absolute (nm) and mixed
(σ ∝ √(T² + c²) with a floor c in nm)."""
# The headline robust fit (the defaults; `tribojax reproduce`): relative errors, Student-t with
# ν = 4 (Lange et al.'s robust choice), tied best by AIC (`python -m fitting.wang2022_robust`)
HEADLINE_NOISE, HEADLINE_FLOOR_NM, HEADLINE_NU = "relative", None, 4.0
FLAG_ALPHA = 0.05  # family-wise level of the outlier flags (Bonferroni over the cells)


def noise_shape(measured, noise: str = "relative", floor_nm: float | None = None) -> np.ndarray:
    """σ_i (nm) of each cell under the noise model `noise` (module docstring)."""
    y = np.asarray(measured, dtype=float)
    if noise == "relative":
        return np.abs(y)
    if noise == "absolute":
        return np.ones_like(y)
    if noise == "mixed":
        if floor_nm is None or not (math.isfinite(floor_nm) and floor_nm > 0):
            raise ValueError(f"floor_nm = {floor_nm} is outside the allowed range (0, inf) nm")
        return np.sqrt(y**2 + float(floor_nm) ** 2)
    raise ValueError(f"noise = {noise!r} is outside the allowed values {NOISE_MODELS}")


def residual_form(measured, noise: str = "relative", floor_nm: float | None = None) -> dict:
    """`fit_measured_slips` keywords (sigma, log_residuals) of the noise shape's residuals."""
    y = np.asarray(measured, dtype=float)
    if noise == "relative":
        return {"sigma": np.ones_like(y), "log_residuals": True}
    return {"sigma": noise_shape(y, noise, floor_nm), "log_residuals": False}


def flag_threshold(n: int, alpha: float = FLAG_ALPHA) -> float:
    """|z| above which a cell is flagged: Φ⁻¹(1 − α/(2n)) (Bonferroni over n cells)."""
    return float(stats.norm.ppf(1.0 - alpha / (2.0 * n)))


def core_scale(r) -> float:
    """Robust standard deviation of the residuals' Gaussian core: 1.4826·median|r_i| (the
    normalised median absolute deviation about the fit; Hampel 1974)."""
    return float(1.482602218505602 * np.median(np.abs(np.asarray(r, dtype=float))))


def standardized_residuals(r, Jw, scale=None) -> np.ndarray:
    """z_i = r_i/(ŝ√(1 − h_ii)), h the hat matrix of the weighted Jacobian Jw = √u·∂r/∂θ and ŝ
    `scale` (default `core_scale(r)`, which outliers do not inflate)."""
    r, Jw = np.asarray(r, dtype=float), np.asarray(Jw, dtype=float)
    scale = core_scale(r) if scale is None else scale
    h = np.sum(Jw * np.linalg.pinv(Jw).T, axis=1).reshape(r.shape)  # diag(Jw (JwᵀJw)⁺ Jwᵀ)
    return r / (scale * np.sqrt(np.clip(1.0 - h, 1e-12, None)))


def _cell_list(values, mask=None, key="value") -> list[dict]:
    """[{table, vacuum_kPa, key: value}] over the (n, 4) cells (where `mask`), load by load
    (the order of `ChainFit.as_dict`'s cells)."""
    vac = wang2022_table(3)["vacuum_kPa"]
    out = []
    for i in range(values.shape[0]):
        for j, n in enumerate(TABLES):
            if mask is None or mask[i, j]:
                kpa = float(vac[i]) if values.shape[0] == len(vac) else float(i)
                out.append({"table": n, "vacuum_kPa": kpa, key: float(values[i, j])})
    return out


@dataclasses.dataclass(frozen=True)
class RobustChainFit:
    """A Student-t (robust) full-chain fit of the measured slips (module docstring).

    Attributes:
        chain: the final weighted `ChainFit` (parameters, standard errors from s²(JᵀUJ)⁻¹).
        noise, floor_nm, nu: the noise model (shape, floor c in nm for "mixed", degrees of
            freedom; inf: Gaussian).
        scale: s (a fraction for relative/mixed, nm for absolute).
        residuals: r (module docstring), (n, 4). weights: the EM weights u, (n, 4).
        standardized: z, (n, 4) (core scale `core_scale(residuals)`). threshold: the flag
            level on |z|.
        log_likelihood: ℓ at the optimum; history: ℓ at the start and after each round of
            `student_t_ml` (reproduction.json's "em_iterations" counts them).
        result: `tribojax.RESULTS` (successful when the maximisation and its fits converged).
    """

    chain: ChainFit
    noise: str
    floor_nm: float | None
    nu: float
    scale: float
    residuals: np.ndarray
    weights: np.ndarray
    standardized: np.ndarray
    threshold: float
    log_likelihood: float
    history: tuple
    result: RESULTS

    @property
    def converged(self) -> bool:
        return bool(self.result == RESULTS.successful)

    @property
    def parameters(self) -> dict:
        return self.chain.parameters

    @property
    def free(self) -> tuple:
        return self.chain.free

    @property
    def model_nm(self) -> np.ndarray:
        return self.chain.model_nm

    @property
    def target_nm(self) -> np.ndarray:
        return self.chain.target_nm

    @property
    def flagged(self) -> np.ndarray:
        """(n, 4) bool: cells whose |standardized residual| exceeds `threshold`."""
        return np.abs(self.standardized) > self.threshold

    @property
    def n_parameters(self) -> int:
        """Free chain parameters + the scale (+ the floor of the mixed model)."""
        return len(self.free) + 1 + (self.noise == "mixed")

    @property
    def aic(self) -> float:
        return 2 * self.n_parameters - 2 * self.log_likelihood

    @property
    def bic(self) -> float:
        return bic(n=self.target_nm.size, k=self.n_parameters, log_likelihood=self.log_likelihood)

    @property
    def rms_relative_residual(self) -> float:
        return rms_relative(self.model_nm, self.target_nm)

    @property
    def rms_relative_residual_unflagged(self) -> float:
        return rms_relative(self.model_nm, self.target_nm, ~self.flagged)

    def flagged_cells(self) -> list[dict]:
        """[{"table", "vacuum_kPa", "standardized_residual"}] of the flagged cells."""
        return _cell_list(self.standardized, self.flagged, "standardized_residual")

    def loss(self) -> dict:
        """The loss / noise model in words and numbers (reproduction.json's "loss")."""
        kind = "gaussian" if math.isinf(self.nu) else "student_t"
        return {
            "kind": kind,
            "nu": None if math.isinf(self.nu) else self.nu,
            "noise": self.noise,
            "floor_nm": self.floor_nm,
            "scale": self.scale,
            "fitted_by": "maximum likelihood on least_squares_fit: theta at fixed scale "
            "(Student-t residuals), then the scale, until the likelihood stops rising",
        }

    def as_dict(self) -> dict:
        """JSON-ready report."""
        c = self.chain.as_dict()
        keep = ("parameters", "free_parameters", "std_errors", "correlation", "fixed")
        out = {k: c[k] for k in keep}
        paper = paper_theory_slips() if self.target_nm.shape == (6, 4) else None
        out.update(
            loss=self.loss(),
            converged=self.converged,
            result=result_name(self.result),
            em_iterations=len(self.history),
            log_likelihood=self.log_likelihood,
            log_likelihood_history=list(self.history),
            n_parameters=self.n_parameters,
            aic=self.aic,
            bic=self.bic,
            flag_threshold=self.threshold,
            core_scale=core_scale(self.residuals),
            flagged_cells=self.flagged_cells(),
            rms_relative_residual=self.rms_relative_residual,
            rms_relative_residual_unflagged=self.rms_relative_residual_unflagged,
            cells=[
                dict(cell, model_nm=float(m), weight=float(w), standardized_residual=float(z))
                for cell, m, w, z in zip(
                    _cell_list(self.target_nm, key="measured_nm"),
                    self.model_nm.ravel(),
                    self.weights.ravel(),
                    self.standardized.ravel(),
                )
            ],
        )
        if paper is not None:
            out["paper_theory_rms_relative_residual_unflagged"] = rms_relative(
                paper, self.target_nm, ~self.flagged
            )
        return out


def robust_fit_measured_slips(
    start=None,
    *,
    free=("D", "G_m", "mu_t"),
    noise: str = HEADLINE_NOISE,
    floor_nm: float | None = HEADLINE_FLOOR_NM,
    nu: float = HEADLINE_NU,
    target=None,
    loads=None,
    initial: ChainFit | None = None,
    initial_weights=None,
    max_iterations: int = 40,
    tol: float = 1e-3,
    **fit_kw,
) -> RobustChainFit:
    """Student-t fit of the chain to the measured phase slips (module docstring).

    Args:
        start: physical start values (as `fit_measured_slips`); ignored if `initial` is given.
        free: the free chain parameters (`fit_measured_slips`).
        noise, floor_nm: the noise shape ("relative", "absolute", or "mixed" with floor c nm).
        nu: Student-t degrees of freedom, > 0 (inf: the Gaussian likelihood, one fit).
        target, loads: data and loads (default: wang2022 Tables 4–7 at Table 3's loads).
        initial: a `ChainFit` of the same data and free parameters to start from (its model
            gives the first scale; saves the first fit; any noise shape). Without it, the first
            fit from `start` is a least-squares fit weighted by `initial_weights` (default 1;
            e.g. another fit's EM weights: a start away from the outlier's pull).
        max_iterations, tol: the maximisation (`student_t_ml`) stops when ℓ rose by less than
            `tol` (nats) in one iteration.
        fit_kw: passed to `fit_measured_slips` (max_steps, rtol, atol, jac, progress).
    Returns:
        RobustChainFit; its `chain` is the EM-weighted fit at the optimum (module docstring,
        Fit; its Jacobian √u·J also gives the leverages). `result` is `RESULTS.not_converged`
        when `max_iterations` were used up, or the inner fit's result when that failed. Never
        raises for non-convergence.
    """
    if not (nu > 0):
        raise ValueError(f"nu = {nu} is outside the allowed range (0, inf]")
    y = measured_slips() if target is None else np.asarray(target, dtype=float)
    sigma = noise_shape(y, noise, floor_nm)  # σ_i of the density
    log = noise == "relative"
    kw = dict(
        free=tuple(free), target=y, loads=loads, **residual_form(y, noise, floor_nm), **fit_kw
    )
    if initial is None:
        initial = fit_measured_slips(start, weights=initial_weights, **kw)

    def theta_step(scale, previous):
        new = fit_measured_slips(previous.parameters, student_t=(nu, scale), **kw)
        return new, new.model_nm

    fit, r, u, scale, history, result = student_t_ml(
        theta_step,
        y,
        sigma,
        nu,
        (initial, initial.model_nm),
        max_iterations=max_iterations,
        tol=tol,
        log=log,
    )
    chain = fit  # (the start could not be evaluated: nothing to weight)
    if np.all(np.isfinite(u)):
        chain = fit_measured_slips(fit.parameters, weights=u, **kw)  # statistics at the optimum
        if result == RESULTS.successful and not chain.converged:
            result = chain.result
    r = (_log_resid if log else _lin_resid)(y, chain.model_nm, sigma)
    scale = t_scale(r, nu)
    J = chain.fit.jacobian
    ok = np.all(np.isfinite(r)) and np.all(np.isfinite(J))  # else a cell was not evaluated
    z = standardized_residuals(r, J) if ok else np.full_like(r, np.nan)
    return RobustChainFit(
        chain=chain,
        noise=noise,
        floor_nm=None if noise != "mixed" else float(floor_nm),
        nu=float(nu),
        scale=scale,
        residuals=r,
        weights=u,
        standardized=z,
        threshold=flag_threshold(y.size),
        log_likelihood=student_t_loglik(r, scale, sigma, nu),
        history=history,
        result=result,
    )
