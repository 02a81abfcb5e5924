"""LuGre friction elements: the full model (wang2022 Eq 25) and the paper's pre-slip form (Eq 27).

The state is the mean bristle deflection z (m) (with a load-coupled pre-slip element, also the
time; see `PreSlipLuGre`). They implement
`AbstractFrictionElement` with the sign convention of `tribojax._friction`: v is the velocity of
the driving body relative to the driven one, and the force is the one transmitted to the driven
body, so in stick F ≈ σ0·u.

The sign function sgn(v) in the bristle law has a kink at v = 0 that stalls the Newton iteration
of implicit ODE solvers whenever a contact comes to rest (the hold phases of a stage profile). The
elements therefore use the smooth sign s_ε(v) = v/√(v² + ε²) with a velocity scale ε
(`velocity_scale`, default 1e-12 m/s). For |v| ≫ ε this is sgn(v) to relative accuracy ε²/(2v²);
for |v| ≲ ε the bristles act as a plain spring (no hysteresis), which only matters once the
motion has died out to picometres per second. `velocity_scale=0` gives the exact sgn.
"""

from __future__ import annotations

from typing import Any

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._checks import as_f64, check_range
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
    """The LuGre friction law with Stribeck curve (wang2022 Eq 25).

        F_f  = σ0·z + σ1·dz/dt + σ2·v
        dz/dt = v·(1 − sgn(v)·σ0·z/g(v))^α
        g(v) = F_c + (F_s − F_c)·exp(−|v/v_s|^β)

    With α = 1 this is the classical LuGre model; at constant v the deflection settles at
    z = sgn(v)·g(v)/σ0 and the force at g(v)·sgn(v) + σ2·v. The bracket is kept ≥ 0, which
    matters for non-integer α (docs/reproduction.md, Eq 27 note).

    Reference: wang2022 Eq 25 (the LuGre model of Canudas de Wit et al. with the exponent α).
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
    """wang2022's pre-slip element (Eq 27), optionally with LuGre's Stribeck and viscous terms
    (Eq 25) and a normal load that follows the stage acceleration.

        F_f  = K·z + C_τ·dz/dt + σ2·v
        dz/dt = v·(1 − sgn(v)·K·z/g(v))^α
        K = K_τ·N/N₀,   g(v) = LuGre's Stribeck curve with F_s·N/N₀, F_c = (1 − δ)·F_s·N/N₀, β = 2
        N(t)/N₀ = 1 + κ·a(t)

    Without the knobs (σ2, δ, κ left at None, the default) this is Eq 27 exactly:
    F_f = K_τ z + C_τ dz/dt, dz/dt = v(1 − sgn(v) z/z_max)^α with z_max = F_s/K_τ (Eq 26),
    i.e. LuGre with σ0 = K_τ, σ1 = C_τ, g = F_s, σ2 = 0. Eq 27 as printed keeps σ0 in the
    bristle law; σ0 = K_τ by the paper's own substitution, which is what is implemented
    (docs/reproduction.md). The bracket is kept ≥ 0 for non-integer α. A knob given as 0 gives
    the same model (and, without a drive, the same numbers to rounding).

    Knobs (signed, so that a fit may step through 0):
        sigma2    viscous coefficient σ2, N s/m (LuGre σ2, Eq 25)
        stribeck  δ, velocity weakening F_c = (1 − δ)F_s (> 0 weakens); needs `v_s` (m/s, > 0)
        kappa     load coupling κ, s²/m: N/N₀ = 1 + κ·a(t) (a coupling κ_g per g is κ_g/g);
                  F_s and K_τ scale with N, so z_max does not; needs `drive`
    `drive`: the stage profile (anything with `acceleration(t)`, m/s²) that drives the slip
    simulation; pass the same profile to `simulate_slip`. The element reads a(t) through a second
    state, the time τ (s, dτ/dt = 1, from 0): with a drive the state is (z, τ).
    `knob_bound` (static, default None): if set to b, δ and κ·a pass through x ↦ b·tanh(x/b)
    (equal to first order, bounded by b), so that trial points of a fit cannot make the strength
    or the load negative (discovery uses b = 0.9).
    Build the plain element from a contact-parameter record with `PreSlipLuGre.from_contact`.

    Reference: wang2022 Eqs 25–27.
    """

    F_s: Array  # maximum static friction, N, > 0
    K_tau: Array  # tangential stiffness, N/m, > 0
    C_tau: Array  # tangential damping, N s/m, >= 0
    alpha: Array  # bristle-law exponent, > 0 (1 in the paper)
    sigma2: Array | None = None  # viscous coefficient, N s/m
    stribeck: Array | None = None  # δ, F_c = (1 − δ)F_s
    v_s: Array | None = None  # Stribeck velocity, m/s, > 0
    kappa: Array | None = None  # load coupling, s²/m
    drive: Any = None  # stage profile with acceleration(t), m/s²
    knob_bound: float | None = eqx.field(static=True, default=None)
    velocity_scale: float = eqx.field(static=True, default=DEFAULT_VELOCITY_SCALE)

    def __init__(
        self,
        F_s,
        K_tau,
        C_tau,
        alpha=1.0,
        *,
        sigma2=None,
        stribeck=None,
        v_s=None,
        kappa=None,
        drive=None,
        knob_bound: float | None = None,
        velocity_scale=DEFAULT_VELOCITY_SCALE,
    ):
        self.F_s = check_range(F_s, "F_s", 0.0, unit="N")
        self.K_tau = check_range(K_tau, "K_tau", 0.0, unit="N/m")
        self.C_tau = check_range(C_tau, "C_tau", 0.0, lo_open=False, unit="N s/m")
        self.alpha = check_range(alpha, "alpha", 0.0)
        if stribeck is not None and v_s is None:
            raise ValueError("stribeck = delta needs the Stribeck velocity v_s (m/s, > 0)")
        if kappa is not None and drive is None:
            raise ValueError("kappa (load coupling) needs drive, the stage profile a(t)")
        if drive is not None and not callable(getattr(drive, "acceleration", None)):
            raise ValueError(f"drive = {drive!r} must be a stage profile with acceleration(t)")
        if knob_bound is not None and not float(knob_bound) > 0:
            raise ValueError(f"knob_bound = {knob_bound!r} must be > 0 (or None)")
        self.sigma2 = None if sigma2 is None else as_f64(sigma2, "sigma2")
        self.stribeck = None if stribeck is None else as_f64(stribeck, "stribeck")
        self.v_s = None if v_s is None else check_range(v_s, "v_s", 0.0, unit="m/s")
        self.kappa = None if kappa is None else as_f64(kappa, "kappa")
        self.drive = drive
        self.knob_bound = None if knob_bound is None else float(knob_bound)
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

    def _bounded(self, x):
        b = self.knob_bound
        return x if b is None else b * jnp.tanh(x / b)

    def _split(self, state):
        """(z, N/N₀ or None): the deflection and the load factor 1 + κ·a(τ)."""
        if self.drive is None:
            return state, None
        z, tau = state
        if self.kappa is None:
            return z, None
        return z, 1.0 + self._bounded(self.kappa * self.drive.acceleration(tau))

    def strength(self, velocity: ArrayLike, load_factor=None) -> Array:
        """g(v), N: F_s, or LuGre's Stribeck curve with F_c = (1 − δ)F_s, β = 2 (wang2022
        Eq 25); times the load factor N/N₀ if given."""
        F_s = self.F_s if load_factor is None else self.F_s * load_factor
        if self.stribeck is None:
            return F_s
        F_c = (1.0 - self._bounded(self.stribeck)) * F_s
        return stribeck_curve(velocity, F_c, F_s, self.v_s, 2.0)

    def _zdot(self, z, m, v):
        if self.stribeck is None and m is None:
            ratio = z / self.z_max  # Eq 27
        else:
            K = self.K_tau if m is None else self.K_tau * m
            ratio = K * z / self.strength(v, m)
        return bristle_rate(v, ratio, self.alpha, self.velocity_scale)

    def initial_state(self):
        z = jnp.zeros_like(self.K_tau)
        return z if self.drive is None else (z, jnp.zeros_like(self.K_tau))

    def state_rate(self, state, velocity):
        """dz/dt, m/s (wang2022 Eq 27, second line, with σ0 = K_τ); with a drive (dz/dt, 1)."""
        z, m = self._split(state)
        zdot = self._zdot(z, m, velocity)
        return zdot if self.drive is None else (zdot, jnp.ones_like(zdot))

    def force(self, state, velocity) -> Array:
        """F_f = K z + C_τ dz/dt (+ σ2 v), N (wang2022 Eq 27, first line; Eq 25)."""
        z, m = self._split(state)
        K = self.K_tau if m is None else self.K_tau * m
        f = K * z + self.C_tau * self._zdot(z, m, velocity)
        return f if self.sigma2 is None else f + self.sigma2 * velocity

    def steady_force(self, velocity: ArrayLike) -> Array:
        """The constant-velocity (macro-slip) limit g(v)·sgn(v) (+ σ2·v), N, at a = 0
        (F_s·sgn(v) without the knobs)."""
        v = jnp.asarray(velocity)
        f = self.strength(v) * jnp.sign(v)
        return f if self.sigma2 is None else f + self.sigma2 * v
