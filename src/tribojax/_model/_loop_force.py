"""The loop model's element (`LoopBaseline`), driven through a record's own displacement history
(any history, not only a clean sinusoid) and compared with the measured force at each sample.

One generalised element covers the baseline and every physical augmentation:

* an Iwan bank (parallel Jenkins elements, slip displacements y_j, stiffnesses k_j). One element
  (y = A0 = μN/K_d, k = K_d) is the Jenkins macroslip element (wu2015 Eq 1); `Mindlin`'s Iwan
  discretisation (`IwanBank.mindlin`, the same bank) is the Mindlin/Koh microslip element
  (wu2015 Eq 2);
* `microslip`: the force is (1 − w)·Jenkins + w·Mindlin with the same μN and K_d (both have initial
  slope K_d and gross-slip force μN); w = 0 is the baseline, w = 1 the full Mindlin law. The
  microslip bank's virgin curve μN[1 − (1 − x/(p·A0))^p] has the shape exponent p (`shape`):
  3/2 is Mindlin's, 2 a bank whose slip limits are spread uniformly (`power_unit_bank`);
* `normal_load_variation`: the normal load follows the displacement, N(u) = N0·(1 + β·u/A +
  γ·(u/A)²) (A: half the record's peak-to-peak u), so μN scales by s(u) = N(u)/N0 and K_d by
  s(u)^p (p = 0.7616, the exponent of wu2015 Eq 5, K_d ∝ N^0.7616, or p = 0: a stiffness that does
  not follow the load); every Iwan slider's limit scales with μN and every spring with K_d.
  β = γ = 0 is the baseline (γ: a load that peaks or dips at both ends of the stroke, e.g. a
  curved or wavy counter-face);
* `viscous_damping`: c·u̇ added to the force (u̇ from the record's displacement by central
  differences); c = 0 is the baseline;
* `backlash`: a clearance of total travel g (m) in series with the contact, of depth ε (—): every
  spring deflection z_j passes a dead zone, f_j = k_j·(z_j − ε·clip(z_j, −g/2, g/2)), and its
  slip limit widens to y_j·a(u) + ε·g/2. With ε = 1 (a clean clearance) and one element: after
  a reversal the force falls along K_d to zero, stays zero while the drive crosses the gap g, and
  rises along K_d on the far side (a rigid play in series with the Jenkins element); 0 < ε < 1
  leaves a soft stiffness (1 − ε)·K_d across the gap. ε = 0 is the baseline. For a bank each
  slider carries the clearance (exact for one element; for the Mindlin bank the slider of limit
  y_j < (1 − ε)g/2 slips below its own force k_j·y_j);
* `self_energizing` (exponent σ, —): the friction force q·F_slip (q ∈ [−1, 1] its share of the
  slip force F_slip = μN·s(u)) is passed through ψ_σ(q) = sign(q)·expm1(σ|q|)/expm1(σ), which
  keeps the slip force and zero force and bends the stick branch between them. A band brake's
  tension grows as e^{μφ} with the wrapped angle φ (capstan law, Euler–Eytelwein; the device of
  `BandBrake`): with φ taken to grow in proportion to the share of the slip force already
  carried, the force rises exponentially towards slip and falls steeply just after a reversal
  (σ > 0); σ < 0 is a softening stick branch. σ = 0 is the baseline (ψ = q).
* `direction_asymmetry` (a, —): the slip force in the positive direction μN·s·(1 + a), in the
  negative μN·s·(1 − a) (a self-energizing band is energized in one direction only, `BandBrake`'s
  F₊ ≠ F₋): the force q·F_slip becomes (1 + a·sign q)·q·F_slip. Unlike a force offset it leaves
  zero force (the clearance's plateau) at zero. a = 0 is the baseline.

Rate-independent updates are exact: z_j ← clip(z_j + Δu, −L_j, L_j), L_j = y_j·a(u) + ε·g/2,
f = Σ k_j·b(u)·(z_j − ε·clip(z_j, −g/2, g/2)) with a = s^(1−p), b = s^p (a = b = 1
without load variation).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import fail_if
from .._friction._rate_independent import IwanBank, power_unit_bank
from .._io._hysteresis_loop import HysteresisLoop, cycle_starts
from .._presets import WU2015_EQ5_EXPONENT
from ._loop_analysis import analyse_loop

KD_LOAD_EXPONENT = WU2015_EQ5_EXPONENT  # wu2015 Eq 5: K_d ∝ N^0.7616
N_IWAN = 128  # Iwan elements of the Mindlin law (interpolation error ~ 1/n² of μN)
MINDLIN_SHAPE = 1.5  # exponent of Mindlin's virgin curve (wu2015 Eq 2)


class LoopData(eqx.Module):
    """A loop record prepared for the drive model (SI units).

    Fields:
        u: displacement from the first upward mean-crossing on, relative to mid-stroke (m); the
            model is driven through it from rest.
        f: measured force at the fitted samples (N): those from the first reversal after the
            crossing on (the virgin loading is not fitted).
        v: velocity at the fitted samples (m/s, central differences of the record's u).
        A: half the peak-to-peak displacement (m), the scale of β.
        skip: index of the first fitted sample within `u` (static).
        index: index of each fitted sample in the original record.
        c_scale: viscous-coefficient scale F/V (N·s/m): half the peak-to-peak force over half the
            peak-to-peak velocity of the record.
        f_start: measured force at the first driven sample (N).
        loaded: (static) start in the state that carries `f_start` (`loaded_state`: the bank
            loaded from rest to that force) instead of at rest — a history that begins with the
            device under load (a band left engaged by the test before).
    """

    u: jax.Array
    f: jax.Array
    v: jax.Array
    A: jax.Array
    index: jax.Array
    c_scale: jax.Array
    f_start: jax.Array
    skip: int = eqx.field(static=True)
    loaded: bool = eqx.field(static=True, default=False)


INITIAL_STATES = ("rest", "measured")
REVERSAL_TRAVEL = 0.02  # a history's first reversal: the drive turns back by this share of ptp(u)


def first_reversal(u, travel: float = REVERSAL_TRAVEL) -> int:
    """Index of the first reversal of a displacement history u: the extreme reached before u first
    turns back by `travel`·ptp(u) after moving that far from its start (len(u) − 1 if never)."""
    u = np.asarray(u, dtype=float)
    tol = travel * float(np.ptp(u))
    hi, lo = np.maximum.accumulate(u), np.minimum.accumulate(u)
    down = (hi - u > tol) & (hi - u[0] > tol)  # went up, now turned down
    up = (u - lo > tol) & (u[0] - lo > tol)
    turned = np.flatnonzero(down | up)
    if not turned.size:
        return len(u) - 1
    i = int(turned[0])
    return int(np.argmax(u[: i + 1]) if down[i] else np.argmin(u[: i + 1]))


def prepare_loop(loop: HysteresisLoop, initial: str = "rest") -> LoopData:
    """`LoopData` of a record: a periodic loop is driven from its first upward crossing, a history
    (`periodic=False`) from its first sample; both are fitted from the first reversal on.
    `initial`: "rest" (the element starts unloaded) or "measured" (in the state that carries the
    force measured at the first driven sample)."""
    if initial not in INITIAL_STATES:
        raise ValueError(f"initial = {initial!r}: one of {list(INITIAL_STATES)} expected")
    t, u = loop.t, loop.u
    mid = 0.5 * (u.max() + u.min())
    if loop.periodic:
        first = int(np.searchsorted(t, cycle_starts(t, u)[0]))
        u_rel = u[first:] - mid
        omega = analyse_loop(loop).omega
        half = int(np.searchsorted(t[first:], t[first] + np.pi / omega))
        skip = int(np.argmax(u_rel[: max(half, 2)]))
    else:
        first, u_rel = 0, u - mid
        skip = first_reversal(u)
    v = np.gradient(u, t, edge_order=2)
    index = np.arange(first + skip, len(t))
    return LoopData(
        u=jnp.asarray(u_rel),
        f=jnp.asarray(loop.f[index]),
        v=jnp.asarray(v[index]),
        A=jnp.asarray(0.5 * (u.max() - u.min())),
        index=jnp.asarray(index),
        c_scale=jnp.asarray(0.5 * np.ptp(loop.f) / (0.5 * np.ptp(v))),
        f_start=jnp.asarray(loop.f[first]),
        skip=skip,
        loaded=initial == "measured",
    )


class LoopSpec(eqx.Module):
    """Parameters of the generalised loop model (array leaves; the baseline has w = β = c = 0).

    Fields: mu_N (gross-slip force, N, > 0), K_d (tangential stiffness, N/m, > 0), w (microslip
    weight, —; 0 Jenkins, 1 Mindlin), beta and gamma (normal load N(u) = N0(1 + βu/A + γ(u/A)²),
    —, N > 0 over the stroke), kd_exponent (p in K_d ∝ N^p, —; default wu2015 Eq 5's 0.7616),
    shape (exponent p of the microslip law's virgin curve μN[1 − (1 − x/(p·A0))^p], —, > 1;
    default 3/2, Mindlin; `power_unit_bank`), c (viscous coefficient, N·s/m), depth (backlash
    depth ε, —; 0 none, 1 a clean clearance), gap (backlash clearance g, total travel of the
    drive across it, m, ≥ 0).
    """

    mu_N: jax.Array
    K_d: jax.Array
    w: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    beta: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    gamma: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    kd_exponent: jax.Array = eqx.field(default_factory=lambda: jnp.asarray(KD_LOAD_EXPONENT))
    shape: jax.Array = eqx.field(default_factory=lambda: jnp.asarray(MINDLIN_SHAPE))
    c: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    depth: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    gap: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    energizing: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))
    asymmetry: jax.Array = eqx.field(default_factory=lambda: jnp.zeros(()))


SIGMA_MAX = 30.0  # |σ| of `self_energizing`: e^30 between the stick branch's ends is far beyond it
SIGMA_SERIES = 1e-3  # |σ| below which ψ_σ is its series in σ (exact to ~σ³)


def energize(q: jax.Array, sigma: jax.Array) -> jax.Array:
    """ψ_σ(q) = sign(q)·expm1(σ|q|)/expm1(σ) for q ∈ [−1, 1] (module docstring, `self_energizing`):
    odd, ψ(0) = 0, ψ(±1) = ±1, ψ_0(q) = q; smooth in σ through 0 (a series there)."""
    x = jnp.abs(q)
    small = jnp.abs(sigma) < SIGMA_SERIES
    s = jnp.where(small, 1.0, sigma)
    exact = jnp.expm1(s * x) / jnp.expm1(s)
    series = x * (1.0 + 0.5 * sigma * (x - 1.0) + sigma**2 * (x * x / 6.0 - x / 4.0 + 1.0 / 12.0))
    return jnp.sign(q) * jnp.where(small, series, exact)


S_MIN = 0.05  # floor of N(u)/N0 inside fits (check=False)


def loop_force(
    spec: LoopSpec, data: LoopData, *, microslip: bool = True, check: bool = True
) -> jax.Array:
    """Model force (N) at the fitted samples of `data` for the parameters `spec`.

    `microslip=False` (static) skips the Mindlin bank (use it when w is identically 0: the result
    is the same, at a fraction of the cost). `check=True` refuses β, γ that make N(u) ≤ 0 and a
    gap < 0 (ValueError, or equinox's runtime error under jit); `check=False` (inside fits, where
    a trial step may overshoot) floors N(u)/N0 at S_MIN instead. The bank starts at rest, or
    (`data.loaded`) in the state of the first measured force (`loaded_state`). References:
    wu2015 Eqs 1, 2, 5 (see the module docstring).
    """
    x = data.u / data.A
    s = 1.0 + spec.beta * x + spec.gamma * x * x
    if check:
        s = fail_if(
            s,
            jnp.any(s <= 0.0),
            "normal_load_variation: beta, gamma must keep N(u) = N0(1 + beta u/A + gamma (u/A)^2)"
            " > 0 over the stroke",
        )
    s_safe = jnp.where(s > S_MIN, s, S_MIN)
    b = s_safe**spec.kd_exponent
    a = s_safe / b
    A0 = spec.mu_N / spec.K_d
    if microslip:  # one bank: the Jenkins element (weight 1 − w) and the Mindlin bank (w)
        y_unit, k_unit = power_unit_bank(N_IWAN, spec.shape, xp=jnp)
        y = A0 * jnp.concatenate([jnp.ones(1), y_unit])
        k = jnp.concatenate([jnp.ones(1) * (1.0 - spec.w), spec.w * k_unit])
    else:
        y, k = A0 * jnp.ones(1), jnp.ones(1)
    if check:
        b = fail_if(b, spec.gap < 0.0, "backlash: gap (m) is outside the allowed range [0, inf)")
        b = fail_if(
            b,
            jnp.abs(spec.energizing) > SIGMA_MAX,
            f"self_energizing: energizing{_got(spec.energizing)} is outside the allowed "
            f"range [-{SIGMA_MAX:g}, {SIGMA_MAX:g}]",
        )
        b = fail_if(
            b,
            jnp.abs(spec.asymmetry) >= 1.0,
            f"direction_asymmetry: asymmetry{_got(spec.asymmetry)} is outside the "
            "allowed range (-1, 1)",
        )
    h = 0.5 * jnp.maximum(spec.gap, 0.0)
    widen = spec.depth * h / y  # per slider: limit scale y_j·a(u) + ε·h, floored at 0 (a trial
    # ε < 0 inside fits)
    sigma = jnp.clip(spec.energizing, -SIGMA_MAX, SIGMA_MAX)

    def spring(z):
        """Σ_j k_j·(z_j − ε·clip(z_j, ±h)) of deflections z (…, n): the clearance's dead zone,
        summed over the sliders."""
        return (z - spec.depth * jnp.clip(z, -h, h)) @ k

    def output(zk, bb, ss):
        """The force from the summed spring deflections zk at load factors bb = s^p, ss = s."""
        force = spec.K_d * bb * zk
        slip = spec.mu_N * ss  # the slip force μN·s(u)
        q = jnp.clip(force / slip, -1.0, 1.0)
        # the band's bend and asymmetry as a change of the force: exactly none at σ = a = 0,
        # also where a fit's trial step (w > 1, ε < 0) carries the force beyond the slip force
        bent = energize(q, sigma) * (1.0 + spec.asymmetry * jnp.sign(q))
        return force + slip * (bent - q)

    bank = IwanBank(y, k)
    z0 = jnp.zeros_like(y)
    if data.loaded:  # the state of the first measured force, reached by loading from rest
        z0 = loaded_state(
            lambda zz: output(spring(zz), b[0], s_safe[0]),
            y * jnp.maximum(a[0] + widen, 0.0),
            data.f_start,
        )

    def step(z, inp):
        du, a_i = inp
        z = bank.increment(z, du, jnp.maximum(a_i + widen, 0.0))
        return z, spring(z)

    if microslip:  # the sum over the sliders inside the scan, no (samples, sliders) array
        _, zk = jax.lax.scan(step, z0, (jnp.diff(data.u), a[1:]))
        zk = jnp.concatenate([spring(z0)[None], zk])
    else:  # one slider: the scan carries its deflection alone
        zk = spring(bank.deflections(data.u, jnp.maximum(a[:, None] + widen[None, :], 0.0), z0))
    return output(zk[data.skip :], b[data.skip :], s_safe[data.skip :]) + spec.c * data.v


BISECTIONS = 64  # halvings of the deflection interval: 2^-64 of it, below round-off


def loaded_state(force_of, limits, target) -> jax.Array:
    """Slider deflections z_j = clip(x, ±L_j) (m) of a bank loaded from rest to the deflection x
    whose force `force_of(z)` (N, non-decreasing in x) is `target` (N), clipped to the forces
    the bank can carry (±slip). x by bisection, then one Newton step from it with its value held
    fixed, so that dx/dθ = −(∂F/∂θ)/(∂F/∂x) (the implicit-function derivative; none inside a
    clearance, where ∂F/∂x = 0)."""
    top = jnp.max(limits)
    at = lambda x: force_of(jnp.clip(x, -limits, limits))  # noqa: E731
    goal = jnp.clip(target, at(-top), at(top))

    def halve(_, bounds):
        lo, hi = bounds
        mid = 0.5 * (lo + hi)
        low = at(mid) < goal
        return jnp.where(low, mid, lo), jnp.where(low, hi, mid)

    lo, hi = jax.lax.fori_loop(0, BISECTIONS, halve, (-top, top))
    xb = jax.lax.stop_gradient(0.5 * (lo + hi))
    value, slope = jax.jvp(at, (xb,), (jnp.ones_like(xb),))
    steep = slope > 1e-12 * jnp.abs(goal) / jnp.maximum(top, 1e-300)
    x = xb - jnp.where(steep, (value - goal) / jnp.where(steep, slope, 1.0), 0.0)
    return jnp.clip(x, -limits, limits)


def _got(x) -> str:
    """ " = <value>" for a concrete scalar (an eager check's message), "" under a trace."""
    return "" if isinstance(x, jax.core.Tracer) else f" = {float(x):g}"


def loop_branch(loop: HysteresisLoop) -> np.ndarray:
    """Branch of each sample: +1 loading (u rising), −1 unloading: the sign of the forward
    difference of a 5-point moving average of u (so a reversal sample belongs to the branch that
    leaves it; the last sample takes its predecessor's branch)."""
    u = np.convolve(loop.u, np.ones(5) / 5.0, mode="same")
    u[:2], u[-2:] = loop.u[:2], loop.u[-2:]
    step = np.diff(u)
    return np.where(np.append(step, step[-1]) >= 0.0, 1.0, -1.0)
