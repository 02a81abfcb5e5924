"""One asperity of a fractal surface: critical areas and regime laws (wang2022 Eqs 2–14, 17–22).

Every per-asperity quantity of wang2022 is a power law c·a'^p in the truncated area a' (with a
regime-dependent c and p), so each is carried here as a `PowerLaw` in log form. Regimes are
indexed ELASTIC, EP1, EP2, PLASTIC, largest asperities first (split at a'_ec > a'_epc > a'_pc).
"""

import math

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ._materials import ContactPair
from ._surface import FractalSurface

Scalar = Float[Array, ""]

ELASTIC, EP1, EP2, PLASTIC = 0, 1, 2, 3
REGIME_NAMES = ("elastic", "ep1", "ep2", "plastic")  # ep = elastic–plastic (first, second)
"""The four deformation regimes of an asperity (wang2022 Section 2, Eqs 5–7): fully elastic
(δ/δ_ec < 1), first elastic–plastic (1–6), second elastic–plastic (6–110), fully plastic (≥ 110)."""

_LN2 = math.log(2.0)
_LNPI = math.log(math.pi)


class PowerLaw(eqx.Module):
    """c·a^p stored as (log c, p); a in m^2."""

    log_c: Scalar
    p: Scalar

    def __call__(self, a):
        return jnp.exp(self.log_c + self.p * jnp.log(a))

    def __mul__(self, other: "PowerLaw") -> "PowerLaw":
        return PowerLaw(self.log_c + other.log_c, self.p + other.p)

    def __pow__(self, k) -> "PowerLaw":
        return PowerLaw(k * self.log_c, k * self.p)

    def scaled(self, log_factor) -> "PowerLaw":
        return PowerLaw(self.log_c + log_factor, self.p)


def _log_x(surface: FractalSurface, pair: ContactPair):
    """log of the bracket of wang2022 Eq 5: 2^(11-2D)/pi^(4-D) (E/KH)^2 G^(2D-4) ln(gamma) / M."""
    D = surface.D
    return (
        (11 - 2 * D) * _LN2
        - (4 - D) * _LNPI
        + 2 * jnp.log(pair.E_star / (pair.K * pair.H))
        + (2 * D - 4) * jnp.log(surface.G)
        + jnp.log(jnp.log(surface.gamma))
        - jnp.log(surface.M)
    )


def log_critical_areas(surface: FractalSurface, pair: ContactPair):
    """log of the critical truncated areas (a'_ec, a'_epc, a'_pc), a' in m^2 (wang2022 Eqs 5–7).

    δ/δ_ec = (a'_ec/a')^(D-2) by Eqs 2 and 4, so δ/δ_ec = 6 and 110 give Eqs 6 and 7.
    """
    lx = _log_x(surface, pair)
    inv = 1.0 / (surface.D - 2.0)
    return lx * inv, (lx - math.log(6.0)) * inv, (lx - math.log(110.0)) * inv


def critical_areas(surface: FractalSurface, pair: ContactPair):
    """Critical truncated areas (a'_ec, a'_epc, a'_pc) in m^2 (wang2022 Eqs 5–7)."""
    return tuple(jnp.exp(v) for v in log_critical_areas(surface, pair))


def load_laws(surface: FractalSurface, pair: ContactPair, log_a_ec) -> tuple[PowerLaw, ...]:
    """Normal load P(a') of one asperity, N, in each regime (wang2022 Eqs 8, 9, 11, 13).

    Eq 9's garbled exponent is corrected (built like Eq 11 from Kogut–Etsion's law) to
    a'^(1.1375 + 0.2875 D) over a'_ec^(2.1375 - 0.7125 D). The printed elastic–plastic laws are
    kept, so P(a') jumps at the regime boundaries (x1.02 at a'_ec) while the load balance stays
    continuous. See docs/reproduction.md, "wang2022: misprints and corrections" (1, 6).
    """
    D, E, H = surface.D, pair.E_star, pair.H
    ln_lng = jnp.log(jnp.log(surface.gamma))
    # Eq 8: 2^((11-2D)/2) / (3 pi^((4-D)/2)) E M^-1/2 G^(D-2) (ln gamma)^1/2 a'^((4-D)/2)
    elastic = PowerLaw(
        0.5 * (11 - 2 * D) * _LN2
        - math.log(3.0)
        - 0.5 * (4 - D) * _LNPI
        + jnp.log(E)
        - 0.5 * jnp.log(surface.M)
        + (D - 2) * jnp.log(surface.G)
        + 0.5 * ln_lng,
        0.5 * (4 - D),
    )
    # Common factor of Eqs 9, 11: pi^(4-D) M E (KH/E)^3 / (2^(11-2D) G^(2D-4) ln gamma) = KH/X.
    log_q = jnp.log(pair.K * H) - _log_x(surface, pair)
    ep1 = PowerLaw(  # Eq 9 (corrected exponent)
        math.log(0.34) + log_q - (2.1375 - 0.7125 * D) * log_a_ec, 1.1375 + 0.2875 * D
    )
    ep2 = PowerLaw(  # Eq 11
        math.log(0.47) + log_q - (1.8945 - 0.6315 * D) * log_a_ec, 0.8945 + 0.3685 * D
    )
    plastic = PowerLaw(jnp.log(H), jnp.ones_like(D))  # Eq 13
    return elastic, ep1, ep2, plastic


def area_laws(surface: FractalSurface, log_a_ec, area: str) -> tuple[PowerLaw, ...]:
    """Contact area a(a') of one asperity, m^2, used in Eqs 14 and 18 (per regime).

    area="truncated": a = a' everywhere (the reading that reproduces Table 3).
    area="real": Hertz a = a'/2 (elastic), Eq 10 (ep1), Eq 12 (ep2, printed as a_en2), a = a'
    (plastic, Eq 13).
    """
    D = surface.D
    one = jnp.ones_like(D)
    if area == "truncated":
        same = PowerLaw(jnp.zeros_like(D), one)
        return same, same, same, same
    if area != "real":
        raise ValueError(f"area must be 'truncated' or 'real', got {area!r}")
    return (
        PowerLaw(-_LN2 * one, one),
        PowerLaw(math.log(0.465) + (0.568 * D - 0.704) * log_a_ec, 1.704 - 0.568 * D),  # Eq 10
        PowerLaw(math.log(0.47) + (0.573 * D - 0.719) * log_a_ec, 1.719 - 0.573 * D),  # Eq 12
        PowerLaw(jnp.zeros_like(D), one),
    )


def friction_coefficients(pair: ContactPair):
    """(c_a, c_P) of Eq 14, T = c_a·a + c_P·P: 8σ_s/(π(6-3ν)) (Pa) and 8(2ν-1)/(π(6-3ν))."""
    den = math.pi * (6.0 - 3.0 * pair.nu)
    return 8.0 * pair.sigma_s / den, 8.0 * (2.0 * pair.nu - 1.0) / den


def mindlin_factors(psi):
    """Functions of ψ = t/(μ_t P) in wang2022 Eqs 18, 20 and 22 (Mindlin, Eq 17 corrected).

    Returns (s_k, phi_d, phi_s):
        s_k   = (1 - ψ)^(1/3)                                    (stiffness, Eq 18)
        phi_d = 1 - (1-ψ)^(5/3) - (5ψ/6)(1 + (1-ψ)^(2/3))        (dissipation, Eq 20)
        phi_s = 3/5 - (1-ψ)^(2/3) + (2/5)(1-ψ)^(5/3)              (stored energy, Eq 22)
    Valid for 0 <= ψ < 1; small-ψ limits and accuracy: docs/reproduction.md, "Further facts".
    """
    ok = psi < 1.0
    one_minus = jnp.where(ok, 1.0 - psi, 1.0)  # double-where: keep the power's input positive
    l1m = jnp.log(one_minus)
    s_k, c23, c53 = jnp.exp(l1m / 3), jnp.exp(2 * l1m / 3), jnp.exp(5 * l1m / 3)
    phi_d = 1.0 - c53 - (5.0 * psi / 6.0) * (1.0 + c23)
    phi_s = 0.6 - c23 + 0.4 * c53
    return s_k, phi_d, phi_s


def asperity_regime(a_trunc, surface: FractalSurface, pair: ContactPair):
    """Regime index (ELASTIC=0 … PLASTIC=3) of an asperity of truncated area a' (m^2)."""
    ec, epc, pc = log_critical_areas(surface, pair)
    la = jnp.log(a_trunc)
    return jnp.where(la > ec, ELASTIC, jnp.where(la > epc, EP1, jnp.where(la > pc, EP2, PLASTIC)))


def asperity_load(a_trunc, surface: FractalSurface, pair: ContactPair):
    """Normal load of one asperity of truncated area a' (m^2), N, in its regime (Eqs 8–13)."""
    ec, _, _ = log_critical_areas(surface, pair)
    laws = load_laws(surface, pair, ec)
    regime = asperity_regime(a_trunc, surface, pair)
    values = jnp.stack([law(a_trunc) for law in laws])
    return jnp.take_along_axis(values, regime[None, ...], axis=0)[0]
