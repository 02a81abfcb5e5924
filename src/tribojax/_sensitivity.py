"""Sensitivities of the surface → contact → friction chain: exact gradients and elasticities.

The chain of wang2022 (Sections 2–5) and wu2015 (Section 5.3) is differentiable end to end, so
the response of any observable y to any input p is one `jax.jacfwd` away. Reported as
elasticities (normalised sensitivities)

    e_ij = ∂ln y_i / ∂ln p_j = (∂y_i/∂p_j) · p_j / y_i,

the relative change of y_i per relative change of p_j. The same formula is used for the fractal
dimension D, so e_D is per *relative* change of D: +1 % of D = 2.8821 is +0.029, a large change of
roughness; divide e_D by D for the change per unit D.

Two chains map a dict of scalar inputs to a dict of outputs: `ReticleChain` (contact and phase
slips, `tribojax._chain`'s path at one load) and `LoopChain` (contact, then wu2015's K̄, C̄).
"""

from __future__ import annotations

import dataclasses

import diffrax as dfx
import equinox as eqx
import jax
import numpy as np

from ._chain import phase_slips
from ._checks import cacheable_call, check_range, fail_if, mode_jit
from ._contact._contact import ContactParameters
from ._contact._materials import ContactPair
from ._contact._presets import wang2022_pair, wang2022_table3_model
from ._dynamics._harmonic import harmonic_balance
from ._friction._lugre import PreSlipLuGre
from ._friction._rate_independent import Jenkins, Mindlin
from ._plot import figure, save_figure
from ._precision import ensure_x64
from ._presets import (
    CALIBRATED_G_M,
    CALIBRATED_MU_T,
    CALIBRATED_SIGMA_S,
    WANG2022_A_MAX,
    WANG2022_GAMMA,
    WANG2022_REFERENCE_LOAD_N,
    WANG2022_RETICLE_MASS_KG,
    WANG2022_TABLE1_D,
)

# Fixed loop amplitude: about the largest measured phase slip of Tables 4–7 (43.9 nm, Table 6 at
# 0.6 kPa); with Table 3's z_max = 33–44 nm this is Ā ≈ 1.1–1.5, Mindlin microslip.
DEFAULT_AMPLITUDE = 50e-9  # m
CONTACT_OUTPUTS = ("F_s", "K_tau", "C_tau", "z_max")
SLIP_OUTPUTS = ("T4", "T5", "T6", "T7")
LOOP_OUTPUTS = ("A_bar", "K_bar", "C_bar")
_RANGES = {  # name: `check_range` bounds (open intervals) and unit
    "D": dict(lo=2.0, hi=3.0),
    "G": dict(lo=0.0, unit="m"),
    "mu_t": dict(lo=0.0),
    "load": dict(lo=0.0, unit="N"),
    "a_max": dict(lo=0.0, unit="m/s^2"),
    "A": dict(lo=0.0, unit="m"),
}


def _checked(params: dict, names) -> dict:
    if not isinstance(params, dict):
        raise TypeError(f"params must be a dict with keys {names}, got {type(params).__name__}")
    missing = [k for k in names if k not in params]
    extra = [k for k in params if k not in names]
    if missing or extra:
        raise ValueError(
            f"params must have exactly the keys {list(names)}: missing {missing}, unknown {extra}"
        )
    return {k: check_range(params[k], k, **_RANGES[k]) for k in names}


class ReticleChain(eqx.Module):
    """wang2022's chain from surface and operating point to contact parameters and phase slips.

    Call with a dict {"D", "G" (m), "mu_t", "load" (N), "a_max" (m/s²)} of scalars; returns a dict
    of scalars F_s (N), K_tau (N/m), C_tau (N s/m), z_max (m) and, if `slip`, T4–T7 (m, Tables
    4–7). Surface: YK with M ridges and γ (Table 1: D; G is the calibrated, not the published,
    value); pair: Table 2 with strength σ_s (Eq 14); contact: `FractalContact` with T = m·a_max
    in T/P (Eqs 17–22) and m in Eq 24; slip: `PreSlipLuGre(F_s, K_τ, C_τ, α)` (Eq 27) under
    `TrapezoidProfile(a_max)`, solved with `adjoint=diffrax.ForwardMode()` so that `jax.jacfwd`
    (the cheap direction for five inputs) works.

    Fields: sigma_s (Pa), M (ridges, ≥ 1), gamma (> 1), mass (kg), alpha (Eq 27 exponent),
    slip (static: also solve the slip ODE), rtol, atol, max_steps (static: slip solver settings,
    see `simulate_slip`). The defaults are 100x tighter than `simulate_slip`'s: derivatives need
    it (docs/reproduction.md, Further facts).
    """

    pair: ContactPair
    M: jax.Array
    gamma: jax.Array
    mass: jax.Array
    alpha: jax.Array
    slip: bool = eqx.field(static=True)
    rtol: float = eqx.field(static=True)
    atol: float = eqx.field(static=True)
    max_steps: int = eqx.field(static=True)

    PARAMETERS = ("D", "G", "mu_t", "load", "a_max")

    def __init__(
        self,
        *,
        sigma_s=CALIBRATED_SIGMA_S,
        M=1.0,
        gamma=WANG2022_GAMMA,
        mass=WANG2022_RETICLE_MASS_KG,
        alpha=1.0,
        slip: bool = True,
        rtol: float = 1e-8,
        atol: float = 1e-18,
        max_steps: int = 50_000,
    ):
        self.pair = wang2022_pair(sigma_s=sigma_s)
        self.M = check_range(M, "M", 1.0, lo_open=False)
        self.gamma = check_range(gamma, "gamma", 1.0)
        self.mass = check_range(mass, "mass", 0.0, unit="kg")
        self.alpha = check_range(alpha, "alpha", 0.0)
        self.slip = bool(slip)
        self.rtol, self.atol, self.max_steps = float(rtol), float(atol), int(max_steps)

    @property
    def outputs(self) -> tuple[str, ...]:
        return CONTACT_OUTPUTS + (SLIP_OUTPUTS if self.slip else ())

    def check(self, params: dict) -> dict:
        """Validated float64 inputs (ValueError naming a bad one, or error_if when traced)."""
        p = _checked(params, self.PARAMETERS)
        ratio = self.mass * p["a_max"] / p["load"]
        p["a_max"] = fail_if(
            p["a_max"],
            ratio >= p["mu_t"],
            "mass*a_max/load must be below mu_t (Mindlin's law, wang2022 Eq 17, needs T < mu_t P)",
        )
        return p

    def contact(self, params: dict, *, throw: bool = True) -> ContactParameters:
        """The full `ContactParameters` record at the inputs (wang2022 Eqs 5–26).

        With `throw=False` a failed load balance or an all-plastic contact is flagged in the
        record (`converged`, `all_plastic`) instead of raising.
        """
        return self._contact(self.check(params), throw)

    def _contact(self, p: dict, throw: bool = True) -> ContactParameters:
        T = self.mass * p["a_max"]
        model = wang2022_table3_model(
            p["G"],
            p["mu_t"],
            self.pair.sigma_s,
            M=self.M,
            D=p["D"],
            gamma=self.gamma,
            tangential_load=T,
            mass=self.mass,
            throw=throw,
        )
        return model(p["load"])

    def __call__(self, params: dict) -> dict:
        p = self.check(params)
        c = self._contact(p)
        out = {"F_s": c.F_s, "K_tau": c.K_tau, "C_tau": c.C_tau, "z_max": c.z_max}
        if self.slip:
            element = PreSlipLuGre(c.F_s, c.K_tau, c.C_tau, self.alpha)
            phases = phase_slips(
                element,
                a_max=p["a_max"],
                mass=self.mass,
                rtol=self.rtol,
                atol=self.atol,
                max_steps=self.max_steps,
                adjoint=dfx.ForwardMode(),
            )
            out.update(zip(SLIP_OUTPUTS, phases))
        return out


class LoopChain(eqx.Module):
    """Surface and operating point → contact → wu2015's K̄, C̄ at a fixed loop amplitude.

    Call with {"D", "G", "mu_t", "load", "a_max", "A" (m)}; returns F_s, K_tau, C_tau, z_max
    (as `ReticleChain`) and A_bar = A/A0, K_bar, C_bar (wu2015 Section 5.3) of a Jenkins (Eq 1)
    or Mindlin (Eq 2, corrected) element with μN = F_s and K_d = K_τ, so A0 = z_max (Eq 26).
    The amplitude A is a fixed physical displacement: K̄ and C̄ depend on Ā only, so the inputs
    act on them through A0 = F_s/K_τ alone (a fixed Ā would make every sensitivity zero).
    """

    contact_chain: ReticleChain
    element: str = eqx.field(static=True)

    PARAMETERS = ("D", "G", "mu_t", "load", "a_max", "A")

    def __init__(self, element: str = "mindlin", **contact_kw):
        if element not in ("jenkins", "mindlin"):
            raise ValueError(f"element must be 'jenkins' or 'mindlin', got {element!r}")
        self.element = element
        self.contact_chain = ReticleChain(slip=False, **contact_kw)

    @property
    def outputs(self) -> tuple[str, ...]:
        return CONTACT_OUTPUTS + LOOP_OUTPUTS

    def check(self, params: dict) -> dict:
        p = _checked(params, self.PARAMETERS)
        return {**self.contact_chain.check({k: p[k] for k in ReticleChain.PARAMETERS}), "A": p["A"]}

    def __call__(self, params: dict) -> dict:
        p = self.check(params)
        A = p.pop("A")
        out = self.contact_chain(p)
        cls = Jenkins if self.element == "jenkins" else Mindlin
        # μ = F_s/F and N = F: only the product μN = F_s enters the loop
        hb = harmonic_balance(cls(out["F_s"] / p["load"], p["load"], out["K_tau"]), A)
        return {**out, "A_bar": hb.A_bar, "K_bar": hb.K_bar, "C_bar": hb.C_bar}


@dataclasses.dataclass(frozen=True)
class Elasticities:
    """Values, exact Jacobian and elasticities of a map from named inputs to named outputs.

    Attributes (NumPy): parameters, outputs (names); point (input values); values (outputs);
    jacobian[i, j] = ∂y_i/∂p_j (SI units); elasticity[i, j] = ∂ln y_i/∂ln p_j (dimensionless).
    """

    parameters: tuple[str, ...]
    outputs: tuple[str, ...]
    point: np.ndarray
    values: np.ndarray
    jacobian: np.ndarray
    elasticity: np.ndarray

    def as_dict(self) -> dict:
        """JSON-ready: {"point", "values", "elasticity": {output: {parameter: e}}}."""
        return {
            "point": dict(zip(self.parameters, self.point.tolist())),
            "values": dict(zip(self.outputs, self.values.tolist())),
            "elasticity": {
                o: dict(zip(self.parameters, row.tolist()))
                for o, row in zip(self.outputs, self.elasticity)
            },
        }

    def table(self) -> str:
        """Markdown table: one row per output (value and e with respect to each input)."""
        head = "| output | value | " + " | ".join(f"e_{p}" for p in self.parameters) + " |"
        rule = "|---|---:|" + "---:|" * len(self.parameters)
        rows = [
            f"| {o} | {v:.4g} | " + " | ".join(f"{e:+.3f}" for e in row) + " |"
            for o, v, row in zip(self.outputs, self.values, self.elasticity)
        ]
        return "\n".join([head, rule, *rows])

    def plot(self, path=None, *, title: str = "Elasticities ∂ln y / ∂ln p"):
        """Bar chart, one panel per output (symmetric-log axis: e_D is ~10x the others).

        Writes a PNG at `path` if given. Returns the matplotlib Figure, or None (with a message)
        when matplotlib is not installed.
        """
        n = len(self.outputs)
        cols = min(n, 4)
        rows = -(-n // cols)
        fig = figure("bar chart", figsize=(3.2 * cols, 2.6 * rows), constrained_layout=True)
        if fig is None:
            return None
        axes = fig.subplots(rows, cols, squeeze=False)
        colours = [f"C{j}" for j in range(len(self.parameters))]
        for ax, name, e in zip(axes.flat, self.outputs, self.elasticity):
            ax.barh(self.parameters, e, color=colours)
            ax.axvline(0.0, color="k", lw=0.6)
            ax.set_xscale("symlog", linthresh=1.0)
            ax.set_title(name, fontsize=9)
            ax.invert_yaxis()
        for ax in list(axes.flat)[n:]:
            ax.set_visible(False)
        fig.suptitle(title)
        if path is not None:
            save_figure(fig, path, dpi=110)
        return fig


@mode_jit
def _value_and_jacobian(fn, params, mode):
    def both(p):
        y = fn(p)
        return y, y

    jac = jax.jacfwd if mode == "fwd" else jax.jacrev
    J, y = jac(both, has_aux=True)(params)
    return y, J


def elasticities(fn, params: dict, *, mode: str = "fwd") -> Elasticities:
    """Exact (JAX) Jacobian and elasticities ∂ln y_i/∂ln p_j of `fn` at `params`.

    Args:
        fn: differentiable map from a dict of scalar inputs to a dict of scalar outputs (a
            `ReticleChain`, a `LoopChain`, or any function). It is compiled with
            `equinox.filter_jit`; an `equinox.Module` is traced, so new field values reuse the
            compiled code.
        params: {name: nonzero finite scalar}.
        mode: "fwd" (`jax.jacfwd`, cheap for few inputs; needed through `ReticleChain`'s ODE) or
            "rev" (`jax.jacrev`).
    Returns:
        `Elasticities`. Raises ValueError for a zero input, an output that is zero (its
        elasticity is undefined; use the Jacobian) and non-finite values or derivatives.
    """
    ensure_x64()
    if mode not in ("fwd", "rev"):
        raise ValueError(f"mode must be 'fwd' or 'rev', got {mode!r}")
    names = tuple(params)
    point = {}
    for k in names:
        v = check_range(params[k], k)
        if v.ndim != 0:
            raise ValueError(f"{k} must be a scalar, got shape {v.shape}")
        if float(v) == 0.0:
            raise ValueError(f"{k} = 0: an elasticity needs a nonzero input (use the Jacobian)")
        point[k] = v
    y, J = cacheable_call(_value_and_jacobian, fn, point, mode)
    order = getattr(fn, "outputs", None)  # the chains' own order; else jax's (sorted) one
    outputs = tuple(order) if order is not None and set(order) == set(y) else tuple(y)
    values = np.array([float(y[o]) for o in outputs])
    jac = np.array([[float(J[o][k]) for k in names] for o in outputs])
    p = np.array([float(point[k]) for k in names])
    for i, o in enumerate(outputs):
        if not (np.isfinite(values[i]) and np.all(np.isfinite(jac[i]))):
            raise ValueError(f"output {o!r} or its derivatives are not finite at {params}")
        if values[i] == 0.0:
            raise ValueError(
                f"output {o!r} is 0 at this point: its elasticities are undefined (use "
                "Elasticities.jacobian from a point where it is nonzero, or inspect the model)"
            )
    return Elasticities(names, outputs, p, values, jac, jac * p[None, :] / values[:, None])


def slip_sensitivities(
    D=WANG2022_TABLE1_D,
    G=CALIBRATED_G_M,
    mu_t=CALIBRATED_MU_T,
    load=WANG2022_REFERENCE_LOAD_N,
    a_max=WANG2022_A_MAX,
    **chain_kw,
) -> Elasticities:
    """Elasticities of F_s, K_τ, C_τ, z_max and the phase slips T4–T7 (wang2022 Tables 3–7).

    Inputs: D (Table 1), G (m), μ_t (Eq 17), normal load (N, Eq 28) and the stage's peak
    acceleration a_max (m/s²). Defaults: the Table-3 calibration at 4 kPa. `chain_kw` go to
    `ReticleChain` (sigma_s, M, gamma, mass, alpha, rtol, atol, max_steps). Forward mode through
    diffrax (`ForwardMode` adjoint): one solve carries the tangents of all five inputs.
    """
    chain = ReticleChain(**chain_kw)
    params = dict(D=D, G=G, mu_t=mu_t, load=load, a_max=a_max)
    chain.check(params)  # concrete checks first: a ValueError naming the input
    return elasticities(chain, params)


def hysteresis_sensitivities(
    D=WANG2022_TABLE1_D,
    G=CALIBRATED_G_M,
    mu_t=CALIBRATED_MU_T,
    load=WANG2022_REFERENCE_LOAD_N,
    a_max=WANG2022_A_MAX,
    A=DEFAULT_AMPLITUDE,
    *,
    element: str = "mindlin",
    **chain_kw,
) -> Elasticities:
    """Elasticities of wu2015's K̄, C̄ (and Ā, F_s, K_τ, C_τ, z_max) for the wang2022 contact.

    μN = F_s and K_d = K_τ of the contact at (D, G, μ_t, load, a_max); loop amplitude A (m,
    default 50 nm, see `LoopChain`). `element`: "mindlin" (default: it dissipates at any Ā and
    is the closer of the two to wu2015's measurements, docs/reproduction.md) or "jenkins" (C̄ = 0,
    so its elasticity is undefined, for Ā ≤ 1).
    """
    chain = LoopChain(element, **chain_kw)
    params = dict(D=D, G=G, mu_t=mu_t, load=load, a_max=a_max, A=A)
    chain.check(params)
    return elasticities(chain, params)
