"""Where model and data disagree: noise level, AR(1) correlation, window tests, regions.

Noise (when the sidecar gives none) comes from first differences of the residual, which a smooth
misfit hardly touches: for AR(1) noise e with lag-1 correlation ρ, Δe has lag-1 correlation
−(1−ρ)/2 and variance 2σ²(1−ρ), so

    ρ̂ = 1 + 2·acf₁(Δr)   (clipped to [0, 0.95]),   σ̂ = 1.4826·MAD(Δr)/√(2(1−ρ̂)).

Windows: the residual is cut into windows of w samples (never across a segment change). Under
the noise model Q = Σ r²/σ² over a window has mean w and, for AR(1) noise, variance
2w(1+ρ²)/(1−ρ²); Q/c is referred to χ²_ν with c = (1+ρ²)/(1−ρ²), ν = w/c (Satterthwaite).
p-values are Bonferroni-corrected over the windows; adjacent flagged windows of one segment merge
into a region, whose statistic and p-value are recomputed over the merged samples.
"""

from __future__ import annotations

from math import erfc, lgamma

import numpy as np

RHO_MAX = 0.95
ALPHA = 0.01  # family-wise level of the noise and score tests
"""Family-wise level of the noise-consistency test of a fit and of the Rao score tests that rank
candidate effects (Bonferroni over windows, grid points and candidates)."""


def ar1_inflation(rho) -> float:
    """Variance inflation (1+ρ)/(1−ρ) of a sum of AR(1) terms (effective n = n/c)."""
    rho = float(np.clip(rho, 0.0, RHO_MAX))
    return (1.0 + rho) / (1.0 - rho)


def ar1_square_inflation(rho):
    """Variance inflation (1+ρ²)/(1−ρ²) of a sum of squared AR(1) terms (Satterthwaite: the sum
    is c times a χ² with n/c degrees of freedom); ρ as given (callers clip it)."""
    return (1.0 + rho**2) / (1.0 - rho**2)


def chi2_sf(x, dof) -> float:
    """Survival function P(χ²_dof > x) of the chi-square distribution, the regularised upper
    incomplete gamma function Q(dof/2, x/2) (`gammaincc`); dof > 0 need not be an integer."""
    return float(gammaincc(np.asarray([dof / 2.0]), np.asarray([max(float(x), 0.0) / 2.0]))[0])


def chi2_sf_many(x, dof) -> np.ndarray:
    """`chi2_sf` of many (x, dof) pairs (arrays of equal length) in one vectorised evaluation."""
    x, dof = np.asarray(x, dtype=float).ravel(), np.asarray(dof, dtype=float).ravel()
    return gammaincc(dof / 2.0, np.maximum(x, 0.0) / 2.0)


_EPS, _TINY, _MAX_TERMS = 4e-16, 1e-300, 100_000  # relative tolerance: 2 ulp


def gammaincc(a, z) -> np.ndarray:
    """Regularised upper incomplete gamma function Q(a, z) = Γ(a, z)/Γ(a), a > 0, z ≥ 0 (NumPy
    arrays of one shape), in NumPy: no compiled program (docs/performance.md). Below z = a + 1 the
    power series of P = 1 − Q (Abramowitz & Stegun 6.5.29), above it the continued fraction of Q
    (A&S 6.5.31, modified Lentz), each until a term changes the sum by less than 4e-16 (at most
    `_MAX_TERMS`; about sqrt(a) terms where z ≈ a); the prefactor z^a e^(−z)/Γ(a) in
    logarithms, so a Q below 1e-308 is 0 (`chi2_logsf` handles that range). Matches SciPy to
    1e-10 relative up to a = 3·10⁴ (tests)."""
    a, z = np.asarray(a, dtype=float), np.asarray(z, dtype=float)
    out = np.ones(a.shape)
    pos = z > 0
    log_pre = np.zeros(a.shape)
    log_pre[pos] = a[pos] * np.log(z[pos]) - z[pos] - np.vectorize(lgamma, otypes=[float])(a[pos])
    series = pos & (z < a + 1.0)
    idx = np.flatnonzero(series)
    if idx.size:
        aa, zz = a[idx], z[idx]
        term = 1.0 / aa
        total, ap = term.copy(), aa.copy()
        live = np.arange(idx.size)
        for _ in range(_MAX_TERMS):
            ap[live] += 1.0
            term[live] *= zz[live] / ap[live]
            total[live] += term[live]
            live = live[np.abs(term[live]) >= np.abs(total[live]) * _EPS]
            if not live.size:
                break
        out[idx] = 1.0 - total * np.exp(log_pre[idx])
    idx = np.flatnonzero(pos & ~series)
    if idx.size:
        aa, zz = a[idx], z[idx]
        b = zz + 1.0 - aa
        c = np.full(idx.size, 1.0 / _TINY)
        d = 1.0 / b
        h = d.copy()
        live = np.arange(idx.size)
        for i in range(1, _MAX_TERMS):
            an = -i * (i - aa[live])
            b[live] += 2.0
            dl = an * d[live] + b[live]
            dl = np.where(np.abs(dl) < _TINY, _TINY, dl)
            cl = b[live] + an / c[live]
            cl = np.where(np.abs(cl) < _TINY, _TINY, cl)
            d[live], c[live] = 1.0 / dl, cl
            step = cl / dl
            h[live] *= step
            live = live[np.abs(step - 1.0) >= _EPS]
            if not live.size:
                break
        out[idx] = h * np.exp(log_pre[idx])
    return np.clip(out, 0.0, 1.0)


def chi2_logsf(x, dof) -> float:
    """log P(χ²_dof > x): `chi2_sf` in log form, for comparing p-values that underflow to 0
    (x above ~1,400 for dof 1). Where Q(a, z) (a = dof/2, z = x/2) is below 1e-280 it is the
    asymptotic series log Q ≈ (a − 1)·log z − z − log Γ(a) + log Σ_j (a−1)⋯(a−j)/z^j
    (Abramowitz & Stegun 6.5.32), six terms: relative error below 1e-12 there for dof ≤ 40."""
    q = chi2_sf(x, dof)
    if q > 1e-280:
        return float(np.log(q))
    a, z = dof / 2.0, max(float(x), 0.0) / 2.0
    term, total = 1.0, 1.0
    for j in range(1, 7):
        term *= (a - j) / z
        total += term
    return float((a - 1.0) * np.log(z) - z - lgamma(a) + np.log(total))


def lag1(r) -> float:
    """Lag-1 autocorrelation of `r` (mean removed); 0 for fewer than 3 samples."""
    r = np.asarray(r, dtype=float) - np.mean(r)
    den = float(r @ r)
    if r.size < 3 or den == 0.0:
        return 0.0
    return float(r[1:] @ r[:-1]) / den


def residual_rho(r) -> float:
    """AR(1) ρ of a residual taken as noise, clipped to [0, RHO_MAX]."""
    return float(np.clip(lag1(r), 0.0, RHO_MAX))


def noise_estimate(r, segment=None) -> tuple[float, float]:
    """(σ̂, ρ̂) of the noise in residual `r` from its first differences (module docstring).

    Differences are taken within segments only.
    """
    r = np.asarray(r, dtype=float)
    seg = np.zeros(r.size, int) if segment is None else np.asarray(segment)
    d = np.diff(r)[np.diff(seg) == 0]
    if d.size < 4:
        raise ValueError(f"noise estimate needs >= 5 samples per segment, got {r.size}")
    rho = float(np.clip(1.0 + 2.0 * lag1(d), 0.0, RHO_MAX))
    mad = float(np.median(np.abs(d - np.median(d))))
    sigma = 1.4826 * mad / np.sqrt(2.0 * (1.0 - rho))
    if sigma == 0.0:
        sigma = float(np.std(d)) / np.sqrt(2.0 * (1.0 - rho))
    return sigma, rho


def _windows(segment, w):
    """(start, stop) sample ranges of ≈w samples inside each run of equal segment labels."""
    seg = np.asarray(segment)
    cuts = np.flatnonzero(np.diff(seg) != 0) + 1
    bounds = np.concatenate([[0], cuts, [seg.size]])
    out = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        m = max(1, int(round((b - a) / w)))
        edges = np.linspace(a, b, m + 1).round().astype(int)
        out += [(int(s), int(e)) for s, e in zip(edges[:-1], edges[1:]) if e > s]
    return out


def _windows_p(r, spans, sigma, rho):
    """(mean r²/σ², p-value) arrays of the sample ranges `spans` of `r` (module docstring)."""
    c = ar1_square_inflation(rho)
    q = np.array([np.sum((r[a:b] / sigma) ** 2) for a, b in spans])
    n = np.array([b - a for a, b in spans], dtype=float)
    return q / n, chi2_sf_many(q / c, n / c)


def find_regions(r, x, segment, sigma, rho, *, n_windows=32, alpha=0.01, segment_names=None):
    """Flag the stretches where residual `r` exceeds the noise (σ, AR(1) ρ).

    Returns a list of dicts {"segment", "start", "end" (abscissa x), "i0", "i1" (sample range,
    end exclusive), "n", "statistic" (mean of r²/σ², 1 for noise), "p_value" (Bonferroni over
    windows)} in sample order. Windows have ≈ n/n_windows samples (at least 8).
    """
    r = np.asarray(r, dtype=float)
    w = max(8, r.size // n_windows)
    wins = _windows(segment, w)
    m = len(wins)
    flags = list(_windows_p(r, wins, sigma, rho)[1] * m < alpha)
    seg = np.asarray(segment)
    spans = []
    i = 0
    while i < m:
        if not flags[i]:
            i += 1
            continue
        j = i
        while j + 1 < m and flags[j + 1] and seg[wins[j + 1][0]] == seg[wins[i][0]]:
            j += 1
        spans.append((wins[i][0], wins[j][1]))
        i = j + 1
    if not spans:
        return []
    stats, ps = _windows_p(r, spans, sigma, rho)  # every region in one call
    regions = []
    for (a, b), stat, p in zip(spans, stats, ps):
        label = int(seg[a])
        regions.append(
            {
                "segment": (segment_names or {}).get(label, label),
                "start": float(x[a]),
                "end": float(x[b - 1]),
                "i0": int(a),
                "i1": int(b),
                "n": int(b - a),
                "statistic": float(stat),
                "p_value": min(1.0, float(p) * m),
            }
        )
    return regions


def excess_rmse(r, sigma) -> float:
    """sqrt(max(mean(r²) − σ², 0)): the RMS misfit beyond the noise (output units)."""
    r = np.asarray(r, dtype=float)
    return float(np.sqrt(max(float(np.mean(r * r)) - float(sigma) ** 2, 0.0)))


def noise_consistent(
    r,
    sigma,
    rho=0.0,
    segment=None,
    x=None,
    n_params=0,
    *,
    alpha=ALPHA,
    n_windows=32,
    estimated=False,
):
    """(consistent, p_value, regions): the one test of "is this residual the noise?" (module
    docstring of `tribojax.discovery._verdict` for the parts): the whole-record χ² of r/σ with
    ν = n − `n_params` (AR(1) ρ: Satterthwaite), and, for a record (`x` given), no flagged
    window (`find_regions`) and no periodic line (Fisher's g), each at level α/3.
    `estimated`: σ is the first-difference estimate from r itself, not a stated noise. Used by
    every fit (`FitResult.noise_consistent`), `discover`'s verdicts and the decimation check."""
    parts = noise_test_parts(r, sigma, rho, segment, x, n_params, alpha, n_windows, estimated)
    p_global, p_line, regions = parts["p_whole"], parts["p_line"], parts["regions"]
    ok = p_global >= alpha / 3 and p_line >= alpha / 3 and not regions
    return bool(ok), min(1.0, 3 * min(p_global, p_line)), regions


def noise_test_parts(
    r, sigma, rho=0.0, segment=None, x=None, n_params=0, alpha=ALPHA, n_windows=32, estimated=False
) -> dict:
    """The parts of `noise_consistent`'s test, each uncorrected: "p_whole" (the whole-record
    test), "p_line" (Fisher's g; 1.0 without `x`) and "regions" (windows flagged at α/3)."""
    r = np.asarray(r, dtype=float)
    n = r.size
    rho = float(np.clip(rho, 0.0, 0.95))
    c = ar1_square_inflation(rho)
    q = float(np.sum((r / sigma) ** 2))
    if estimated:
        # σ̂ from first differences carries its own error: relative variance of σ̂² ≈ 8/n
        # (MAD scale: 1.36σ²/n for σ̂, ×1.5 for the lag-1 correlation −½ of differences);
        # normal approximation of mean(r²)/σ̂² − 1 with both variances
        z = (q / max(n - n_params, 1) - 1.0) / np.sqrt(2.0 * c / n + 8.0 / n)
        p_global = float(0.5 * erfc(z / np.sqrt(2.0)))
    else:
        p_global = chi2_sf(q / c, max(n - n_params, 1) / c)
    if x is None:  # a few values (a table, block sums): the χ² test alone
        return {"p_whole": p_global, "p_line": 1.0, "regions": []}
    segment = np.zeros(n, int) if segment is None else segment
    regions = find_regions(r, x, segment, sigma, rho, n_windows=n_windows, alpha=alpha / 3)
    return {"p_whole": p_global, "p_line": fisher_g(r[1:] - rho * r[:-1]), "regions": regions}


def fisher_g(w) -> float:
    """p-value of Fisher's g test for a periodic component in w (white under the null)."""
    w = np.asarray(w, dtype=float) - np.mean(w)
    power = np.abs(np.fft.rfft(w)[1 : (w.size - 1) // 2 + 1]) ** 2
    m = power.size
    if m < 2 or not np.sum(power) > 0:
        return 1.0
    g = float(np.max(power) / np.sum(power))
    return float(min(1.0, m * (1.0 - g) ** (m - 1)))
