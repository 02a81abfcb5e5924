"""Slip side of discovery: the pre-slip LuGre baseline (wang2022 Eq 27, α = 1) and six effects.

Baseline: `PreSlipLuGre(F_s, K_τ, C_τ, α=1)` in the two-body slip model (wang2022 Eq 27,
consistent reading, `tribojax.simulate_slip`), driven by the record's own acceleration samples
(linear between samples, steps stopped at every sample: `record_profile`), F_s, K_τ, C_τ fitted
in log form.

Physics knobs of the baseline (null values in brackets), all inside one friction element:
    viscous      ν  [0]:  σ2 = ν·σ_ref added to the friction force, σ2·v (LuGre σ2, Eq 25)
    stribeck     δ  [0]:  strength g(v) = F_s·(1 − δ·(1 − exp(−(v/v_s)²))) (Eq 25 with
                          F_c = (1 − δ)F_s, β = 2); δ > 0 is velocity weakening
    log10_v_s       [−5]: the Stribeck velocity scale (a nuisance, on a grid)
    load_coupling κ [0]:  normal load N(t) = N₀(1 + κ·a(t)/g), so F_s and K_τ scale by the
                          same factor (stage acceleration a, g = 9.81 m/s²)
The element carries the time as a second state (τ' = 1) so that it can read a(τ).

Additive (measurement) effects, linear in their strengths:
    sensor_drift     c₀ + c₁P₁(s) + c₂P₂(s) + c₃P₃(s), Legendre in s = scaled time ∈ [−1, 1]
    position_error   ε·x_s(t), x_s = ∫∫a dt the stage travel from the record (fibre bending,
                     Abbe/cosine errors: a reading error proportional to travel)
    vibration        A₁·q(t) + A₂·q̇(t)/ω, q the response of a damped oscillator
                     q̈ + 2ζωq̇ + ω²q = −a(t) to the stage acceleration; ω, ζ on a grid
"""

from __future__ import annotations

from typing import ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import expm
from jaxtyping import Array

from .._dynamics._profiles import AbstractProfile, MeasuredProfile
from .._dynamics._slip import simulate_slip
from .._friction._element import AbstractFrictionElement
from .._friction._lugre import DEFAULT_VELOCITY_SCALE, _bristle_rate
from .._presets import STANDARD_GRAVITY_WANG2022 as G_ACC  # m/s², wang2022 Eq 28
from ._core import AbstractBaseline, AbstractEffect, DiscoveryData, EffectDesign, register_effect
from ._regions import noise_estimate

KNOBS = ("viscous", "stribeck", "log10_v_s", "load_coupling")
VS_GRID = tuple(10.0 ** np.arange(-7.0, -3.4, 0.5))  # m/s, Stribeck velocity grid


class AugmentedPreSlip(AbstractFrictionElement):
    """Pre-slip LuGre (wang2022 Eq 27, α = 1) with viscous, Stribeck and load-coupling terms.

        N(t)/N₀ = 1 + κ·a(t)/g,   K = K_τ·N/N₀,   g(v) = F_s·N/N₀·(1 − δ(1 − exp(−(v/v_s)²)))
        (κa/g and δ pass through x ↦ 0.9·tanh(x/0.9): equal to first order, bounded by 0.9)
        dz/dt = v·(1 − s(v)·K z/g(v)),   F_f = K z + C_τ dz/dt + σ2·v   (wang2022 Eqs 25–27)

    State (z, τ): bristle deflection (m) and time (s, τ' = 1) to read the stage acceleration.
    With σ2 = δ = κ = 0 it is `PreSlipLuGre(F_s, K_τ, C_τ, 1)`.
    """

    F_s: Array  # N, > 0
    K_tau: Array  # N/m, > 0
    C_tau: Array  # N s/m, >= 0
    sigma2: Array  # N s/m, signed
    stribeck: Array  # δ, signed (velocity weakening > 0)
    v_s: Array  # m/s, > 0
    kappa: Array  # load coupling per g, signed
    profile: AbstractProfile
    velocity_scale: float = eqx.field(static=True, default=DEFAULT_VELOCITY_SCALE)

    def _factor(self, tau):
        # 1 + κa/g, kept within (0.1, 1.9) (tanh, identical to first order) so that trial
        # points of a fit cannot make the load negative
        return 1.0 + 0.9 * jnp.tanh(self.kappa * self.profile.acceleration(tau) / G_ACC / 0.9)

    def initial_state(self):
        return (jnp.zeros_like(self.K_tau), jnp.zeros_like(self.K_tau))

    def _zdot(self, z, tau, v):
        m = self._factor(tau)
        delta = 0.9 * jnp.tanh(self.stribeck / 0.9)  # |δ| < 0.9, = δ to first order
        weak = 1.0 - delta * (1.0 - jnp.exp(-((v / self.v_s) ** 2)))
        g = self.F_s * m * weak
        return _bristle_rate(v, self.K_tau * m * z / g, 1.0, self.velocity_scale)

    def state_rate(self, state, velocity):
        z, tau = state
        return (self._zdot(z, tau, velocity), jnp.ones_like(tau))

    def force(self, state, velocity):
        z, tau = state
        m = self._factor(tau)
        return (
            self.K_tau * m * z + self.C_tau * self._zdot(z, tau, velocity) + self.sigma2 * velocity
        )


def stage_travel(t, accel):
    """Stage velocity and travel (m/s, m) from sampled acceleration, trapezoid rule, from rest."""
    t, a = np.asarray(t, float), np.asarray(accel, float)
    dt = np.diff(t)
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * dt)])
    # exact for piecewise-linear a: x += v_k dt + (2a_k + a_{k+1}) dt²/6
    dx = v[:-1] * dt + (2 * a[:-1] + a[1:]) * dt**2 / 6.0
    return v, np.concatenate([[0.0], np.cumsum(dx)])


def slip_start(t, accel, slip, mass) -> np.ndarray:
    """Data-driven start (F_s, K_τ, C_τ) from the hold and cruise slip levels.

    For α = 1 the quasi-static bristle law gives, at a hold of acceleration a after rest,
    Δx₁ = −z_max ln(1 − q) and, back at a = 0, Δx₂ − Δx₁ = −z_max ln(1 + q), q = m a/F_s
    (wang2022 Eqs 26–27 integrated along dz/dΔx = 1 ∓ z/z_max). The ratio of the two gives q,
    then z_max, F_s = m a/q, K_τ = F_s/z_max; C_τ from a damping ratio 0.2. Falls back to
    q = 0.6 when the record does not show the two levels.
    """
    t, a, y = (np.asarray(v, float) for v in (t, accel, slip))
    amax = float(np.max(np.abs(a)))
    if amax <= 0:
        raise ValueError("slip record: the stage acceleration is zero throughout")
    i_peak = int(np.argmax(np.abs(a)))
    sgn = np.sign(a[i_peak])
    hold = np.abs(a - a[i_peak]) < 0.05 * amax
    hold[: max(0, i_peak - 1)] &= np.cumsum(np.abs(a) > 0.95 * amax)[: max(0, i_peak - 1)] > 0
    first = np.flatnonzero(hold)
    end_hold = first[np.flatnonzero(np.diff(first) > 1)[0]] if np.any(np.diff(first) > 1) else (
        first[-1])  # fmt: skip
    seg = first[first <= end_hold]
    lvl1 = float(np.mean(y[seg[len(seg) // 3 :]]) - y[0]) * sgn
    after = np.flatnonzero((np.arange(t.size) > end_hold) & (np.abs(a) < 0.05 * amax))
    q = 0.6
    if after.size > 4 and lvl1 > 0:
        run = after[: np.argmax(np.diff(after) > 1) + 1] if np.any(np.diff(after) > 1) else after
        lvl2 = float(np.mean(y[run[len(run) // 3 :]]) - y[0]) * sgn
        drop = lvl1 - lvl2
        if drop > 0:
            ratio = lvl1 / drop
            qs = np.linspace(0.02, 0.98, 97)
            f = -np.log(1 - qs) / np.log(1 + qs)
            if f[0] < ratio < f[-1]:
                q = float(np.interp(ratio, f, qs))
    zmax = max(lvl1, 1e-12) / -np.log(1 - q)
    F_s = mass * amax / q
    K = F_s / zmax
    C = 2 * 0.2 * np.sqrt(K * mass)
    return np.array([F_s, K, C])


class SlipBaseline(AbstractBaseline):
    """wang2022's pre-slip baseline on one slip record (α = 1; F_s, K_τ, C_τ fitted)."""

    kind: ClassVar[str] = "slip"
    param_names: ClassVar[tuple] = ("F_s", "K_tau", "C_tau")
    param_units: ClassVar[tuple] = ("N", "N/m", "N s/m")
    knob_names: ClassVar[tuple] = KNOBS
    t: Array  # s
    accel: Array  # m/s²
    slip: Array  # m
    mass: Array  # kg
    noise_std: Array  # m, NaN when unknown
    start_values: Array  # (F_s, K_τ, C_τ) start
    sigma_ref: Array  # N s/m: unit of the viscous knob (the start C_τ)
    profile: MeasuredProfile
    t_end: float = eqx.field(static=True)  # s, the last sample (a solver setting)

    def knob_null(self):
        return np.array([0.0, 0.0, -5.0, 0.0])

    def start(self):
        return np.log(np.asarray(self.start_values))

    def physical(self, theta):
        return jnp.exp(theta)

    def element(self, theta, knobs):
        F_s, K, C = jnp.exp(theta[0]), jnp.exp(theta[1]), jnp.exp(theta[2])
        return AugmentedPreSlip(F_s, K, C, knobs[0] * self.sigma_ref, knobs[1],
                                10.0 ** knobs[2], knobs[3], self.profile)  # fmt: skip

    def _solve(self, theta, knobs):
        return simulate_slip(self.element(theta, knobs), self.profile, self.mass, ts=self.t,
                             t_end=self.t_end, adjoint=dfx.ForwardMode(), throw=False)  # fmt: skip

    def predict(self, theta, knobs):
        return self._solve(theta, knobs).slip

    def solver_ok(self, theta, knobs):
        return bool(_ok(self, theta, knobs))

    def data(self):
        sd = float(self.noise_std)
        return DiscoveryData(
            y=np.asarray(self.slip),
            x=np.asarray(self.t),
            segment=np.zeros(self.t.shape[0], int),
            noise_std=sd if np.isfinite(sd) else None,
            x_label="time (s)",
            y_label="slip (m)",
        )


@eqx.filter_jit
def _ok(baseline, theta, knobs):
    return baseline._solve(theta, knobs).ok


def record_profile(t, accel) -> MeasuredProfile:
    """The record's acceleration, linear between samples (the step controller handles the kinks).

    With Kvaerno5 (an implicit stage solve) forward-mode derivatives came out non-finite unless
    the solver stopped at every sample; with the default Rosenbrock solver (`Rodas4`, linear
    stages) they are finite without stops, and a 5,001-sample record costs ~30 ms per solve and
    ~70 ms per forward-mode Jacobian instead of ~150 and ~320 ms with a stop at every sample.
    """
    return MeasuredProfile(np.asarray(t, float), np.asarray(accel, float))


def slip_baseline(run, start=None) -> SlipBaseline:
    """The baseline for a slip record (`SlipRun`, or any object with t, accel, slip, mass and
    optionally noise_std). `start`: (F_s, K_τ, C_τ) start values, default `slip_start`."""
    t = np.asarray(run.t, float)
    if t[0] < 0 or np.any(np.diff(t) <= 0):
        raise ValueError("slip record: t must be >= 0 and strictly increasing")
    sv = slip_start(t, run.accel, run.slip, run.mass) if start is None else np.asarray(start)
    if sv.shape != (3,) or np.any(~(sv > 0)):
        raise ValueError(f"start = {sv} must be three positive numbers (F_s, K_tau, C_tau)")
    noise = getattr(run, "noise_std", None)
    return SlipBaseline(
        t=jnp.asarray(t),
        accel=jnp.asarray(run.accel, dtype=jnp.float64),
        slip=jnp.asarray(run.slip, dtype=jnp.float64),
        mass=jnp.asarray(float(run.mass)),
        noise_std=jnp.asarray(np.nan if noise is None else float(noise)),
        start_values=jnp.asarray(sv, dtype=jnp.float64),
        sigma_ref=jnp.asarray(float(sv[2])),
        profile=record_profile(t, run.accel),
        t_end=float(t[-1]),
    )


# ------------------------------------------------------------------------- effects


def _y_scale(baseline) -> float:
    d = baseline.data()
    if d.noise_std:
        return float(d.noise_std)
    return float(noise_estimate(d.y)[0]) or float(np.std(d.y)) or 1.0


def _unit_rms(col):
    rms = float(np.sqrt(np.mean(col**2)))
    return col / rms if rms > 0 else col


@register_effect
class SensorDrift(AbstractEffect):
    """Smooth additive drift of the slip reading: cubic (Legendre P0–P3) in time."""

    name: ClassVar[str] = "sensor_drift"
    kind: ClassVar[str] = "slip"
    degree: int = 3

    def designs(self, baseline):
        t = np.asarray(baseline.t)
        s = 2 * (t - t[0]) / (t[-1] - t[0]) - 1
        cols = np.polynomial.legendre.legvander(s, self.degree)
        ys = _y_scale(baseline)
        k = self.degree + 1
        return [EffectDesign(tuple(f"c{i}" for i in range(k)), ("m",) * k, np.full(k, ys),
                             basis=cols * ys)]  # fmt: skip


@register_effect
class PositionError(AbstractEffect):
    """Reading error proportional to stage travel, ε·x_s(t) (e.g. interferometer fibre bending)."""

    name: ClassVar[str] = "position_error"
    kind: ClassVar[str] = "slip"

    def designs(self, baseline):
        _, x = stage_travel(baseline.t, baseline.accel)
        ys = _y_scale(baseline)
        rms = float(np.sqrt(np.mean(x**2))) or 1.0
        return [EffectDesign(("epsilon",), ("m/m",), np.array([ys / rms]),
                             basis=(x / rms * ys)[:, None])]  # fmt: skip


@jax.jit
def _oscillator(t, a, omega, zeta):
    """q, q̇ of q̈ + 2ζωq̇ + ω²q = −a(t), a linear between samples (exact discretisation)."""
    A = jnp.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    M = jnp.zeros((4, 4)).at[:2, :2].set(A).at[1, 2].set(-1.0).at[2, 3].set(1.0)
    h = jnp.diff(t)
    E = jax.vmap(lambda hh: expm(M * hh))(h)
    slope = jnp.diff(a) / h

    def step(x, inp):
        Ek, ak, sk = inp
        y = Ek @ jnp.concatenate([x, jnp.stack([ak, sk])])
        return y[:2], y[:2]

    _, xs = jax.lax.scan(step, jnp.zeros(2), (E, a[:-1], slope))
    return jnp.concatenate([jnp.zeros((1, 2)), xs])


def _golden_max(f, lo, hi, iters=18):
    """Maximiser of a unimodal f on [lo, hi] (golden section)."""
    g = (np.sqrt(5) - 1) / 2
    a, b = lo, hi
    c, d = b - g * (b - a), a + g * (b - a)
    fc, fd = f(c), f(d)
    for _ in range(iters):
        if fc > fd:
            b, d, fd = d, c, fc
            c = b - g * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + g * (b - a)
            fd = f(d)
    return (c, fc) if fc > fd else (d, fd)


@register_effect
class Vibration(AbstractEffect):
    """A lightly damped structural mode excited by the stage acceleration, seen in the reading.

    Additive A₁q + A₂q̇/ω (two signed amplitudes set the phase); natural frequency and damping
    ratio on a grid (default 40 frequencies between 3/T and 0.4 × the sampling rate, capped at
    500 Hz, × ζ ∈ {0.01, 0.03, 0.1}), then refined around the best grid point by golden-section
    searches on the score (log f within one grid step, then log ζ within a factor 3).
    """

    name: ClassVar[str] = "vibration"
    kind: ClassVar[str] = "slip"
    zetas: tuple = (0.01, 0.03, 0.1)
    n_freq: int = 40

    def design(self, baseline, f, z):
        ys = _y_scale(baseline)
        q = np.asarray(_oscillator(baseline.t, baseline.accel, 2 * np.pi * f, z))
        cols = np.stack([_unit_rms(q[:, 0]), _unit_rms(q[:, 1])], 1) * ys
        return EffectDesign(("A_q", "A_qdot"), ("m", "m"), np.full(2, ys), basis=cols,
                            nuisance={"f_Hz": float(f), "zeta": float(z)},
                            n_nuisance=2)  # fmt: skip

    def frequencies(self, baseline):
        t = np.asarray(baseline.t)
        fs = (t.size - 1) / (t[-1] - t[0])
        return np.geomspace(3.0 / (t[-1] - t[0]), min(0.4 * fs, 500.0), self.n_freq)

    def designs(self, baseline):
        return [self.design(baseline, f, z) for f in self.frequencies(baseline)
                for z in self.zetas]  # fmt: skip

    def refine(self, baseline, design, score):
        f0, z0 = design.nuisance["f_Hz"], design.nuisance["zeta"]
        step = float(np.log(self.frequencies(baseline)[1] / self.frequencies(baseline)[0]))
        lf, _ = _golden_max(lambda u: score(self.design(baseline, np.exp(u), z0)),
                            np.log(f0) - step, np.log(f0) + step)  # fmt: skip
        lz, _ = _golden_max(lambda u: score(self.design(baseline, np.exp(lf), np.exp(u))),
                            np.log(z0 / 3), np.log(min(3 * z0, 0.7)), iters=12)  # fmt: skip
        return self.design(baseline, np.exp(lf), np.exp(lz))


def _knob_design(knob, strength, unit, scale, knob_set=None, nuisance=None, n_nuisance=0):
    gain = np.zeros((len(KNOBS), 1))
    gain[KNOBS.index(knob), 0] = 1.0
    return EffectDesign((strength,), (unit,), np.array([scale]), knob_gain=gain,
                        knob_set=knob_set or {}, nuisance=nuisance or {},
                        n_nuisance=n_nuisance)  # fmt: skip


@register_effect
class LoadCoupling(AbstractEffect):
    """Normal load (hence F_s and K_τ) varying with stage acceleration: N = N₀(1 + κa/g)."""

    name: ClassVar[str] = "load_coupling"
    kind: ClassVar[str] = "slip"

    def designs(self, baseline):
        return [_knob_design("load_coupling", "kappa", "1 (per g)", 1.0)]


@register_effect
class Stribeck(AbstractEffect):
    """Velocity weakening g(v) = F_s(1 − δ(1 − exp(−(v/v_s)²))); v_s on a grid (`VS_GRID`)."""

    name: ClassVar[str] = "stribeck"
    kind: ClassVar[str] = "slip"

    def designs(self, baseline):
        return [
            _knob_design(
                "stribeck",
                "delta",
                "1",
                1.0,
                knob_set={"log10_v_s": np.log10(vs)},
                nuisance={"v_s_m_per_s": vs},
                n_nuisance=1,
            )  # fmt: skip
            for vs in VS_GRID
        ]


@register_effect
class ViscousFriction(AbstractEffect):
    """A viscous term σ2·v in the friction force (LuGre σ2, wang2022 Eq 25)."""

    name: ClassVar[str] = "viscous_friction"
    kind: ClassVar[str] = "slip"

    def designs(self, baseline):
        return [_knob_design("viscous", "sigma2", "N s/m", float(baseline.sigma_ref))]
