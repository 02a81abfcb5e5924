"""Synthetic loop records with hidden effects, and stand-in loops that reproduce wu2015 Eq 7.

`hidden_effect_loop` generates a record from a model richer than the Jenkins baseline, with the
effect's strength fixed below (all at the wu2015 rig scale: μ = 0.3, N = 2.94 N, K_d from wu2015
Eq 5, 22 Hz; A0 = μN/K_d ≈ 0.66 µm):

* "none": the Jenkins element (wu2015 Eq 1);
* "microslip": the Mindlin/Koh element (wu2015 Eq 2, same μN and K_d) — full partial slip;
* "viscous_damping": Jenkins + c·u̇ with c·ω·A0 = 0.08·μN (a viscous force of 8 % of μN at
  Ā = 1, e.g. a damped load path in parallel with the contact);
* "normal_load_variation": Jenkins whose normal load follows the displacement,
  N(u) = N0(1 + 0.1·u/A) (±10 % over the stroke, e.g. a tilted flat), μN ∝ N and K_d ∝ N^0.7616
  (wu2015 Eq 5). Integrated here by its own sample loop (independent of the fitting code).

The drive is u = A·sin ωt, noise is white Gaussian on the force with sd `noise`·μN.

`eq7_standin_loop` builds, for one Ā, a Masing loop whose first-harmonic K̄ and C̄ equal wu2015
Eq 7 (the paper's linear fits of its measured K̄, C̄). wu2015 publishes no raw loops, so these are a
STAND-IN for them: a Masing loop (branches = the doubled backbone from the last reversal) with the
power backbone φ(x) = F·[1 − (1 − x/(p·X))^p] (X = F/K_d, so the initial slope is K_d as Eq 6
measures it; p = 1 is Jenkins, p = 1.5 Mindlin), whose shape p and saturation force F = s·μN are
solved for the two numbers. Exact solutions exist for 0.25 ≤ Ā ≤ 4 (at Ā = 4.5, p reaches its
Jenkins bound).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._checks import check_range
from .._contact._presets import wu2015_eq5_stiffness
from .._fit._solver import LevenbergMarquardt
from .._friction._rate_independent import Jenkins, Mindlin
from .._io._hysteresis_loop import HysteresisLoop, synthetic_loop
from .._presets import WU2015_EQ5_EXPONENT
from .._reproduce._wu2015 import eq7_curves

LOOP_EFFECTS = ("microslip", "viscous_damping", "normal_load_variation")
MU = 0.3  # friction coefficient of the synthetic rig (wu2015 gives none; a typical steel value)
VISCOUS_STRENGTH = 0.08  # c·ω·A0 / μN
LOAD_GRADIENT = 0.1  # β in N(u) = N0(1 + βu/A)
KD_EXPONENT = WU2015_EQ5_EXPONENT  # wu2015 Eq 5


def rig(normal_load: float = 2.94, frequency: float = 22.0):
    """(μN in N, K_d in N/m, A0 in m, ω in rad/s) of the synthetic rig at a normal load (N) and
    frequency (Hz): μ = 0.3, K_d from wu2015 Eq 5."""
    mu_N = MU * normal_load
    K_d = float(wu2015_eq5_stiffness(normal_load))
    return mu_N, K_d, mu_N / K_d, 2.0 * np.pi * frequency


def hidden_effect_loop(
    effect: str,
    noise: float,
    amplitude: float,
    seed: int,
    *,
    normal_load: float = 2.94,
    frequency: float = 22.0,
    cycles: int = 3,
    samples_per_cycle: int = 200,
    give_noise: bool = True,
) -> HysteresisLoop:
    """A loop record with one hidden effect (or "none"), generated from the richer model.

    Args:
        effect: "none" or one of `LOOP_EFFECTS` (strengths in the module docstring).
        noise: force-noise sd as a fraction of μN (≥ 0).
        amplitude: Ā = A/A0 of the drive u = A·sin ωt (> 0).
        seed: NumPy seed of the noise.
        give_noise: record the noise sd on the loop (as a sidecar would); False leaves it unknown.
    Returns:
        `HysteresisLoop` with `cycles` whole cycles, its normal load and frequency set.
    """
    if effect not in ("none", *LOOP_EFFECTS):
        raise ValueError(f"effect must be 'none' or one of {LOOP_EFFECTS}, got {effect!r}")
    noise = float(check_range(noise, "noise", 0.0, lo_open=False))
    amplitude = float(check_range(amplitude, "amplitude", 0.0))
    mu_N, K_d, A0, omega = rig(normal_load, frequency)
    A = amplitude * A0
    kw = dict(cycles=cycles, samples_per_cycle=samples_per_cycle)
    if effect == "normal_load_variation":
        clean = _load_varying_loop(mu_N, K_d, A, omega, **kw)
    else:
        cls = Mindlin if effect == "microslip" else Jenkins
        clean = synthetic_loop(cls(MU, normal_load, K_d), A, omega, **kw)
    f = clean.f
    if effect == "viscous_damping":
        c = VISCOUS_STRENGTH * mu_N / (omega * A0)
        f = f + c * A * omega * np.cos(omega * clean.t)
    f = f + noise * mu_N * np.random.default_rng(seed).standard_normal(f.shape)
    return HysteresisLoop(
        clean.t,
        clean.u,
        f,
        source=f"<hidden {effect}, seed {seed}>",
        normal_load=normal_load,
        frequency=frequency,
        noise_std=noise * mu_N if (give_noise and noise > 0) else None,
    )


def _load_varying_loop(mu_N, K_d, A, omega, *, cycles, samples_per_cycle):
    """Jenkins with N(u) = N0(1 + βu/A); one warm-up cycle dropped; synthetic_loop's grid."""
    n = cycles * samples_per_cycle + samples_per_cycle // 4 + 1
    k = np.arange(-samples_per_cycle, n)
    t = k / samples_per_cycle * (2.0 * np.pi / omega)
    u = A * np.sin(omega * t)
    s = 1.0 + LOAD_GRADIENT * u / A
    limit = mu_N * s / (K_d * s**KD_EXPONENT)  # slip displacement μN(u)/K_d(u)
    z, f = 0.0, np.zeros_like(u)
    for i in range(1, len(u)):
        z = min(max(z + u[i] - u[i - 1], -limit[i]), limit[i])
        f[i] = K_d * s[i] ** KD_EXPONENT * z
    keep = slice(samples_per_cycle, None)
    return HysteresisLoop(t[keep] - t[samples_per_cycle], u[keep], f[keep])


# --- wu2015 Eq 7 stand-in loops -------------------------------------------------------------

_M = 2048  # midpoint rule on the half cycle (the branch is smooth except at θ*)
_THETA = (np.arange(_M) + 0.5) * np.pi / _M


def _backbone(x, p, s):
    """Power backbone of a unit element (μN = 1, K_d = 1): s[1 − (1 − x/(p s))^p], s beyond."""
    q = 1.0 - x / (p * s)
    inside = q > 0.0
    return s * (1.0 - jnp.where(inside, jnp.where(inside, q, 1.0) ** p, 0.0))


def _masing_falling(u, A, p, s):
    """Falling branch of the steady Masing loop of the unit power-backbone element (Ā = A)."""
    return _backbone(A, p, s) - 2.0 * _backbone(0.5 * (A - u), p, s)


def _kc(A_bar, p, s):
    th = jnp.asarray(_THETA)
    f = _masing_falling(A_bar * jnp.cos(th), A_bar, p, s)
    f_c = 2.0 * jnp.mean(f * jnp.cos(th))
    f_s = 2.0 * jnp.mean(f * jnp.sin(th))
    return f_c / A_bar, -jnp.pi * f_s / A_bar  # K̄ = K_eq/K_d, C̄ = W/(K_d A²)


def _shape_residual(y, args):
    A_bar, K7, C7 = args[0], args[1], args[2]
    K, C = _kc(A_bar, 1.0 + jnp.exp(y[0]), jnp.exp(y[1]))
    return jnp.stack([K - K7, C - C7])


@jax.jit
def _solve_shape(y0, args):
    sol = optx.least_squares(
        _shape_residual,
        LevenbergMarquardt(1e-12, 1e-14),
        y0,
        args,
        throw=False,
        max_steps=200,
    )
    return sol.value, jnp.linalg.norm(_shape_residual(sol.value, args))


def eq7_standin_shape(A_bar: float) -> dict:
    """Backbone shape p and slip-force ratio s = F/μN whose Masing loop has Eq 7's K̄, C̄ at Ā.

    Solved by Levenberg–Marquardt in (log(p − 1), log s) from several starts; returns
    {"p", "s", "K_bar", "C_bar", "K_bar_eq7", "C_bar_eq7", "mismatch"} (mismatch = the remaining
    |(K̄, C̄) − Eq 7|, ~1e-16 where an exact solution exists).
    """
    A_bar = float(check_range(A_bar, "A_bar", 0.0, 4.5, hi_open=False))
    K7, C7 = (float(x) for x in eq7_curves(A_bar))
    args = jnp.array([A_bar, K7, C7])
    best = None
    for y0 in ([0.0, 0.0], [-2.0, 0.0], [1.0, -1.0], [-1.0, -0.5], [-0.5, -1.3]):
        y, miss = _solve_shape(jnp.array(y0), args)
        if best is None or float(miss) < best[0]:
            best = (float(miss), y)
        if best[0] < 1e-12:
            break
    miss, y = best
    p, s = 1.0 + float(np.exp(y[0])), float(np.exp(y[1]))
    K, C = (float(x) for x in _kc(A_bar, p, s))
    return dict(p=p, s=s, K_bar=K, C_bar=C, K_bar_eq7=K7, C_bar_eq7=C7, mismatch=miss)


def eq7_standin_loop(
    A_bar: float,
    *,
    normal_load: float = 2.94,
    frequency: float = 22.0,
    noise: float = 0.01,
    seed: int = 0,
    cycles: int = 3,
    samples_per_cycle: int = 200,
) -> HysteresisLoop:
    """A loop at Ā whose first-harmonic K̄, C̄ equal wu2015 Eq 7 (a stand-in for raw data).

    μN = 0.3·N, K_d from wu2015 Eq 5 (N in N), u = A·sin ωt with A = Ā·μN/K_d, ω = 2π·frequency;
    the force is the steady Masing loop of `eq7_standin_shape(Ā)` plus white noise of sd
    `noise`·μN (not recorded on the loop: the discovery estimates it). The shape is rate
    independent, so the frequency only sets the time axis.
    """
    shape = eq7_standin_shape(A_bar)
    mu_N, K_d, A0, omega = rig(normal_load, frequency)
    n = cycles * samples_per_cycle + samples_per_cycle // 4 + 1
    t = np.arange(n) / samples_per_cycle * (2.0 * np.pi / omega)
    theta = np.mod(omega * t - 0.5 * np.pi, 2.0 * np.pi)  # u = A cos θ = A sin ωt
    ubar = A_bar * np.cos(theta)
    falling = theta < np.pi
    fall = np.asarray(_masing_falling(jnp.asarray(ubar), A_bar, shape["p"], shape["s"]))
    rise = -np.asarray(_masing_falling(jnp.asarray(-ubar), A_bar, shape["p"], shape["s"]))
    f = mu_N * np.where(falling, fall, rise)
    f = f + noise * mu_N * np.random.default_rng(seed).standard_normal(n)
    return HysteresisLoop(
        t,
        A_bar * A0 * np.sin(omega * t),
        f,
        source=f"<Eq 7 stand-in, Ā={A_bar}>",
        normal_load=normal_load,
        frequency=frequency,
    )
