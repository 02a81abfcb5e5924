"""Is a residual noise? The verdict of a discovery run, where a misfit lives, what could close it.

One noise-consistency test decides both "none" (for the baseline residual) and "explained" (for
the final residual): with noise sd σ and AR(1) ρ (sidecar or first-difference estimates, see
`_regions`), the residual r of a model with p parameters is consistent with the noise when

  - the whole-record statistic Q = Σr²/σ² passes the χ² test (Q/c against χ²_ν, ν = (n − p)/c,
    c = (1+ρ²)/(1−ρ²), Satterthwaite) at level α/2, and
  - no window is flagged by `find_regions` at level α/3 (Bonferroni over windows), and
  - Fisher's g test finds no periodic component in the AR(1)-prewhitened residual
    w_t = r_t − ρ r_{t−1}: g = max periodogram ordinate / their sum over the m Fourier
    frequencies strictly between 0 and Nyquist, p ≈ m(1 − g)^(m−1) (Fisher 1929), at level α/3
    (a line such as mains pickup that a first-difference noise estimate absorbs).

The χ² test is at level α/3 too. When σ is estimated from the residual's first differences, the
whole-record test is the normal approximation of mean(r²)/σ̂² − 1 with the estimator's own
variance added (≈ 8/n relative for σ̂²), not χ² (which would flag a σ̂ two of its standard errors
low).

Excess misfit (beyond the noise): e = sqrt(max(mean(r²) − σ², 0)), output units.

Verdict (issue 14): "none" when the baseline passes (nothing is added then); "explained" when
the added effects make the final residual pass; "partly_explained" when they at least halve
e; "unexplained" otherwise.

Flexible correction: the remaining residual fitted by a linear spline (hat functions on knots at
quantiles) in one measured signal; the share of e² it removes is an upper bound on what a missing
term that is a function of that signal alone could explain.
"""

from __future__ import annotations

from math import erfc

import numpy as np

from ._regions import chi2_sf, find_regions

N_KNOTS = 12  # knots of the flexible correction


def excess_rmse(r, sigma) -> float:
    """sqrt(max(mean(r²) − σ², 0)): the RMS misfit beyond the noise (output units)."""
    r = np.asarray(r, dtype=float)
    return float(np.sqrt(max(float(np.mean(r * r)) - float(sigma) ** 2, 0.0)))


def noise_consistent(r, sigma, rho, segment, x, n_params, *, alpha=0.01, n_windows=32,
                     estimated=False):  # fmt: skip
    """(consistent, p_value, regions): the module's noise-consistency test of residual r;
    `estimated`: σ is the first-difference estimate from r itself, not the sidecar's."""
    r = np.asarray(r, dtype=float)
    n = r.size
    rho = float(np.clip(rho, 0.0, 0.95))
    c = (1.0 + rho**2) / (1.0 - rho**2)
    q = float(np.sum((r / sigma) ** 2))
    if estimated:
        # σ̂ from first differences carries its own error: relative variance of σ̂² ≈ 8/n
        # (MAD scale: 1.36σ²/n for σ̂, ×1.5 for the lag-1 correlation −½ of differences);
        # normal approximation of mean(r²)/σ̂² − 1 with both variances
        z = (q / max(n - n_params, 1) - 1.0) / np.sqrt(2.0 * c / n + 8.0 / n)
        p_global = float(0.5 * erfc(z / np.sqrt(2.0)))
    else:
        p_global = chi2_sf(q / c, max(n - n_params, 1) / c)
    regions = find_regions(r, x, segment, sigma, rho, n_windows=n_windows, alpha=alpha / 3)
    p_line = fisher_g(r[1:] - rho * r[:-1])
    ok = p_global >= alpha / 3 and p_line >= alpha / 3 and not regions
    return bool(ok), min(1.0, 3 * min(p_global, p_line)), regions


def fisher_g(w) -> float:
    """p-value of Fisher's g test for a periodic component in w (white under the null)."""
    w = np.asarray(w, dtype=float) - np.mean(w)
    power = np.abs(np.fft.rfft(w)[1 : (w.size - 1) // 2 + 1]) ** 2
    m = power.size
    if m < 2 or not np.sum(power) > 0:
        return 1.0
    g = float(np.max(power) / np.sum(power))
    return float(min(1.0, m * (1.0 - g) ** (m - 1)))


def verdict(n_effects, base_ok, final_ok, excess_before, excess_after) -> str:
    """The issue-14 verdict from the consistency tests and the excess misfits."""
    if base_ok:
        return "none"
    if n_effects == 0:
        return "unexplained"
    if final_ok:
        return "explained"
    if excess_before > 0 and excess_after <= 0.5 * excess_before:
        return "partly_explained"
    return "unexplained"


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
            best = {"signal": name, "knots": knots.tolist(), "values": coef.tolist(),
                    "excess_rmse_after_correction": e1,
                    "gap_closed": float(1.0 - e1**2 / e0**2)}  # fmt: skip
    return best
