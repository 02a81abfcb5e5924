"""LuGre friction elements: the full model (wang2022 Eq 25) and the paper's pre-slip form (Eq 27).

The state is the mean bristle deflection z (m); v and the force follow the sign convention of
`AbstractFrictionElement`, so in stick F ≈ σ0·u.

The sign function sgn(v) in the bristle law has a kink at v = 0 that stalls the Newton iteration
of implicit ODE solvers whenever a contact comes to rest (the hold phases of a stage profile). The
elements therefore use the smooth sign s_ε(v) = v/√(v² + ε²) with a velocity scale ε
(`velocity_scale`, default 1e-12 m/s). For |v| ≫ ε this is sgn(v) to relative accuracy ε²/(2v²);
for |v| ≲ ε the bristles act as a plain spring (no hysteresis), which only matters once the
motion has died out to picometres per second. `velocity_scale=0` gives the exact sgn.
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._checks import check_range
from .._contact._contact import ContactParameters
from ._element import AbstractFrictionElement

DEFAULT_VELOCITY_SCALE = 1e-12  # m/s; see the module docstring


def smooth_sign(v, eps):
    """sgn(v) regularised as v/√(v² + ε²) (exact `jnp.sign` when ε = 0); finite gradient at 0."""
    v = jnp.asarray(v)
    if eps == 0:
        return jnp.sign(v)
    return v / jnp.sqrt(v * v + eps * eps)


def bristle_rate(v, sigma0_z_over_g, alpha, eps):
    """v·(1 − s(v)·σ0 z/g)^α with the bracket kept ≥ 0 (double-where for non-integer α)."""
    base = 1.0 - smooth_sign(v, eps) * sigma0_z_over_g
    pos = base > 0.0
    safe = jnp.where(pos, base, 1.0)
    return v * jnp.where(pos, safe**alpha, 0.0)


_LOG_POWER_MAX = 50.0  # exp(-exp(50)) == 0.0 in float64


def stribeck_curve(v, F_c, F_s, v_s, beta):
    """The Stribeck strength g(v) = F_c + (F_s − F_c)·exp(−|v/v_s|^β), N (wang2022 Eq 25).

    v in m/s, F_c and F_s in N, v_s in m/s (> 0), β > 0. The power is double-where masked at
    v = 0, so derivatives stay finite there for any β; it is also masked where β·ln u > 50
    (exp(−e^50) is 0 in float64), so a large β or a small v_s gives g = F_c with finite
    derivatives instead of an overflow of u^β to inf and NaN gradients.
    """
    u = jnp.abs(jnp.asarray(v) / v_s)
    nz = u > 0.0
    safe_u = jnp.where(nz, u, 1.0)
    live = nz & (beta * jnp.log(safe_u) < _LOG_POWER_MAX)
    powed = jnp.where(live, safe_u, 1.0) ** jnp.where(live, beta, 1.0)
    decay = jnp.where(live, jnp.exp(-powed), 0.0)
    decay = jnp.where(nz, decay, 1.0)
    return F_c + (F_s - F_c) * decay


class LuGre(AbstractFrictionElement):
    """The LuGre law (Canudas de Wit et al.) with Stribeck curve and exponent α (wang2022 Eq 25).

        F_f  = σ0·z + σ1·dz/dt + σ2·v
        dz/dt = v·(1 − sgn(v)·σ0·z/g(v))^α
        g(v) = F_c + (F_s − F_c)·exp(−|v/v_s|^β)

    With α = 1 this is the classical LuGre model; at constant v the deflection settles at
    z = sgn(v)·g(v)/σ0 and the force at g(v)·sgn(v) + σ2·v. The bracket is kept ≥ 0, which
    matters for non-integer α (docs/reproduction.md, Eq 27 note).
    """

    sigma0: Array  # bristle stiffness, N/m, > 0
    sigma1: Array  # bristle damping, N s/m, >= 0
    sigma2: Array  # viscous coefficient, N s/m, >= 0
    F_c: Array  # Coulomb friction, N, > 0
    F_s: Array  # static (breakaway) friction, N, >= F_c
    v_s: Array  # Stribeck velocity, m/s, > 0
    alpha: Array  # bristle-law exponent, > 0
    beta: Array  # Stribeck exponent, > 0
    velocity_scale: float = eqx.field(static=True, default=DEFAULT_VELOCITY_SCALE)

    def __init__(
        self,
        sigma0,
        sigma1,
        sigma2,
        F_c,
        F_s,
        v_s,
        alpha=1.0,
        beta=2.0,
        *,
        velocity_scale: float = DEFAULT_VELOCITY_SCALE,
    ):
        self.sigma0 = check_range(sigma0, "sigma0", 0.0, unit="N/m")
        self.sigma1 = check_range(sigma1, "sigma1", 0.0, lo_open=False, unit="N s/m")
        self.sigma2 = check_range(sigma2, "sigma2", 0.0, lo_open=False, unit="N s/m")
        self.F_c = check_range(F_c, "F_c", 0.0, unit="N")
        self.F_s = check_range(F_s, "F_s", 0.0, unit="N")
        self.v_s = check_range(v_s, "v_s", 0.0, unit="m/s")
        self.alpha = check_range(alpha, "alpha", 0.0)
        self.beta = check_range(beta, "beta", 0.0)
        if velocity_scale < 0:
            raise ValueError(f"velocity_scale = {velocity_scale:g} m/s must be >= 0")
        self.velocity_scale = float(velocity_scale)

    def stribeck(self, velocity: ArrayLike) -> Array:
        """g(v) = F_c + (F_s − F_c)·exp(−|v/v_s|^β), N (wang2022 Eq 25)."""
        return stribeck_curve(velocity, self.F_c, self.F_s, self.v_s, self.beta)

    def initial_state(self) -> Array:
        return jnp.zeros_like(self.sigma0)

    def state_rate(self, state, velocity) -> Array:
        """dz/dt, m/s (wang2022 Eq 25, second line)."""
        ratio = self.sigma0 * state / self.stribeck(velocity)
        return bristle_rate(velocity, ratio, self.alpha, self.velocity_scale)

    def force(self, state, velocity) -> Array:
        """F_f = σ0 z + σ1 dz/dt + σ2 v, N (wang2022 Eq 25, first line)."""
        return (
            self.sigma0 * state
            + self.sigma1 * self.state_rate(state, velocity)
            + self.sigma2 * velocity
        )

    def constant_velocity_step(self, state, velocity, h) -> Array:
        """Exact z after a time h (s) at constant velocity v, for α = 1 (wang2022 Eq 25).

        With α = 1 the bristle law dz/dt = v − |v|σ0 z/g(v) is linear in z at fixed v, so
        z(h) = z_ss + (z − z_ss)·exp(−σ0|v|h/g(v)) with z_ss = sgn(v)·g(v)/σ0: stable for any
        step, unlike RK4 when σ0|v|h/g ≳ 2.8 (coarse samples, stiff bristles). Needs α = 1.
        """
        v = jnp.asarray(velocity)
        g = self.stribeck(v)
        z_ss = jnp.sign(v) * g / self.sigma0
        return z_ss + (state - z_ss) * jnp.exp(-self.sigma0 * jnp.abs(v) * h / g)

    def steady_force(self, velocity: ArrayLike) -> Array:
        """The constant-velocity limit g(v)·sgn(v) + σ2·v, N (α-independent)."""
        v = jnp.asarray(velocity)
        return self.stribeck(v) * jnp.sign(v) + self.sigma2 * v


class PreSlipLuGre(AbstractFrictionElement):
    """wang2022's pre-slip element (Eq 27):

        F_f = K_τ·z + C_τ·dz/dt,   dz/dt = v·(1 − sgn(v)·z/z_max)^α,   z_max = F_s/K_τ (Eq 26)

    i.e. LuGre (Eq 25) with σ0 = K_τ, σ1 = C_τ, g = F_s, σ2 = 0. Eq 27 as printed keeps σ0 in
    the bristle law; σ0 = K_τ by the paper's own substitution, which is what is implemented
    (docs/reproduction.md). The bracket is kept ≥ 0 for non-integer α; sgn is the smooth sign of
    this module (`velocity_scale`). The state is z (m). Build it from a contact-parameter record
    with `PreSlipLuGre.from_contact`. (The slip model's element with viscous, Stribeck and load
    coupling knobs is `tribojax.discovery.AugmentedPreSlip`.)
    """

    F_s: Array  # maximum static friction, N, > 0
    K_tau: Array  # tangential stiffness, N/m, > 0
    C_tau: Array  # tangential damping, N s/m, >= 0
    alpha: Array  # bristle-law exponent, > 0 (1 in the paper)
    velocity_scale: float = eqx.field(static=True, default=DEFAULT_VELOCITY_SCALE)

    def __init__(self, F_s, K_tau, C_tau, alpha=1.0, *, velocity_scale=DEFAULT_VELOCITY_SCALE):
        self.F_s = check_range(F_s, "F_s", 0.0, unit="N")
        self.K_tau = check_range(K_tau, "K_tau", 0.0, unit="N/m")
        self.C_tau = check_range(C_tau, "C_tau", 0.0, lo_open=False, unit="N s/m")
        self.alpha = check_range(alpha, "alpha", 0.0)
        if velocity_scale < 0:
            raise ValueError(f"velocity_scale = {velocity_scale:g} m/s must be >= 0")
        self.velocity_scale = float(velocity_scale)

    @classmethod
    def from_contact(cls, params: ContactParameters, alpha=1.0, **kw) -> PreSlipLuGre:
        """The element for one contact-parameter record (F_s, K_τ, C_τ of wang2022 Eqs 14–24)."""
        return cls(params.F_s, params.K_tau, params.C_tau, alpha, **kw)

    @property
    def z_max(self) -> Array:
        """Maximum tangential deformation F_s/K_τ, m (wang2022 Eq 26)."""
        return self.F_s / self.K_tau

    def initial_state(self):
        return jnp.zeros_like(self.K_tau)

    def state_rate(self, state, velocity):
        """dz/dt, m/s (wang2022 Eq 27, second line, with σ0 = K_τ)."""
        return bristle_rate(velocity, state / self.z_max, self.alpha, self.velocity_scale)

    def force(self, state, velocity) -> Array:
        """F_f = K_τ z + C_τ dz/dt, N (wang2022 Eq 27, first line)."""
        return self.K_tau * state + self.C_tau * self.state_rate(state, velocity)

    def steady_force(self, velocity: ArrayLike) -> Array:
        """The constant-velocity (macro-slip) limit F_s·sgn(v), N."""
        return self.F_s * jnp.sign(jnp.asarray(velocity))
