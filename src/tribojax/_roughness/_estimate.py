"""Estimating D and G of a measured surface, in the conventions of wang2022 Eq 1 / wu2015 Eq 3.

For the YK/W-M function with the (ln γ)^(1/2) normalisation, the discrete sum over modes n has
the continuous one-sided power spectral density of an x-profile (derived in the notebook
01b and checked in tests/test_roughness.py against synthetic surfaces)

    P(f) = K_x G^(2D-4) / (2 f^(7-2D))                   (m³; f in 1/m, ∫ P df = variance)

and, with S(τ) = 2 ∫ P(f) (1 - cos 2πfτ) df, the structure function

    S(τ) = <(z(x+τ) - z(x))²> = C(D) K_x G^(2D-4) τ^(6-2D),
    C(D) = (2π)^α π / (2 Γ(1+α) sin(πα/2)),  α = 6 - 2D,

where D is the surface dimension (2, 3) and K_x = 1 for one ridge along x (M = 1; see
`synthesis.direction_factor` for M > 1). A third method uses the mean square of the heights left
after removing a straight line from windows of length ℓ, which is K G^(2D-4) c(α, n) Δx^α with an
exact discrete constant c (the variance/RMS-vs-scale method; we read wang2022's "3D-RMS method"
[44] as this, but its reference list is not in our copy, so that reading is unconfirmed).

Each method fits a straight line in log-log over a scaling band chosen automatically
(`_choose_band`) and reports the band and an uncertainty: the regression standard error combined
with the spread of D over the accepted windows. Estimation works on concrete NumPy data (the band
choice is discrete); the model spectra `psd_model` and `structure_function_model` are JAX code.
"""

from __future__ import annotations

import dataclasses
import math

import jax.numpy as jnp
import numpy as np
from jax.scipy.special import gammaln

from .._checks import check_range
from .._limits import ROUGHNESS_METHODS
from ._synthesis import direction_factor
from ._topography import Topography, validate

METHODS = ROUGHNESS_METHODS


def sf_constant(D):
    """C(D) of S(τ) = C K G^(2D-4) τ^(6-2D): ∫₀^∞ u^(-1-α)(1 - cos 2πu) du, α = 6 - 2D."""
    a = 6.0 - 2.0 * D
    return (
        (2.0 * jnp.pi) ** a * jnp.pi / (2.0 * jnp.exp(gammaln(1.0 + a)) * jnp.sin(0.5 * jnp.pi * a))
    )


def psd_model(f, D, G, K=1.0):
    """One-sided PSD (m³) of an x-profile of the YK/W-M surface at frequency f (1/m).

    P = K G^(2D-4) / (2 f^(7-2D)); D in (2, 3), G in m, K the direction factor (1 for M = 1).
    Continuous limit of wang2022 Eq 1 / wu2015 Eq 3 (with D_p = D - 1).
    """
    D = check_range(D, "D", 2.0, 3.0)
    G = check_range(G, "G", 0.0, unit="m")
    f = check_range(f, "f", 0.0, unit="1/m")
    return K * G ** (2.0 * D - 4.0) / (2.0 * f ** (7.0 - 2.0 * D))


def structure_function_model(tau, D, G, K=1.0):
    """Structure function S(τ) = <(z(x+τ) - z(x))²> (m²) of the YK/W-M x-profile, τ in m."""
    D = check_range(D, "D", 2.0, 3.0)
    G = check_range(G, "G", 0.0, unit="m")
    tau = check_range(tau, "tau", 0.0, unit="m")
    return sf_constant(D) * K * G ** (2.0 * D - 4.0) * tau ** (6.0 - 2.0 * D)


@dataclasses.dataclass(frozen=True)
class RoughnessEstimate:
    """D and G of a surface by one method, with the band used and the uncertainty.

    Attributes:
        D, G: surface fractal dimension and roughness (m), wang2022 Eq 1 conventions (M = 1
            unless `M` says otherwise). D_std, log10G_std: one standard uncertainty.
        method: "structure", "psd" or "rms". band: (lo, hi) of the fit in metres (lags or
            wavelengths 1/f). slope, r2: the log-log fit. n_points: points in the band.
        source: the topography's source.
        rms_residual: rms residual of the log10 fit over the band (the band's quality).
        warning: non-empty when the band fails the scaling test and was used anyway (a band
            given by the user, or `best_band=True`): the estimate is then only indicative.
    """

    D: float
    G: float
    D_std: float
    log10G_std: float
    method: str
    band: tuple[float, float]
    slope: float
    r2: float
    n_points: int
    M: int = 1
    source: str = ""
    rms_residual: float = math.nan
    warning: str = ""

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def _rows(topo: Topography, axis: str):
    z = np.asarray(topo.heights, dtype=np.float64)
    if z.ndim == 1:
        return z[None, :], topo.dx
    if axis == "x":
        return z, topo.dx
    if axis == "y":
        return z.T, topo.dy
    raise ValueError(f"axis = {axis!r}; use 'x' or 'y'")


def _detrend(z):
    n = z.shape[-1]
    t = np.arange(n) - 0.5 * (n - 1)
    zc = z - z.mean(axis=-1, keepdims=True)
    slope = (zc @ t) / (t @ t)
    return zc - slope[:, None] * t


def _log_points(lo, hi, per_decade=12):
    k = np.unique(np.round(np.logspace(np.log10(lo), np.log10(hi), 64)).astype(int))
    step = max(1, int(len(k) / (per_decade * max(np.log10(hi / lo), 1e-9)) + 0.5))
    return k[::step] if len(k) > 4 * per_decade else k


def structure_points(z, dx):
    """(τ, S₂(τ)) at log-spaced lags 1 … n/8 samples, averaged over rows.

    S₂(τ) = <(z(x+τ) - 2z(x) + z(x-τ))²>, the second-order structure function: a linear trend
    cancels exactly and modes far below the band add only O(τ⁴), so D near 2 is not biased by
    the longest wavelengths as the first-order S(τ) is (they add O(τ²) there).
    """
    n = z.shape[-1]
    lags = _log_points(1, max(2, n // 8))
    s = np.array([np.mean((z[:, 2 * k :] - 2.0 * z[:, k:-k] + z[:, : -2 * k]) ** 2) for k in lags])
    return lags * dx, s


def psd_points(z, dx, ratio=1.5):
    """(wavelength 1/f, band-averaged one-sided PSD) from Hann-windowed periodograms.

    Bands are contiguous with edges in the ratio `ratio`; the PSD is averaged over all FFT bins
    in each band (so line spectra are integrated, not sampled) and over rows. The default 1.5 is
    the γ of wang2022/wu2015: each line of a YK/W-M surface then falls in exactly one band
    (narrower bands leave some empty); for a measured, continuous spectrum it only sets the
    resolution (5.7 bands a decade).
    """
    n = z.shape[-1]
    w = np.hanning(n)
    spec = np.abs(np.fft.rfft(_detrend(z) * w, axis=-1)) ** 2
    p = 2.0 * dx * spec.mean(axis=0) / np.sum(w**2)
    f = np.fft.rfftfreq(n, dx)
    lo, hi = 4.0 / (n * dx), 1.0 / (4.0 * dx)  # Hann leakage below; sampling above
    edges = lo * ratio ** np.arange(int(np.log(hi / lo) / np.log(ratio)) + 1)
    bands = [(a, b, (f >= a) & (f < b)) for a, b in zip(edges[:-1], edges[1:])]
    fc = np.asarray([math.sqrt(a * b) for a, b, sel in bands if sel.any()])
    pc = np.asarray([p[sel].mean() for _, _, sel in bands if sel.any()])
    return 1.0 / fc[::-1], pc[::-1]


def _rms_constant(alpha, n):
    """Exact mean square residual of a line fit over n samples when S(k) = k^α (k in samples)."""
    t = np.arange(n) - 0.5 * (n - 1)
    # projection onto {1, t}: P_ij = 1/n + t_i t_j / Σt²; diagonal sums d_k = Σ_{i-j=k} P_ij
    k = np.arange(1, n)
    st = np.sum(t * t)
    d = (n - k) / n + np.array([np.dot(t[kk:], t[:-kk]) for kk in k]) / st
    return np.sum(d * k**alpha) / n


def rms_points(z, dx):
    """(ℓ, mean square of line-detrended heights in windows of ℓ samples), averaged over rows."""
    n = z.shape[-1]
    sizes = _log_points(8, max(9, n // 4))
    out = [np.mean(_detrend(z[:, : n // m * m].reshape(-1, m)) ** 2) for m in sizes]
    return sizes * dx, np.asarray(out)


def _fit_line(x, y):
    A = np.vstack([np.ones_like(x), x]).T
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    r = y - A @ coef
    dof = max(len(x) - 2, 1)
    s2 = float(r @ r) / dof
    cov = s2 * np.linalg.inv(A.T @ A)
    ss = float(np.sum((y - y.mean()) ** 2))
    return coef, cov, float(np.sqrt(np.mean(r**2))), 1.0 - float(r @ r) / ss if ss > 0 else 0.0


def _choose_band(lx, ly, min_decades, band, slope_range, allowance=2e-4):
    """Index windows [i, j) over log10 x; return the accepted windows, best first, by the rule of
    docs/surfaces.md, "How the scaling band is chosen" (`slope_range`: 2 < D < 3)."""
    n = len(lx)
    if band is not None:
        sel = np.flatnonzero((lx >= np.log10(band[0]) - 1e-9) & (lx <= np.log10(band[1]) + 1e-9))
        if len(sel) < 4:
            raise ValueError(f"band = {band} m holds {len(sel)} points; at least 4 are needed")
        return [(sel[0], sel[-1] + 1)]
    if lx[-1] - lx[0] < min_decades - 1e-9:
        raise ValueError(
            f"the usable range spans {lx[-1] - lx[0]:.2f} decades, less than min_decades = "
            f"{min_decades}; the profile is too short (or too coarsely sampled) to find a band"
        )
    wins = [
        (i, j)
        for i in range(n)
        for j in range(i + 4, n + 1)
        if lx[j - 1] - lx[i] >= min_decades - 1e-9
    ]
    fits = [_fit_line(lx[i:j], ly[i:j]) for i, j in wins]
    rms = np.array([f[2] for f in fits])
    slope = np.array([f[0][1] for f in fits])
    fractal = (slope > slope_range[0]) & (slope < slope_range[1])
    if not fractal.any():
        return [wins[int(np.argmin(rms))]]  # reported as "no scaling" by the caller
    ok = fractal & (rms <= 1.5 * rms[fractal].min() + allowance)
    width = np.array([lx[j - 1] - lx[i] for i, j in wins])
    order = np.lexsort((rms, -width))  # widest first, then most linear
    return [wins[k] for k in order if ok[k]]


def estimate_fractal(
    topo: Topography,
    method: str = "psd",
    *,
    band=None,
    min_decades: float = 1.0,
    M: int = 1,
    ridge_weights: str = "wang2022",
    axis: str = "x",
    max_rms: float = 0.15,
    best_band: bool = False,
) -> RoughnessEstimate:
    """D and G of `topo` (wang2022 Eq 1 conventions) by one method, band chosen automatically.

    Args:
        topo: a `Topography` (profile or map; maps are analysed along `axis`, rows averaged).
        method: "structure" (structure function), "psd" (power spectrum) or "rms" (variance of
            line-detrended windows vs window length).
        band: (lo, hi) in m (lags, wavelengths or window lengths) to force the fit band.
        min_decades: the narrowest band the automatic choice may take.
        M, ridge_weights: the YK ridge count the G is referred to (through the direction factor).
        max_rms: largest acceptable rms residual of the log10 fit; above it there is no scaling.
            (0.15: a single measured profile's binned periodogram scatters by ~0.1 in log10.)
        best_band: when no band passes the `max_rms` test, return the best band with 2 < D < 3
            anyway, with `warning` set (a given `band` is always used, with a warning if poor).
    Raises:
        ValueError for NaNs, flat or too-short data, when the fitted D is outside (2, 3), or
        (unless `best_band` or `band`) when no band shows power-law scaling within `max_rms`.
    """
    if method not in METHODS:
        raise ValueError(f"method = {method!r}; choose one of {METHODS}")
    validate(topo)
    z, dx = _rows(topo, axis)
    z = _detrend(z)
    points = {"structure": structure_points, "psd": psd_points, "rms": rms_points}[method]
    x, y = points(z, dx)
    keep = y > 0
    x, y = x[keep], y[keep]
    if len(x) < 4:
        raise ValueError(f"{topo.source}: too few usable points ({len(x)}) for a fit")
    lx, ly = np.log10(x), np.log10(y)
    # slope → α = 6 - 2D: structure and rms: slope = α; psd (vs wavelength): slope = 1 + α
    shift = 1.0 if method == "psd" else 0.0
    # D within (2.02, 2.98): a slope indistinguishable from white noise (D = 3) is no scaling
    allowance = 0.01 if method == "psd" else 2e-4
    wins = _choose_band(lx, ly, min_decades, band, (shift + 0.04, 1.96 + shift), allowance)
    i, j = wins[0]
    coef, cov, rms, r2 = _fit_line(lx[i:j], ly[i:j])
    slope = float(coef[1])
    alpha = slope - shift
    D = 3.0 - 0.5 * alpha
    lenient = best_band or band is not None
    if (rms > max_rms and not lenient) or not (2.02 < D < 2.98):
        which = "the given band" if band is not None else "the best band"
        raise ValueError(
            f"{topo.source}: no fractal scaling band found by {method!r}: {which} "
            f"{x[i]:.3g}-{x[j - 1]:.3g} m has slope {slope:.3f} (D = {D:.3f}, the model needs "
            f"2 < D < 3) and rms log10 residual {rms:.3f} (limit {max_rms}); try another method, "
            "band or min_decades"
        )
    warning = ""
    if rms > max_rms:
        warning = (
            f"the band {x[i]:.3g}-{x[j - 1]:.3g} m is not a clean power law by {method!r} (rms "
            f"log10 residual {rms:.3f} > {max_rms}, r2 = {r2:.3f}): D and G are indicative only"
        )
    # G from the fitted line at the band's centre (log10 x_c), not by extrapolation to 1 m
    xc = 0.5 * (lx[i] + lx[j - 1])
    yc = float(coef[0] + coef[1] * xc)
    K = float(direction_factor(D, M, ridge_weights=ridge_weights))
    if method == "structure":
        log_const = math.log10((4.0 - 2.0**alpha) * float(sf_constant(D)) * K)
        log_scale = alpha * xc
    elif method == "psd":
        log_const = math.log10(0.5 * K)
        log_scale = (7.0 - 2.0 * D) * xc  # P = K G^(2D-4)/2 · λ^(7-2D)
    else:
        m_c = 10**xc / dx
        c_rms = _rms_constant(alpha, max(int(round(m_c)), 3)) * float(sf_constant(D))
        log_const = math.log10(c_rms * K)
        log_scale = alpha * math.log10(dx)
    log10G = (yc - log_const - log_scale) / (2.0 * D - 4.0)
    Ds = [3.0 - 0.5 * (_fit_line(lx[a:b], ly[a:b])[0][1] - shift) for a, b in wins[:20]]
    D_std = math.hypot(0.5 * math.sqrt(cov[1, 1]), float(np.std(Ds)))
    # dlog10G/dD at fixed fitted value yc: -(log10 G - xc)·2/(2D-4) (+ the constant's drift)
    dG = abs(2.0 * (log10G - xc) / (2.0 * D - 4.0)) * D_std
    sy = math.sqrt(max(cov[0, 0] + 2 * xc * cov[0, 1] + xc * xc * cov[1, 1], 0.0))
    log10G_std = math.hypot(dG, sy / (2.0 * D - 4.0))
    return RoughnessEstimate(
        D=D,
        G=10**log10G,
        D_std=D_std,
        log10G_std=log10G_std,
        method=method,
        band=(float(x[i]), float(x[j - 1])),
        slope=slope,
        r2=r2,
        n_points=int(j - i),
        M=M,
        source=topo.source,
        rms_residual=rms,
        warning=warning,
    )
