"""Contact parameters of a rough interface: F_s, K_τ, C_τ, z_max (wang2022 Sections 2–4).

The asperity truncated areas follow Mandelbrot's island distribution (wang2022 Eq 15),

    n(a') = (D-1)/(2 a'_l) (a'_l/a')^((D+1)/2),   0 < a' <= a'_l,

and every per-asperity law is a power law c·a'^p (see `_asperity`), so each regime integral is
closed-form:

    ∫_lo^hi c a'^p n(a') da' = c (D-1)/2 a'_l^((D-1)/2) ∫_lo^hi a'^(q-1) da',  q = p - (D-1)/2.

The largest truncated area a'_l follows from the load balance Σ_regimes ∫ P n da' = F, solved for
log a'_l with an optimistix Newton root find and differentiated by the implicit function theorem.
"""

import math
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Bool, Float

from .._checks import check_range, fail_if, failures_as_nan, mode_jit
from .._export import cached_jit
from .._precision import ensure_x64
from ._asperity import (
    EP1,
    EP2,
    PLASTIC,
    PowerLaw,
    area_laws,
    friction_coefficients,
    load_laws,
    log_critical_areas,
    mindlin_factors,
)
from ._materials import ContactPair
from ._surface import FractalSurface

Scalar = Float[Array, ""]


def _expm1_over_x(x):
    """expm1(x)/x for x <= 0, smooth through x = 0 (double-where)."""
    small = jnp.abs(x) < 1e-6
    safe = jnp.where(small, -1.0, x)
    return jnp.where(small, 1.0 + x / 2.0 + x * x / 6.0, jnp.expm1(safe) / safe)


def regime_integral(law: PowerLaw, log_lo, log_hi, log_al, D):
    """∫ law(a') n(a') da' over [lo, hi] ∩ (0, a'_l] in closed form (wang2022 Eq 15 weighting).

    `log_lo=None` means a lower limit of 0 (needs q = p - (D-1)/2 > 0); `log_hi=None` means a'_l.
    Written as exp(q·base)·L·expm1(-|q| L)/(-|q| L) with L = ln(hi/lo), which has no overflow and
    no 0/0 at q = 0 (D = 2.5 in the elastic regime).
    """
    h = 0.5 * (D - 1.0)
    q = law.p - h
    log_pref = law.log_c + jnp.log(h) + h * log_al
    hi = log_al if log_hi is None else jnp.minimum(log_hi, log_al)
    if log_lo is None:
        return jnp.exp(log_pref + q * hi) / q
    lo = jnp.minimum(log_lo, log_al)
    span = hi - lo
    base = jnp.where(q > 0, hi, lo)
    return jnp.exp(log_pref + q * base) * span * _expm1_over_x(-jnp.abs(q) * span)


_SURFACE = ("D", "G", "M", "gamma")


def _regime_bounds(log_ec, log_epc, log_pc):
    """(lo, hi) in log a' for each regime, ELASTIC … PLASTIC; None = a'_l above, 0 below."""
    return ((log_ec, None), (log_epc, log_ec), (log_pc, log_epc), (None, log_pc))


def _integrals(laws, bounds, log_al, D):
    return jnp.stack(
        [regime_integral(law, lo, hi, log_al, D) for law, (lo, hi) in zip(laws, bounds)]
    )


_SCALARS = (
    "load",
    "F_s",
    "K_tau",
    "C_tau",
    "z_max",
    "a_l",
    "a_ec",
    "a_epc",
    "a_pc",
    "psi",
    "W_d",
    "W_s",
)


def _packed(name: str) -> property:
    i = _SCALARS.index(name)
    return property(lambda self: self.values[..., i], doc=f"{name} (see ContactParameters)")


_NOT_CONVERGED = (
    "load balance for a'_l (wang2022 Eqs 8-15) did not converge: check D, G, M and the load for "
    "extreme values, or raise max_steps"
)
_ALL_PLASTIC = (
    "every asperity is fully plastic (a'_l <= a'_pc), so the fractal model carries no tangential "
    "load: check G (too large?), M and the units of the load"
)


class ContactParameters(eqx.Module):
    """Contact parameters at one normal load (all SI units); batched under `jax.vmap`.

    The numbers are stored packed in one float array (a single output buffer keeps the overhead
    of a jitted call low) and read through these properties:

        load:       normal load F, N.
        F_s:        maximum static friction, N (Eqs 14, 16).
        K_tau:      tangential stiffness, N/m (Eqs 17–19).
        C_tau:      tangential damping, N s/m (Eqs 20–24).
        z_max:      maximum tangential deformation F_s/K_τ, m (Eq 26).
        a_l:        largest truncated asperity area a'_l, m^2 (load balance).
        a_ec, a_epc, a_pc: critical truncated areas, m^2 (Eqs 5–7).
        psi:        tangential-load ratio T/(μ_t P) used in Eqs 18–22.
        W_d, W_s:   dissipated and stored tangential energy per cycle, J (Eqs 21, 23).
        load_share: share of F carried in each regime (elastic, ep1, ep2, plastic); sums to 1.
        converged:  whether the load balance converged.
        all_plastic: every asperity is fully plastic (a'_l <= a'_pc): the model then carries no
                    tangential load, and F_s, K_τ, C_τ and z_max are returned as 0.
        no_static_friction: F_s = z_max = 0 with K_τ > 0 (a'_l <= a'_epc: no asperity is elastic
                    or first elastic–plastic, the only ones that carry static friction); an eager
                    call with throw=True warns (RuntimeWarning), an all-plastic contact raises.
    """

    values: Float[Array, "... 16"]
    flags: Bool[Array, "... 2"]

    load, F_s, K_tau, C_tau, z_max, a_l, a_ec, a_epc, a_pc, psi, W_d, W_s = map(_packed, _SCALARS)

    @property
    def load_share(self):
        return self.values[..., len(_SCALARS) :]

    @property
    def converged(self):
        return self.flags[..., 0]

    @property
    def all_plastic(self):
        return self.flags[..., 1]

    @property
    def no_static_friction(self):
        return (self.values[..., 1] == 0.0) & ~self.flags[..., 1]

    def as_dict(self) -> dict:
        """Plain dict of NumPy values (for printing and JSON)."""
        keys = (*_SCALARS, "load_share", "converged", "all_plastic")
        return {k: np.asarray(getattr(self, k)) for k in keys}


class FractalContact(eqx.Module):
    """The fractal contact model of wang2022 Sections 2–3 for one surface and one material pair.

    Call it with a normal load (N) to get a `ContactParameters` record; batch over loads with
    `jax.vmap(model)(loads)` and over surfaces with `eqx.filter_vmap`. Every field that is a
    number is an array leaf, so D, G, M, μ_t, σ_s, the load … can be differentiated or fitted.

    Fields:
        surface:         `FractalSurface` (D, G, M, γ).
        pair:            `ContactPair` (E*, G', H, ν, σ_s).
        mu_t:            friction coefficient in Mindlin's law (Eq 17), > 0. Not published.
        tangential_load: T in the ratio T/P of Eqs 18–22, N, >= 0; for Table 3 the reticle's
                         inertial load m·a_max = 0.321 N (docs/reproduction.md, misprint 4).
        mass:            slider mass m in Eq 24, kg, > 0 (0.321 kg reticle in the paper).
        area:            "truncated" (a = a', default) or "real" (Eqs 10, 12, Hertz a'/2) for the
                         contact area in Eqs 14 and 18 (static).
        throw:           raise if the load balance fails (static). With False, check
                         `ContactParameters.converged`.
        max_steps:       Newton steps allowed for the load balance (static).
    """

    surface: FractalSurface
    pair: ContactPair
    mu_t: Scalar
    tangential_load: Scalar
    mass: Scalar
    area: str = eqx.field(static=True)
    throw: bool = eqx.field(static=True)
    max_steps: int = eqx.field(static=True)

    def __init__(
        self,
        surface: FractalSurface,
        pair: ContactPair,
        *,
        mu_t,
        tangential_load,
        mass,
        area: str = "truncated",
        throw: bool = True,
        max_steps: int = 64,
    ):
        if not isinstance(surface, FractalSurface):
            raise TypeError(f"surface must be a FractalSurface, got {type(surface).__name__}")
        if not isinstance(pair, ContactPair):
            raise TypeError(f"pair must be a ContactPair, got {type(pair).__name__}")
        if area not in ("truncated", "real"):
            raise ValueError(f"area must be 'truncated' or 'real', got {area!r}")
        self.surface = surface
        self.pair = pair
        self.mu_t = check_range(mu_t, "mu_t", 0.0)
        self.tangential_load = check_range(
            tangential_load, "tangential_load", 0.0, lo_open=False, unit="N"
        )
        self.mass = check_range(mass, "mass", 0.0, unit="kg")
        self.area = area
        self.throw = throw
        self.max_steps = max_steps

    def log_total_load(self, log_al, log_bounds=None):
        """log of the load carried when the largest area is exp(log_al) (Eqs 8–13, 15)."""
        s = self.surface
        if log_bounds is None:
            log_bounds = log_critical_areas(s, self.pair)
        laws = load_laws(s, self.pair, log_bounds[0])
        return jnp.log(jnp.sum(_integrals(laws, _regime_bounds(*log_bounds), log_al, s.D)))

    def solve_load_balance(self, load):
        """log a'_l such that the asperity loads sum to `load` (N); returns (log a'_l, ok)."""
        s = self.surface
        log_bounds = log_critical_areas(s, self.pair)
        log_f = jnp.log(load)

        def residual(log_al, args):
            return self.log_total_load(log_al, log_bounds) - log_f

        # All-plastic solution as the start; the true a'_l is never smaller (elastic and
        # elastic–plastic asperities carry less than H·a').
        y0 = jnp.log(load * (3.0 - s.D) / (self.pair.H * (s.D - 1.0)))
        solver = optx.Newton(rtol=1e-13, atol=1e-13)
        sol = optx.root_find(residual, solver, y0, max_steps=self.max_steps, throw=False)
        ok = (sol.result == optx.RESULTS.successful) & jnp.isfinite(sol.value)
        return sol.value, ok

    def __call__(self, load) -> ContactParameters:
        """Contact parameters at normal load `load` (N, > 0). wang2022 Eqs 5–26.

        Concrete inputs are validated here (ValueError); the computation itself is compiled
        (`equinox.filter_jit`), so eager calls are fast too and calls inside a user's jit are
        inlined.
        """
        ensure_x64()
        load = check_range(load, "load", 0.0, math.inf, unit="N")
        for name, value in (("load", load), *((k, getattr(self.surface, k)) for k in _SURFACE)):
            if not isinstance(value, jax.core.Tracer) and jnp.ndim(value) != 0:
                raise ValueError(
                    f"{name} has shape {jnp.shape(value)}; FractalContact evaluates one surface at "
                    "one load (a scalar): use jax.vmap over loads, eqx.filter_vmap over surfaces"
                )
        psi = self.tangential_load / (self.mu_t * load)
        fail_if(psi, psi >= 1.0, self._psi_message(load))
        if any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves((self, load))):
            out = _evaluate(self, load)  # inlined in the caller's trace, checks included
        else:  # a stored program without host callbacks; its failures raised here
            with failures_as_nan():
                values, flags = _evaluate_quiet(self, load)
            out = ContactParameters(values, flags)
            (converged, all_plastic), F_s = np.asarray(flags), np.asarray(values)[1]
            if self.throw and not converged:
                raise eqx.EquinoxRuntimeError(_NOT_CONVERGED)
            if self.throw and all_plastic:
                raise eqx.EquinoxRuntimeError(_ALL_PLASTIC)
            if self.throw and F_s == 0.0:  # `no_static_friction`, in NumPy (a JAX op: 1 ms)
                warnings.warn(
                    "no asperity is elastic or first elastic-plastic (a'_l <= a'_epc), so F_s and "
                    "z_max are 0 (wang2022 Eqs 14, 16) while K_tau is not: D is close to 3 or G "
                    "large for this load; check D, G, M and the units of the load",
                    RuntimeWarning,
                    stacklevel=2,
                )
        return out

    def _psi_message(self, load) -> str:
        msg = (
            "tangential_load / load must be below mu_t (Mindlin's law, wang2022 Eq 17, needs "
            "T < mu_t P)"
        )
        if isinstance(load, jax.core.Tracer) or isinstance(self.mu_t, jax.core.Tracer):
            return msg
        ratio = jnp.max(self.tangential_load / load)
        return msg + f": T/P = {float(ratio):g}, mu_t = {float(jnp.min(self.mu_t)):g}"

    def _evaluate(self, load, throw=True) -> ContactParameters:
        s, pair = self.surface, self.pair
        D = s.D
        psi = self.tangential_load / (self.mu_t * load)
        psi = fail_if(psi, psi >= 1.0, self._psi_message(load))

        log_al, ok = self.solve_load_balance(load)
        if throw:
            log_al = fail_if(log_al, ~ok, _NOT_CONVERGED)
        log_ec, log_epc, log_pc = log_bounds = log_critical_areas(s, pair)
        bounds = _regime_bounds(*log_bounds)
        loads = load_laws(s, pair, log_ec)
        areas = area_laws(s, log_ec, self.area)

        load_parts = _integrals(loads, bounds, log_al, D)
        area_parts = _integrals(areas, bounds, log_al, D)

        # Eqs 14, 16: static friction from the elastic and first elastic–plastic asperities.
        c_a, c_p = friction_coefficients(pair)
        F_s = c_a * jnp.sum(area_parts[:EP2]) + c_p * jnp.sum(load_parts[:EP2])

        # Eqs 18, 19: stiffness from all but the plastic asperities.
        s_k, phi_d, phi_s = mindlin_factors(psi)
        root_area = [a**0.5 for a in areas[:PLASTIC]]
        root_parts = _integrals(root_area, bounds[:PLASTIC], log_al, D)
        K_tau = 8.0 * pair.G_star / math.sqrt(math.pi) * s_k * jnp.sum(root_parts)

        # Eqs 20–23: per-asperity energies ∝ P²/r with r = (a/π)^(1/2).
        p2_over_r = [
            (P**2 * a**-0.5).scaled(0.5 * math.log(math.pi))
            for P, a in zip(loads[:PLASTIC], areas[:PLASTIC])
        ]
        e_parts = _integrals(p2_over_r, bounds[:PLASTIC], log_al, D)
        mu2_g = self.mu_t**2 / pair.G_star
        W_d = 0.9 * mu2_g * phi_d * jnp.sum(e_parts[EP1:])  # Eq 21
        W_s = 3.0 / 16.0 * mu2_g * phi_s * jnp.sum(e_parts)  # Eq 23
        all_plastic = log_al <= log_pc
        if throw:
            K_tau = fail_if(K_tau, all_plastic, _ALL_PLASTIC)
        # double-where: an all-plastic contact has K = W_s = 0; return zeros, not 0/0.
        safe_k = jnp.where(all_plastic, 1.0, K_tau)
        safe_ws = jnp.where(all_plastic, 1.0, W_s)
        C_tau = jnp.where(all_plastic, 0.0, W_d / safe_ws * jnp.sqrt(self.mass * safe_k))  # Eq 24
        z_max = jnp.where(all_plastic, 0.0, F_s / safe_k)  # Eq 26

        # packed in _SCALARS order
        a_l, a_ec, a_epc, a_pc = (jnp.exp(v) for v in (log_al, log_ec, log_epc, log_pc))
        scalars = (load, F_s, K_tau, C_tau, z_max, a_l, a_ec, a_epc, a_pc, psi, W_d, W_s)
        values = jnp.concatenate([jnp.stack(scalars), load_parts / jnp.sum(load_parts)])
        return ContactParameters(values=values, flags=jnp.stack([ok, all_plastic]))


@mode_jit
def _evaluate(model: FractalContact, load) -> ContactParameters:
    return model._evaluate(load, model.throw)


@cached_jit  # eager calls: no host callback, so the trace is stored and the compile cached
def _evaluate_quiet(model: FractalContact, load):
    out = model._evaluate(load, throw=False)
    return out.values, out.flags


def contact_parameters(
    surface: FractalSurface,
    pair: ContactPair,
    load,
    *,
    mu_t,
    tangential_load,
    mass,
    area="truncated",
) -> ContactParameters:
    """Functional form of `FractalContact(surface, pair, ...)(load)`; see there."""
    model = FractalContact(
        surface, pair, mu_t=mu_t, tangential_load=tangential_load, mass=mass, area=area
    )
    return model(load)
