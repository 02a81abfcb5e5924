"""wang2022's chain, once: parameters → contact → element → observables (phase slips).

    (D, G, μ_t, σ_s)  --FractalContact, Eqs 5–24-->  F_s, K_τ, C_τ at the normal loads (Eq 28)
    (F_s, K_τ, C_τ, α) --PreSlipLuGre, Eq 27, slip ODE-->  phase slips T4…T7 (Tables 4–7)

under the stage cycle `TrapezoidProfile(a_max)` (docs/reproduction.md; its users:
docs/architecture.md, One of each). Also the one mapping between unconstrained fit coordinates θ
and physical parameters (`to_physical`, `to_theta`).

Derivatives of the contact at many loads. optimistix 0.1.0's forward linearisation of a residual
that contains the contact's optimistix root find is rejected by lineax as non-finite. The contact
map (n loads × 4 parameters) is therefore wrapped in a `jax.custom_jvp` whose tangent is its dense
Jacobian (`jax.jacfwd`, which is finite) times the input tangent; it is linear in the tangent, so
reverse mode (`jax.grad`) works through it too.
"""

from __future__ import annotations

import math

import diffrax as dfx
import jax
import jax.numpy as jnp
import numpy as np

from ._checks import as_f64
from ._contact._presets import wang2022_table3_model
from ._dynamics._profiles import TrapezoidProfile
from ._dynamics._rodas4 import Rodas4
from ._dynamics._slip import slip_phase_averages
from ._friction._lugre import PreSlipLuGre
from ._presets import (
    CHAIN_DEFAULTS,
    WANG2022_A_MAX,
    WANG2022_RETICLE_MASS_KG,
    WANG2022_TANGENTIAL_LOAD_N,
)
from ._tables import wang2022_table

# --- θ (unconstrained) <-> physical -------------------------------------------------------------
# Search boxes for D and log G (scaled logits keep Levenberg–Marquardt inside them).
D_RANGE = (2.05, 2.98)
LOG_G_RANGE = (math.log(1e-11), math.log(1e-5))


def _logit(u):
    return math.log(u / (1.0 - u))


def mu_min(loads, tangential_load=WANG2022_TANGENTIAL_LOAD_N) -> float:
    """T/P at the smallest load: Mindlin's law (wang2022 Eq 17) needs μ_t above it."""
    return float(tangential_load / np.min(np.asarray(loads)))


def to_physical(theta, names, mu_min):
    """θ → physical values of `names` (JAX, differentiable).

    D: scaled logit over `D_RANGE`; G_m (m): scaled logit of log G over `LOG_G_RANGE`;
    mu_t: μ_min(1 + e^θ) > T/P (Eq 17); sigma_s_Pa (Pa) and alpha: e^θ.
    """
    out = []
    for i, name in enumerate(names):
        t = theta[i]
        if name == "D":
            out.append(D_RANGE[0] + (D_RANGE[1] - D_RANGE[0]) * jax.nn.sigmoid(t))
        elif name == "G_m":
            lo, hi = LOG_G_RANGE
            out.append(jnp.exp(lo + (hi - lo) * jax.nn.sigmoid(t)))
        elif name == "mu_t":
            out.append(mu_min * (1.0 + jnp.exp(t)))
        elif name in ("sigma_s_Pa", "alpha"):
            out.append(jnp.exp(t))
        else:
            raise ValueError(f"unknown parameter {name!r}")
    return jnp.stack(out)


def to_theta(values, names, mu_min) -> np.ndarray:
    """Physical values of `names` → θ (inverse of `to_physical`); ValueError outside the ranges."""
    d0, d1 = D_RANGE
    g0, g1 = LOG_G_RANGE
    ranges = {
        "D": (lambda v: d0 < v < d1, f"({d0}, {d1})"),
        "G_m": (lambda v: 1e-11 < v < 1e-5, "(1e-11, 1e-05) m"),
        "mu_t": (lambda v: v > mu_min, f"({mu_min:.4g}, inf) (Eq 17: mu_t > T/P)"),
        "sigma_s_Pa": (lambda v: v > 0, "(0, inf) Pa"),
        "alpha": (lambda v: v > 0, "(0, inf)"),
    }
    theta = []
    for name, v in zip(names, values):
        v = float(v)
        good, rng = ranges[name]
        if not (math.isfinite(v) and good(v)):
            raise ValueError(f"{name} = {v:g} is outside the allowed range {rng}")
        if name == "D":
            theta.append(_logit((v - d0) / (d1 - d0)))
        elif name == "G_m":
            theta.append(_logit((math.log(v) - g0) / (g1 - g0)))
        elif name == "mu_t":
            theta.append(math.log(v / mu_min - 1.0))
        else:
            theta.append(math.log(v))
    return np.array(theta)


# --- parameters → contact -----------------------------------------------------------------------


def wang2022_loads() -> jnp.ndarray:
    """Table 3's six normal loads, N (Eq 28)."""
    return jnp.asarray(wang2022_table(3)["load_N"])


def table3_contact():
    """Table 3's published F_s (N), K_τ (N/m), C_τ (N s/m) at its six rows."""
    t3 = wang2022_table(3)
    return tuple(jnp.asarray(t3[k]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))


def _contact_raw(phys4, loads):
    """(D, G, μ_t, σ_s) -> [F_s, K_τ, C_τ] at `loads` (3, n), plus a per-load validity flag."""
    D, G, mu_t, sigma_s = phys4
    model = wang2022_table3_model(G, mu_t, sigma_s, D=D, throw=False)
    out = jax.vmap(model)(loads)
    ok = out.converged & ~out.all_plastic & (out.K_tau > 0) & (out.F_s > 0)
    ok = ok & jnp.isfinite(out.values).all(-1)
    return jnp.stack([out.F_s, out.K_tau, out.C_tau]), ok


_SAFE_PHYS4 = tuple(CHAIN_DEFAULTS[k] for k in ("D", "G_m", "mu_t", "sigma_s_Pa"))


@jax.custom_jvp
def _contact(phys4, loads):
    values, ok = _contact_raw(phys4, loads)
    return jnp.concatenate([values, ok.astype(values.dtype)[None]])  # (4, n): last row = ok


@_contact.defjvp
def _contact_jvp(primals, tangents):
    phys4, loads = primals
    dphys, _ = tangents  # the loads are data here
    out = _contact(phys4, loads)
    # Where a load balance failed, the implicit derivative of its root find is a non-finite
    # linear solve that raises: differentiate at a safe point instead and zero the tangent
    # (those rows are flagged and their residuals are not used).
    good = jnp.all(out[3] > 0.5)
    p_eval = jnp.where(good, phys4, jnp.asarray(_SAFE_PHYS4, dtype=phys4.dtype))
    J = jax.jacfwd(lambda p: _contact_raw(p, loads)[0])(p_eval)  # (3, n, 4)
    dout = jnp.where(good, J, 0.0) @ dphys
    return out, jnp.concatenate([dout, jnp.zeros_like(dout[:1])])


def chain_contact(params, loads=None):
    """F_s (N), K_τ (N/m), C_τ (N s/m) at `loads` (N) for physical params (D, G, μ_t, σ_s[, α]).

    wang2022 Eqs 5–24 (`wang2022_table3_model` with D free). Returns ((3, n), ok (n,)), ok False
    where the load balance failed or the contact is all-plastic (F_s or K_τ zero).
    Differentiable by `jax.jacfwd` and `jax.grad` (custom JVP, see the module docstring).
    """
    loads = wang2022_loads() if loads is None else as_f64(loads, "loads")
    p = jnp.asarray(params, dtype=jnp.float64)[:4]
    out = _contact(p, loads)
    return out[:3], out[3] > 0.5


# --- element → observables ----------------------------------------------------------------------


PAPER_SOLVER = Rodas4(lu="lapack")  # the wang2022 chain's slip solves (`phase_slips`)


def phase_slips(
    element, *, a_max=WANG2022_A_MAX, profile=None, mass=WANG2022_RETICLE_MASS_KG, **solver_kw
):
    """[T4, T5, T6, T7] (m) of `element` under `TrapezoidProfile(a_max)` (wang2022 Tables 4–7).

    `profile` replaces the stage profile; `solver_kw` go to `slip_phase_averages`. The solver
    defaults to Rodas4 with LAPACK's LU (`PAPER_SOLVER`, docs/performance.md, "One kernel per
    solve": the reproduction's measured-table fit stops on a ridge in the other rounding).
    """
    profile = TrapezoidProfile(a_max=a_max) if profile is None else profile
    solver_kw.setdefault("solver", PAPER_SOLVER)
    return slip_phase_averages(element, profile, mass, **solver_kw)


def lugre_phase_slips_nm(F_s, K_tau, C_tau, alpha, **kw):
    """Phase slips (nm), shape (n, 4), of `PreSlipLuGre(F_s, K_τ, C_τ, α)` (Eq 27) per row."""

    def one(f, k, c):
        return phase_slips(PreSlipLuGre(f, k, c, alpha), **kw)

    return jax.vmap(one)(F_s, K_tau, C_tau) * 1e9


# --- the whole chain ----------------------------------------------------------------------------
# Slip tolerances of the full-chain fit (docs/performance.md, The full-chain fit's slip tolerances)
SLIP_ATOL = 1e-15
SLIP_RTOL = 1e-6
SLIP_MAX_STEPS = 40_000


def chain_phase_slips(
    params,
    loads=None,
    *,
    adjoint=dfx.RecursiveCheckpointAdjoint(),
    atol=SLIP_ATOL,
    rtol=SLIP_RTOL,
    max_steps=SLIP_MAX_STEPS,
    lu="lapack",
):
    """Phase slips [T4, T5, T6, T7] (nm) at `loads` for params (D, G m, μ_t, σ_s Pa, α).
    `lu`: the slip solver's factorisation (`Rodas4.lu`; the arithmetic setting, "lapack" as
    `PAPER_SOLVER`).


    The whole chain (wang2022 Eqs 5–24, 26–27 and the phase windows of docs/reproduction.md),
    vmapped over the loads. Returns (slips (n, 4) in nm, ok (n,)): ok is False where the contact
    is all-plastic or its load balance failed, or the slip solver did not finish (those rows are
    then not meaningful), or F_s <= m·a_max (gross sliding: outside Eq 27's pre-sliding model).
    `adjoint=diffrax.ForwardMode()` for `jax.jacfwd`; the default for `jax.grad`.
    """
    params = jnp.asarray(params, dtype=jnp.float64)
    (F_s, K, C), ok = chain_contact(params, loads)
    ok = ok & (F_s > WANG2022_TANGENTIAL_LOAD_N)  # else gross sliding: run with stand-ins
    F_s, K, C = (jnp.where(ok, x, safe) for x, safe in zip((F_s, K, C), (1.0, 1e7, 500.0)))
    slips = lugre_phase_slips_nm(
        F_s,
        K,
        C,
        params[4],
        adjoint=adjoint,
        atol=atol,
        rtol=rtol,
        max_steps=max_steps,
        throw=False,
        solver=Rodas4(lu=lu),
    )
    ok = ok & jnp.all(jnp.isfinite(slips), axis=-1)
    return slips, ok
