"""The friction element the slip-run model's effects move (`SlipBaseline.element`): wang2022's
pre-slip element (Eq 27) with LuGre's viscous and Stribeck terms (Eq 25) and a normal load that
follows the stage acceleration; at its null, `PreSlipLuGre`."""

from __future__ import annotations

from typing import final

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike

from .._checks import as_f64, check_range
from .._dynamics._profiles import AbstractProfile
from .._friction._element import AbstractFrictionElement
from .._friction._lugre import DEFAULT_VELOCITY_SCALE, bristle_rate, stribeck_curve
from .._presets import STANDARD_GRAVITY_WANG2022 as G_ACC  # m/s², wang2022 Eq 28

KNOB_BOUND = 0.9  # δ and κa/g pass through x ↦ b·tanh(x/b): trial points keep g, N > 0


@final
class AugmentedPreSlip(AbstractFrictionElement):
    """Pre-slip friction with three signed knobs (wang2022 Eqs 25–27, consistent reading):

        N(t)/N₀ = 1 + b·tanh(κ·a(t)/(g·b)),   K = K_τ·N/N₀,
        g(v) = F_s·N/N₀·(1 − δ_b·(1 − exp(−(v/v_s)²))),   δ_b = b·tanh(δ/b),
        dz/dt = v·(1 − s(v)·K z/g(v))^α,   F_f = K z + C_τ dz/dt + σ2·v

    with b = `KNOB_BOUND` (equal to first order; the strength and the load stay positive at any
    trial point of a fit), g = 9.8 m/s² (wang2022 Eq 28) and s(v) the smooth sign of
    `PreSlipLuGre`. σ2 (N s/m, viscous, ≥ 0 dissipates), δ (—, > 0 velocity weakening: F_c =
    (1 − δ)F_s, β = 2), v_s (m/s, > 0) and κ (per g, load coupling) at 0 give `PreSlipLuGre`.
    `profile` is the stage drive a(t) (m/s²), also passed to `simulate_slip`; the state is
    (z, τ), the time τ (s, dτ/dt = 1) reading a(τ).
    """

    F_s: Array  # N
    K_tau: Array  # N/m
    C_tau: Array  # N s/m
    sigma2: Array  # N s/m
    stribeck: Array  # δ
    v_s: Array  # m/s
    kappa: Array  # s²/m (κ per g divided by g)
    alpha: Array  # bristle exponent
    profile: AbstractProfile
    velocity_scale: float = eqx.field(static=True)

    def __init__(
        self,
        F_s,
        K_tau,
        C_tau,
        sigma2,
        stribeck,
        v_s,
        kappa,
        profile,
        *,
        velocity_scale=DEFAULT_VELOCITY_SCALE,
        alpha=1.0,
    ):
        self.F_s = check_range(F_s, "F_s", 0.0, unit="N")
        self.K_tau = check_range(K_tau, "K_tau", 0.0, unit="N/m")
        self.C_tau = check_range(C_tau, "C_tau", 0.0, lo_open=False, unit="N s/m")
        self.alpha = check_range(alpha, "alpha", 0.0)
        self.sigma2 = as_f64(sigma2, "sigma2")
        self.stribeck = as_f64(stribeck, "stribeck")
        self.v_s = check_range(v_s, "v_s", 0.0, unit="m/s")
        self.kappa = as_f64(kappa, "kappa") / G_ACC
        if not callable(getattr(profile, "acceleration", None)):
            raise ValueError(f"profile = {profile!r} must be a stage profile with acceleration(t)")
        self.profile = profile
        if velocity_scale < 0:
            raise ValueError(f"velocity_scale = {velocity_scale:g} m/s must be >= 0")
        self.velocity_scale = float(velocity_scale)

    @staticmethod
    def _bounded(x):
        return KNOB_BOUND * jnp.tanh(x / KNOB_BOUND)

    def load_factor(self, tau):
        """N/N₀ at time τ (s)."""
        return 1.0 + self._bounded(self.kappa * self.profile.acceleration(tau))

    def strength(self, velocity: ArrayLike, load_factor=1.0) -> Array:
        """g(v), N (wang2022 Eq 25 with F_c = (1 − δ_b)F_s, β = 2) at load factor N/N₀."""
        F_s = self.F_s * load_factor
        F_c = (1.0 - self._bounded(self.stribeck)) * F_s
        return stribeck_curve(velocity, F_c, F_s, self.v_s, 2.0)

    def _zdot(self, z, m, v):
        return bristle_rate(
            v, self.K_tau * m * z / self.strength(v, m), self.alpha, self.velocity_scale
        )

    def initial_state(self):
        z = jnp.zeros_like(self.K_tau)
        return z, jnp.zeros_like(self.K_tau)

    def state_rate(self, state, velocity):
        """(dz/dt, dτ/dt = 1) (wang2022 Eq 27 with the knobs)."""
        z, tau = state
        zdot = self._zdot(z, self.load_factor(tau), velocity)
        return zdot, jnp.ones_like(zdot)

    def force(self, state, velocity) -> Array:
        """F_f = K z + C_τ dz/dt + σ2 v, N (wang2022 Eqs 25, 27)."""
        z, tau = state
        m = self.load_factor(tau)
        return self.K_tau * m * z + self.C_tau * self._zdot(z, m, velocity) + self.sigma2 * velocity

    def steady_force(self, velocity: ArrayLike) -> Array:
        """The constant-velocity limit g(v)·sgn(v) + σ2·v, N, at a = 0."""
        v = jnp.asarray(velocity)
        return self.strength(v) * jnp.sign(v) + self.sigma2 * v
