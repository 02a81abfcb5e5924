"""The slip-run model: the pre-slip LuGre baseline (wang2022 Eq 27, α = 1) and six effects.

Baseline: `PreSlipLuGre(F_s, K_τ, C_τ, α=1)` in the two-body slip model (wang2022 Eq 27,
consistent reading, `tribojax.simulate_slip`), driven by the record's own acceleration
(`SlipRun.profile`, linear between samples), F_s, K_τ, C_τ fitted in log form.

Physics knobs of the baseline (null values in brackets), all inside one friction element:
    viscous      ν  [0]:  σ2 = |ν|·σ_ref ≥ 0 (viscous friction dissipates) added to the friction
                          force, σ2·v (LuGre σ2, Eq 25)
    stribeck     δ  [0]:  strength g(v) = F_s·(1 − δ·(1 − exp(−(v/v_s)²))) (Eq 25 with
                          F_c = (1 − δ)F_s, β = 2); δ > 0 is velocity weakening
    log10_v_s       [−5]: the Stribeck velocity scale (a nuisance, on a grid)
    load_coupling κ [0]:  normal load N(t) = N₀(1 + κ·a(t)/g), so F_s and K_τ scale by the
                          same factor (stage acceleration a, g = 9.8 m/s², wang2022 Eq 28)
and five knobs of a mode term added to the reading (`vibration`, `_mode`): amplitudes mode_q,
mode_qdot [0], mode_log_f (log f), mode_logit_zeta (ζ = ZETA_MAX/(1 + e^−u): a lightly damped
mode) and mode_static [1]. The element is `AugmentedPreSlip`; the model alone runs the paper's
`PreSlipLuGre`. The additive (measurement) effects are `tribojax.discovery._slip_effects`'.
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._dynamics._profiles import MeasuredProfile
from .._dynamics._slip import DEFAULT_ATOL, simulate_slip
from .._friction._lugre import PreSlipLuGre
from .._io._slip_run import SlipRun
from ._base import AbstractBaseline, RecordData
from ._modes import oscillator
from ._slip_element import AugmentedPreSlip
from ._start import C_TAU_START_FACTORS, c_tau_start, quasi_static_fit, slip_run_start

KNOBS = (
    "viscous",
    "stribeck",
    "log10_v_s",
    "load_coupling",
    "mode_q",
    "mode_qdot",
    "mode_log_f",
    "mode_logit_zeta",
    "mode_static",
)
ZETA_MAX = 0.3  # damping ratio bound of a structural mode (above: a low-pass of a(t), not a mode)
N_ODE_KNOBS = 4  # the knobs of the friction element; the mode's knobs act on the reading
# relative tolerance of the model's slip solve (atol scaled with it): at simulate_slip's 1e-6 a
# fit's cost moved by ±0.3 noise variances between neighbouring points and fits stalled where
# rounding left them; ±0.015 at 1e-7 (docs/discovery.md, "Stability")
ODE_RTOL = 1e-7
ODE_MAX_STEPS = 60_000  # ODE step budget of one solve of the model
# the least budget of a stalled fit's restarts and of a held-out check where a solve ran out
# (docs/discovery.md, "The slip model's ODE budget"); at rtol 1e-7 the model's own
ODE_RETRY_STEPS = 60_000
F_CAP_NEAR = 0.9  # F_s above this fraction of its bound: at the bound (not identified)
F_MAX_OVER_DRIVE = 100.0  # bound of F_s in units of m·max|a| (beyond: slip ∝ (m a/F_s)², tiny)
LOG10_VS_RANGE = (-12.0, 3.0)  # bound of log10 v_s (m/s) in the fit
VS_GRID = tuple(10.0 ** np.arange(-7.0, -3.4, 0.5))  # m/s, Stribeck velocity grid


def stage_travel(t, accel):
    """Stage velocity and travel (m/s, m) from sampled acceleration, trapezoid rule, from rest."""
    t, a = np.asarray(t, float), np.asarray(accel, float)
    dt = np.diff(t)
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * dt)])
    # exact for piecewise-linear a: x += v_k dt + (2a_k + a_{k+1}) dt²/6
    dx = v[:-1] * dt + (2 * a[:-1] + a[1:]) * dt**2 / 6.0
    return v, np.concatenate([[0.0], np.cumsum(dx)])


def slip_start(t, accel, slip, mass) -> np.ndarray:
    """Start values (F_s in N, K_τ in N/m, C_τ in N s/m) of the baseline:
    `tribojax.slip_run_start` (the quasi-static limit of wang2022 Eq 27) as an array."""
    s = slip_run_start(
        SlipRun(
            t=np.asarray(t, float),
            accel=np.asarray(accel, float),
            slip=np.asarray(slip, float),
            mass=float(mass),
            source="slip record",
        )
    )
    return np.array([s["F_s"], s["K_tau"], s["C_tau"]])


class SlipBaseline(AbstractBaseline):
    """wang2022's pre-slip model of one slip run (Eq 27, consistent reading): F_s, K_τ, C_τ
    fitted, the bristle exponent α held at `alpha` (1: the paper's law, discovery's baseline) or
    fitted as a fourth parameter (`free_alpha`). The ODE is solved at `rtol` (default
    `ODE_RTOL` = 1e-7, atol scaled with it) with `max_steps` steps."""

    kind: ClassVar[str] = "slip"
    knob_names: ClassVar[tuple] = KNOBS
    t: Array  # s
    accel: Array  # m/s²
    slip: Array  # m
    mass: Array  # kg
    noise_std: Array  # m, NaN when unknown
    start_values: Array  # (F_s, K_τ, C_τ) start
    sigma_ref: Array  # N s/m: unit of the viscous knob (the start C_τ)
    f_max: Array  # N: upper bound of F_s (`F_MAX_OVER_DRIVE` × m·max|a|)
    profile: MeasuredProfile
    t_end: float = eqx.field(static=True)  # s, the last sample (a solver setting)
    alpha: float = eqx.field(static=True, default=1.0)  # bristle exponent (start when free)
    free_alpha: bool = eqx.field(static=True, default=False)
    max_steps: int = eqx.field(static=True, default=ODE_MAX_STEPS)  # ODE steps of one solve
    rtol: float = eqx.field(static=True, default=ODE_RTOL)  # the ODE's relative tolerance

    @property
    def param_names(self):
        return ("F_s", "K_tau", "C_tau", "alpha")[: 4 if self.free_alpha else 3]

    @property
    def param_units(self):
        return ("N", "N/m", "N s/m", "")[: 4 if self.free_alpha else 3]

    def param_ranges(self):
        """F_s below the bound `f_max`, K_τ, C_τ (and α) > 0 (`physical`)."""
        return ((0.0, float(self.f_max)),) + ((0.0, np.inf),) * (len(self.param_names) - 1)

    def knob_null(self):
        return np.array([0.0, 0.0, -5.0, 0.0, 0.0, 0.0, np.log(50.0), 0.0, 1.0])

    def start(self):
        return self._theta_start(*np.asarray(self.start_values, dtype=float))

    def _theta_start(self, F, K, C):
        cap = np.log(float(self.f_max))
        u = min(np.log(F), cap - 0.7)  # invert the cap (F below half the bound)
        th = [cap - np.log(np.expm1(cap - u)), np.log(K), np.log(C)]
        return np.array(th + ([np.log(float(self.alpha))] if self.free_alpha else []))

    def restart(self, designs):
        """θ (baseline, then every design's strengths) of the quasi-static start fitted jointly
        with the designs' additive columns (`quasi_static_fit`): an effect that the baseline's
        own start read as slip (a drift larger than the slip) moves F_s and K_τ far from where
        the baseline fit stopped. None when a design moves a knob or has no columns."""
        if not designs or any(
            d.basis is None or d.knob_gain is not None or d.knob_set for d in designs
        ):
            return None
        cols = np.concatenate([np.asarray(d.basis, dtype=float) for d in designs], axis=1)
        slip = np.asarray(self.slip, dtype=float)
        fit = quasi_static_fit(float(self.mass) * np.asarray(self.accel, dtype=float), slip, cols)
        if fit is None:
            return None
        F, K, s = fit
        return np.concatenate([self._theta_start(F, K, c_tau_start(K, float(self.mass))), s])

    def starts(self):
        """The start and its C_τ multiplied by 0.1 and 10 (`C_TAU_START_FACTORS`), as
        `fit_slip_run` does: the cost has separate minima in C_τ."""
        one = [1.0] * (4 if self.free_alpha else 3)
        return [self.start() + np.log([1.0, 1.0, c, *one[3:]]) for c in C_TAU_START_FACTORS]

    def physical(self, theta):
        """θ → (F_s, K_τ, C_τ): F_s = exp(L − softplus(L − θ₀)), L = log `f_max` (≈ exp θ₀ below
        the bound, never above it: a fit that cannot see F_s stops at the bound instead of
        running it off), K_τ = exp θ₁, C_τ = exp θ₂ (α = exp θ₃ when free)."""
        cap = jnp.log(self.f_max)
        F_s = jnp.exp(cap - jax.nn.softplus(cap - theta[0]))
        return jnp.concatenate([F_s[None], jnp.exp(theta[1:])])

    def theta_of(self, values) -> np.ndarray:
        """θ of physical values (F_s, K_τ, C_τ[, α]): the inverse of `physical` (F_s below the
        cap `f_max`)."""
        v = np.asarray(values, dtype=float)
        cap = np.log(float(self.f_max))
        if not v[0] < float(self.f_max):
            raise ValueError(
                f"F_s = {v[0]:g} N is outside the model's range (0, {float(self.f_max):g})"
            )
        return np.concatenate([[cap - np.log(np.expm1(cap - np.log(v[0])))], np.log(v[1:])])

    def options(self):
        """{"alpha": the held bristle exponent, or "free" when it is fitted}."""
        return {"alpha": "free" if self.free_alpha else float(self.alpha)}

    def bristle_exponent(self, theta):
        """α: fitted (exp θ₃) or held."""
        return jnp.exp(theta[3]) if self.free_alpha else self.alpha

    def unidentified(self, values: dict, std_errors: dict) -> dict:
        """Parameters the record does not determine, with their bound: F_s within 10 % of
        `f_max` or with a standard error above its value (m·a_max/F_s too small to show it)."""
        F, sd = values["F_s"], std_errors["F_s"]
        fm = float(self.f_max)
        if F > F_CAP_NEAR * fm or not sd < F:
            return {
                "F_s": {
                    "lower_bound": float(min(F, fm) / 2 if not sd < F else F - 2 * sd),
                    "upper_bound": fm,
                    "unit": "N",
                }
            }
        return {}

    @property
    def atol(self) -> float:
        """The ODE's absolute tolerance of slip and deflection, m: `simulate_slip`'s default
        scaled with `rtol` (1e-15 m at 1e-6)."""
        return DEFAULT_ATOL * self.rtol / 1e-6

    def more_steps(self, factor: int = 1):
        """This model with `factor` × `ODE_RETRY_STEPS` ODE steps (at least its own)."""
        steps = max(self.max_steps, factor * ODE_RETRY_STEPS)
        return dataclasses.replace(self, max_steps=steps)

    def at_bound(self, theta) -> bool:
        """F_s within 10 % of `f_max` (`F_CAP_NEAR`): a reticle that hardly slips."""
        F_s = float(self.physical(np.asarray(theta, dtype=float))[0])
        return F_s > F_CAP_NEAR * float(self.f_max)

    def element(self, theta, knobs):
        F_s, K, C = self.physical(theta)[:3]
        # v_s within [1e-12, 1e3] m/s: a trial step of the fit cannot underflow it to 0
        log_vs = jnp.clip(knobs[2], LOG10_VS_RANGE[0], LOG10_VS_RANGE[1])
        return AugmentedPreSlip(
            F_s,
            K,
            C,
            jnp.abs(knobs[0]) * self.sigma_ref,
            knobs[1],
            10.0**log_vs,
            knobs[3],
            self.profile,
            alpha=self.bristle_exponent(theta),
        )

    def _simulate(self, element):
        """The slip solve of `element` on the record's drive, at the model's tolerances."""
        return simulate_slip(
            element,
            self.profile,
            self.mass,
            ts=self.t,
            t_end=self.t_end,
            adjoint=dfx.ForwardMode(),
            throw=False,
            max_steps=self.max_steps,
            rtol=self.rtol,
            atol=self.atol,
        )

    def _solve(self, theta, knobs):
        return self._simulate(self.element(theta, knobs))

    def _mode(self, km):
        """The mode term of the reading: A_q·q_s/rms(q_s) + A_q̇·q̇/rms(q̇), m, for knobs
        (A_q, A_q̇, log f, logit ζ/`ZETA_MAX`, s) (`oscillator`, the `Vibration` effect's
        shape), q_s = q + (1 − s)·a/ω²: s = 1 the full response q, s = 0 its dynamic part (the
        quasi-static deflection −a/ω² compensated, e.g. by a feed-forward)."""
        zeta = ZETA_MAX * jax.nn.sigmoid(km[3:4])
        omega = 2 * jnp.pi * jnp.exp(km[2:3])
        q = oscillator(self.t, self.accel, omega, zeta)[0]
        q = q.at[:, 0].add((1.0 - km[4]) * self.accel / omega[0] ** 2)
        rms = jnp.sqrt(jnp.mean(q * q, axis=0)) + 1e-300
        return q[:, 0] / rms[0] * km[0] + q[:, 1] / rms[1] * km[1]

    def predict(self, theta, knobs):
        return self._solve(theta, knobs[:N_ODE_KNOBS]).slip + self._mode(knobs[N_ODE_KNOBS:])

    def predict_null(self, theta, null=None):
        """The paper's element alone (`PreSlipLuGre(F_s, K_τ, C_τ, α)`, state z only): the
        model with every knob at its null, without the knob states (a smaller program)."""
        F_s, K, C = self.physical(theta)[:3]
        return self._simulate(PreSlipLuGre(F_s, K, C, self.bristle_exponent(theta))).slip

    def value_and_jacobian(self, theta, null=None):
        def f(tb):
            out = self.predict_null(tb)
            return out, out

        jb, value = jax.jacfwd(f, has_aux=True)(theta)
        return value, jb

    def value_and_jacobians(self, theta, knobs):
        """The ODE differentiated over θ and its own knobs only, the mode term over its knobs."""

        def ode(tb, kn):
            out = self._solve(tb, kn).slip
            return out, out

        def mode(km):
            out = self._mode(km)
            return out, out

        (jb, jk), value = jax.jacfwd(ode, argnums=(0, 1), has_aux=True)(theta, knobs[:N_ODE_KNOBS])
        jm, vm = jax.jacfwd(mode, has_aux=True)(knobs[N_ODE_KNOBS:])
        return value + vm, jb, jnp.concatenate([jk, jm], axis=1)

    def signals(self):
        t, a = np.asarray(self.t), np.asarray(self.accel)
        v, x = stage_travel(t, a)
        return {
            "time": t,
            "accel": a,
            "jerk": np.gradient(a, t),
            "stage_velocity": v,
            "stage_travel": x,
        }

    def data(self):
        sd = float(self.noise_std)
        return RecordData(
            y=np.asarray(self.slip),
            x=np.asarray(self.t),
            segment=np.zeros(self.t.shape[0], int),
            noise_std=sd if np.isfinite(sd) else None,
            x_label="time (s)",
            y_label="slip (m)",
        )


def slip_baseline(run, start=None, alpha=1.0) -> SlipBaseline:
    """The model of a slip record (`SlipRun`, or any object with t, accel, slip, mass and
    optionally noise_std). `start`: (F_s, K_τ, C_τ) start values, default `slip_start`;
    `alpha`: the bristle exponent held fixed (> 0), or None to fit it (from 1)."""
    t = np.asarray(run.t, float)
    if t[0] < 0 or np.any(np.diff(t) <= 0):
        raise ValueError("slip record: t must be >= 0 and strictly increasing")
    sv = slip_start(t, run.accel, run.slip, run.mass) if start is None else np.asarray(start)
    if sv.shape != (3,) or np.any(~(sv > 0)):
        raise ValueError(f"start = {sv} must be three positive numbers (F_s, K_tau, C_tau)")
    noise = getattr(run, "noise_std", None)
    record = run if isinstance(run, SlipRun) else SlipRun(t, run.accel, run.slip, run.mass)
    return SlipBaseline(
        t=jnp.asarray(t),
        accel=jnp.asarray(run.accel, dtype=jnp.float64),
        slip=jnp.asarray(run.slip, dtype=jnp.float64),
        mass=jnp.asarray(float(run.mass)),
        noise_std=jnp.asarray(np.nan if noise is None else float(noise)),
        start_values=jnp.asarray(sv, dtype=jnp.float64),
        sigma_ref=jnp.asarray(float(sv[2])),
        f_max=jnp.asarray(F_MAX_OVER_DRIVE * float(run.mass) * float(np.max(np.abs(run.accel)))),
        profile=record.profile(),
        t_end=float(t[-1]),
        alpha=1.0 if alpha is None else float(alpha),
        free_alpha=alpha is None,
    )
