"""Is a residual noise? The verdict of a discovery run, where a misfit lives, what could close it.

One noise-consistency test decides both "none" (for the baseline residual) and "explained" (for
the final residual): with noise sd σ and AR(1) ρ (sidecar or first-difference estimates of
`_fit._noise`), the residual r of a model with p parameters is consistent with the noise when

  - the whole-record statistic Q = Σr²/σ² passes the χ² test (Q/c against χ²_ν, ν = (n − p)/c,
    c = (1+ρ²)/(1−ρ²), Satterthwaite) at level α/3, and
  - no window is flagged by `find_regions` at level α/3 (Bonferroni over windows), and
  - Fisher's g test finds no periodic component in the AR(1)-prewhitened residual
    w_t = r_t − ρ r_{t−1}: g = max periodogram ordinate / their sum over the m Fourier
    frequencies strictly between 0 and Nyquist, p ≈ m(1 − g)^(m−1) (Fisher 1929), at level α/3
    (a line such as mains pickup that a first-difference noise estimate absorbs).

When σ is estimated from the residual's first differences, the whole-record test is the normal
approximation of mean(r²)/σ̂² − 1 with the estimator's own variance added (≈ 8/n relative for
σ̂²), not χ² (which would flag a σ̂ two of its standard errors low).

Excess misfit (beyond the noise): e = sqrt(max(mean(r²) − σ², 0)), output units.

Held-out excess: the same excess of the two-fold held-out residual
(`tribojax._model.heldout_residual`: each fold of `folds()` predicted by the model fitted on the
other fold alone), of the baseline (h₀) and of the final model with its effects' nuisance values
fixed (h₁).

Verdict: "none" when the baseline passes (nothing is added then); "explained"
when the added effects make the final residual pass, at least halve the held-out excess
(h₁ ≤ h₀/2) and predict the samples they did not see nearly as well as those they fitted: the
held-out gap √max(h₁² − e₁², 0) (e₁ the final in-sample excess) at most `HELDOUT_GAP` σ;
"partly_explained" when they at least halve e and lower the held-out excess; "unexplained"
otherwise. Where no held-out residual could be computed (a fold's fit failed) the in-sample
tests decide alone. (The gap bound was set on the project study: docs/discovery.md, "Why each
rule is set where it is".)

Flexible correction: the remaining residual fitted by a linear spline (hat functions on knots at
quantiles) in one measured signal; the share of e² it removes is an upper bound on what a missing
term that is a function of that signal alone could explain.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._noise import excess_rmse

N_KNOTS = 12  # knots of the flexible correction
# noise sd: the most held-out excess beyond the in-sample one for "explained" (module docstring)
HELDOUT_GAP = 0.6
# relative: held-out mean squares closer than this are a tie (the fold fits' tolerance, 1e-8 on
# the parameters, moves a held-out mean square by ~1e-8; a tie keeps the fewer parameters)
HELDOUT_TIE = 1e-6
# BIC units: candidates whose ΔBIC differ by less are a tie (each refit's cost stops within
# GAIN_TOL = 0.01 residual variances of its minimum, so a ΔBIC within ~0.02 of another is noise);
# a tie goes to the fewer added parameters, then the name (`_refits.choose`)
BIC_TIE = 0.05


@dataclasses.dataclass
class NoiseModel:
    """The noise a discovery run tests residuals against: sd `sigma` (output units), AR(1)
    `rho`, and `hat`, the smallest first-difference estimate σ̂ of a residual seen so far.
    `estimated`: σ comes from the residuals (the record states none)."""

    sigma: float
    rho: float
    hat: float
    estimated: bool

    def sharpen(self, baseline, fit, y) -> None:
        """Update from `fit`'s residual when its estimate σ̂ (`baseline.noise_model`) is below
        `hat`: then ρ̂ is taken from it, and σ too when estimated. σ̂ from a residual that still
        holds a misfit is inflated by it, and ρ̂ with it (docs/discovery.md, "Noise model");
        every refit's residual is a further estimate, the smallest the least contaminated."""
        if not (fit.converged and np.all(np.isfinite(fit.prediction))):
            return
        s_new, rho_new = baseline.noise_model(y - fit.prediction)
        if 0 < s_new < self.hat:
            self.hat, self.rho = float(s_new), float(rho_new)
            if self.estimated:
                self.sigma = float(s_new)


def verdict(
    n_effects,
    base_ok,
    final_ok,
    excess_before,
    excess_after,
    heldout=None,
    *,
    sigma=None,
    heldout_ms=None,
) -> str:
    """The verdict (module docstring) from the consistency tests, the excess misfits and
    `heldout` = (h₀, h₁), the held-out excesses (None: not available; h₁ None: the final
    model's held-out fit failed), all in output units; `sigma`: the noise sd (None: the
    held-out gap is not checked); `heldout_ms` = (m₀, m₁), the held-out mean squares: "lowered"
    compares them (beyond `HELDOUT_TIE`), and where h₀ = 0 (the held-out misfit within the
    noise's mean square, so an excess cannot halve) they stand for "halved" too."""
    if base_ok:
        return "none"
    if n_effects == 0:
        return "unexplained"
    h0, h1 = (None, None) if heldout is None else heldout
    m0, m1 = (None, None) if heldout_ms is None else heldout_ms
    if h1 is not None and m0 is not None and m1 is not None:
        lowered = m1 < m0 * (1.0 - HELDOUT_TIE)
    else:
        lowered = heldout is None or (h1 is not None and h1 < h0)
    halved = heldout is None or (h1 is not None and h1 <= 0.5 * h0 and h0 > 0)
    if heldout is not None and h0 == 0 and m0 is not None:
        halved = lowered
    close = (
        heldout is None
        or sigma is None
        or h1 is None
        or heldout_gap(h1, excess_after) <= HELDOUT_GAP * sigma
    )
    if final_ok and halved and close:
        return "explained"
    if excess_before > 0 and excess_after <= 0.5 * excess_before and lowered:
        return "partly_explained"
    return "unexplained"


def heldout_gap(heldout_excess, excess) -> float:
    """√max(h² − e², 0): the held-out excess beyond the in-sample one (output units)."""
    return float(np.sqrt(max(heldout_excess**2 - excess**2, 0.0)))


def correlations(r, signals: dict) -> list:
    """Pearson correlation of residual r with each signal, largest |correlation| first."""
    r = np.asarray(r, dtype=float) - np.mean(r)
    out = []
    for name, s in signals.items():
        s = np.asarray(s, dtype=float) - np.mean(s)
        den = float(np.sqrt((r @ r) * (s @ s)))
        out.append({"signal": name, "correlation": float(r @ s) / den if den > 0 else 0.0})
    return sorted(out, key=lambda d: -abs(d["correlation"]))


def _hat_basis(s, knots):
    """Linear-spline (hat function) basis of values s on increasing knots, shape (n, m)."""
    eye = np.eye(knots.size)
    return np.stack([np.interp(s, knots, eye[j]) for j in range(knots.size)], axis=1)


def flexible_correction(r, signals: dict, sigma, n_knots=N_KNOTS) -> dict | None:
    """The best linear-spline correction of residual r in one signal (by remaining excess).

    Returns {"signal", "knots", "values" (the correction at the knots, output units),
    "excess_rmse_after_correction", "gap_closed" (share of the excess² removed)} or None.
    """
    r = np.asarray(r, dtype=float)
    e0 = excess_rmse(r, sigma)
    if e0 == 0.0:
        return None
    best = None
    for name, s in signals.items():
        s = np.asarray(s, dtype=float)
        knots = np.unique(np.quantile(s, np.linspace(0, 1, n_knots)))
        if knots.size < 2:
            continue
        B = _hat_basis(s, knots)
        coef = np.linalg.lstsq(B, r, rcond=None)[0]
        e1 = excess_rmse(r - B @ coef, sigma)
        if best is None or e1 < best["excess_rmse_after_correction"]:
            best = {
                "signal": name,
                "knots": knots.tolist(),
                "values": coef.tolist(),
                "excess_rmse_after_correction": e1,
                "gap_closed": float(1.0 - e1**2 / e0**2),
            }
    return best
