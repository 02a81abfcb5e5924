"""Fractal test surfaces: the YK height function (wang2022 Eq 1) and the W-M profile (wu2015 Eq 3).

Conventions (the same as `FractalSurface` and the contact model):

- D is the fractal dimension of the *surface*, 2 < D < 3; the profile dimension is D - 1.
  wu2015 Eq 3 is written with the profile dimension D_p = D - 1 in (1, 2).
- G (m) is the fractal roughness; L (m) the sample length, which is also the longest wavelength:
  mode n has spatial frequency γⁿ/L, n = 0 … n_max.
- γ (default 1.5) sets the frequency density, M the number of ridges; ridge m runs along the
  direction θ_m = πm/M, so a height map's x-profile sees ridge m at frequency γⁿ|cos θ_m|/L.
- Phases φ_{m,n} are uniform on [0, 2π) from a `jax.random` key, so a surface is reproducible
  and differentiable in D and G (the phases do not depend on them).

With the (ln γ)^(1/2) normalisation the discrete sum has, to a relative error below 1e-10 for
γ = 1.5, the continuous spectrum of `roughness.psd_model`, independent of γ. wu2015 Eq 3 with
D_p = D - 1 is identical to wang2022 Eq 1 with M = 1 along x (tested).
"""

import math

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._checks import check_range, fail_if
from ._topography import Topography

RIDGE_WEIGHTS = ("wang2022", "yk1998")


def default_n_max(n_points: int, gamma: float = 1.5, *, oversample: float = 4.0) -> int:
    """Largest mode index whose wavelength spans at least `oversample` samples.

    With N samples over L the highest frequency kept is γ^n_max/L <= N/(oversample·L).
    """
    return int(math.floor(math.log(n_points / oversample) / math.log(gamma)))


def _amplitude_args(D, G, L, gamma, M, n_max, d_lo):
    D = check_range(D, "D", d_lo, d_lo + 1.0)
    G = check_range(G, "G", 0.0, unit="m")
    L = check_range(L, "L", 0.0, unit="m")
    gamma = check_range(gamma, "gamma", 1.0)
    if int(M) != M or M < 1:
        raise ValueError(f"M = {M} must be a whole number of ridges >= 1")
    if int(n_max) != n_max or n_max < 0:
        raise ValueError(f"n_max = {n_max} must be a whole number >= 0")
    return D, G, L, gamma


def yk_heights(
    key, D, G, x, y=None, *, L, M: int = 1, gamma=1.5, n_max: int = 20, ridge_weights="wang2022"
) -> Float[Array, "..."]:
    """Heights (m) of the Yan–Komvopoulos fractal surface at points (x, y) (wang2022 Eq 1).

        Z = L (G/L)^(D-2) (ln γ / M)^(1/2) Σ_m w_m Σ_n γ^((D-3)n)
            [cos φ_mn - cos(2π γⁿ (x cos θ_m + y sin θ_m)/L + φ_mn)],  θ_m = πm/M.

    wang2022 prints Eq 1 for a profile (y = 0) and with ridge weights w_m = (m/M)^(3-D)
    (`ridge_weights="wang2022"`); Yan & Komvopoulos' original function has w_m = 1
    (`"yk1998"`). The two agree for M = 1.

    Args:
        key: jax.random key for the phases φ_{m,n}.
        D: surface fractal dimension, (2, 3). G: roughness, m. L: sample length, m.
        x, y: coordinates, m (broadcast together; y = None means a profile along x).
        M: number of ridges (static). gamma: frequency density, > 1. n_max: highest mode (static).
    Returns:
        Heights in m, shaped like the broadcast of x and y.
    """
    D, G, L, gamma = _amplitude_args(D, G, L, gamma, M, n_max, 2.0)
    if ridge_weights not in RIDGE_WEIGHTS:
        raise ValueError(f"ridge_weights = {ridge_weights!r}; choose one of {RIDGE_WEIGHTS}")
    x = jnp.asarray(x, dtype=jnp.float64)
    y = jnp.zeros_like(x) if y is None else jnp.asarray(y, dtype=jnp.float64)
    x, y = jnp.broadcast_arrays(x, y)
    m = jnp.arange(1, M + 1, dtype=jnp.float64)
    n = jnp.arange(n_max + 1, dtype=jnp.float64)
    theta = jnp.pi * m / M
    w = (m / M) ** (3.0 - D) if ridge_weights == "wang2022" else jnp.ones_like(m)
    phi = jax.random.uniform(key, (M, n_max + 1), maxval=2.0 * jnp.pi, dtype=jnp.float64)
    amp = w[:, None] * gamma ** ((D - 3.0) * n)[None, :]  # (M, n)
    k = 2.0 * jnp.pi * gamma**n / L  # rad/m
    lead = (1,) * x.ndim  # explicit ranks (tests run with strict rank promotion)
    proj = jnp.multiply.outer(x, jnp.cos(theta)) + jnp.multiply.outer(y, jnp.sin(theta))
    arg = jnp.multiply.outer(proj, k) + phi.reshape(lead + phi.shape)  # (..., M, n)
    terms = amp.reshape(lead + amp.shape) * (jnp.cos(phi).reshape(lead + phi.shape) - jnp.cos(arg))
    pref = L * (G / L) ** (D - 2.0) * jnp.sqrt(jnp.log(gamma) / M)
    return pref * jnp.sum(terms, axis=(-2, -1))


def wm_profile(key, D, G, x, *, L, gamma=1.5, n_max: int = 20) -> Float[Array, "..."]:
    """Heights (m) of the Weierstrass–Mandelbrot profile of wu2015 Eq 3 at positions x (m).

        z(x) = L (G/L)^(D_p-1) (ln γ)^(1/2) Σ_n γ^((D_p-2)n) [cos φ_n - cos(2π γⁿ x/L - φ_n)]

    Here D is the profile dimension D_p of wu2015, in (1, 2) (a surface of dimension D + 1).

    Args:
        key: jax.random key for the phases. D: profile dimension, (1, 2). G: roughness, m.
        x: positions, m. L: sample length, m. gamma: > 1. n_max: highest mode (static).
    Returns:
        Heights in m, shaped like x.
    """
    D, G, L, gamma = _amplitude_args(D, G, L, gamma, 1, n_max, 1.0)
    x = jnp.asarray(x, dtype=jnp.float64)
    n = jnp.arange(n_max + 1, dtype=jnp.float64)
    phi = jax.random.uniform(key, (n_max + 1,), maxval=2.0 * jnp.pi, dtype=jnp.float64)
    lead = (1,) * x.ndim
    arg = jnp.multiply.outer(x, 2.0 * jnp.pi * gamma**n / L) - phi.reshape(lead + phi.shape)
    amp = gamma ** ((D - 2.0) * n)
    terms = amp.reshape(lead + amp.shape) * (jnp.cos(phi).reshape(lead + phi.shape) - jnp.cos(arg))
    return L * (G / L) ** (D - 1.0) * jnp.sqrt(jnp.log(gamma)) * jnp.sum(terms, axis=-1)


def synthesize(
    key,
    D,
    G,
    *,
    L,
    n_points: int,
    ny: int | None = None,
    M: int = 1,
    gamma=1.5,
    n_max: int | None = None,
    ridge_weights="wang2022",
):
    """A sampled YK surface (wang2022 Eq 1) on a regular grid, as a `Topography`.

    `ny=None` gives a profile of `n_points` samples along x over [0, L); otherwise an
    (ny, n_points) height map with the same spacing in y. `n_max` defaults to
    `default_n_max(n_points, gamma)`. The heights are differentiable in D and G; use
    `yk_heights` directly inside jit/grad.
    """
    if n_points < 8:
        raise ValueError(f"n_points = {n_points} is too few; use at least 8")
    n_max = default_n_max(n_points, float(gamma)) if n_max is None else n_max
    dx = float(L) / n_points
    x = jnp.arange(n_points) * dx
    y = None if ny is None else (jnp.arange(ny) * dx)[:, None]
    z = yk_heights(key, D, G, x, y, L=L, M=M, gamma=gamma, n_max=n_max, ridge_weights=ridge_weights)
    z = fail_if(z, ~jnp.all(jnp.isfinite(z)), "synthesised heights are not finite")
    return Topography(
        z, dx=dx, dy=None if ny is None else dx, source="synthetic YK (wang2022 Eq 1)"
    )


def direction_factor(D, M: int = 1, *, ridge_weights="wang2022"):
    """K_x = (1/M) Σ_m w_m² |cos θ_m|^(6-2D): the x-profile spectrum of an M-ridge YK surface
    relative to that of one ridge along x (so K_x = 1 for M = 1). See `roughness.psd_model`."""
    m = jnp.arange(1, M + 1, dtype=jnp.float64)
    c = jnp.abs(jnp.cos(jnp.pi * m / M))
    w2 = (m / M) ** (6.0 - 2.0 * D) if ridge_weights == "wang2022" else jnp.ones_like(m)
    # double-where: |cos θ| = 0 (θ = π/2) with a fractional power
    safe = jnp.where(c > 1e-12, c, 1.0)
    return jnp.sum(w2 * jnp.where(c > 1e-12, safe ** (6.0 - 2.0 * D), 0.0)) / M
