"""Independent hidden-effect loop records for the discovery study (issue 14).

Nothing here is shared with tribojax's loop models or candidate effects (`_model._loop_force`,
`_loop_synthetic`): the force is computed by this module's own NumPy code, sample by sample on a
time grid 8× finer than the record (then decimated), with its own parameterisations:

- the contact: a force-form stop operator F ← clip(F + k·Δu, −F_s, F_s) (a Jenkins element; the
  clean record);
- microslip, "mindlin": Mindlin's law in closed form — backbone F_s[1 − (1 − δ/δ*)^(3/2)],
  δ* = 3F_s/(2k), branches from the last reversal by Masing's rule — mixed with the Jenkins force
  at weight w; "iwan_power": a parallel bank of 400 equal-stiffness sliders whose slip
  displacements have density ∝ x^χ on (0, x_max] plus a share S at x_max (Segalman's form);
- viscous_damping: "linear" c·u̇, "power_0.6" c·|u̇|^0.6·sgn(u̇);
- normal_load_variation: N(u)/N0 = 1 + β·u/A ("linear") or 1 + γ·(u/A)² ("quadratic"), slip force
  ∝ N; the "_stiffness" shapes make k ∝ (N/N0)^e as well, the others keep k constant;
- out of the vocabulary: "channel_lag" (the force channel delayed by τ), "stiffness_hardening"
  (stick force k·z·(1 + h·(k·z/F_s)²)), "velocity_weakening" (slip force
  F_s·(r + (1 − r)·exp(−|u̇|/v_s))), "mains_pickup" (a 50 Hz line in the force reading).

Each record draws its rig from its seed: N0, μ, k, the drive frequency and Ā = A·k/F_s, all from
ranges, none on a tribojax grid. The drive is u = A·sin ωt; one warm-up cycle is dropped and the
record keeps 3 cycles of 200 samples (+ a quarter and one sample, the length of the library's
synthetic loops). Force noise: white, sd = noise·F_s with "low" 0.6 % and "high" 1.8 % of F_s,
recorded on the loop (a sidecar) or not.
"""

from __future__ import annotations

import dataclasses

import numpy as np

import tribojax as tj

CYCLES, SPC, FINE = 3, 200, 8  # recorded cycles, samples per cycle, fine steps per sample
NOISE = {"low": 0.006, "high": 0.018}  # force-noise sd / F_s
IN_VOCAB = {
    "microslip": ("mindlin", "iwan_power"),
    "viscous_damping": ("linear", "power_0.6"),
    "normal_load_variation": ("linear", "linear_stiffness", "quadratic", "quadratic_stiffness"),
}
OUT_OF_VOCAB = ("channel_lag", "stiffness_hardening", "velocity_weakening", "mains_pickup")


@dataclasses.dataclass(frozen=True)
class LoopRecordSpec:
    """One loop record: effect ("clean", an `IN_VOCAB` key or an `OUT_OF_VOCAB` name), shape,
    noise level, sidecar noise or not, seed (which also draws the rig and the strength)."""

    effect: str
    shape: str
    noise: str
    sidecar: bool
    seed: int
    kind = "loop"

    @property
    def label(self) -> str:
        return (
            f"loop:{self.effect}/{self.shape} {self.noise}"
            f"{'' if self.sidecar else ' est'} s{self.seed}"
        )


def _stop(u, k, limit):
    """Force-form stop operator along u: F ← clip(F + k_i·Δu, −L_i, L_i) (k, limit per step)."""
    k = np.broadcast_to(k, u.shape)
    limit = np.broadcast_to(limit, u.shape)
    f = np.zeros_like(u)
    for i in range(1, u.size):
        f[i] = min(max(f[i - 1] + k[i] * (u[i] - u[i - 1]), -limit[i]), limit[i])
    return f


def _mindlin_masing(u, k, F_s):
    """Mindlin's backbone F_s[1 − (1 − δ/δ*)^1.5], δ* = 1.5 F_s/k, by Masing's rule from the last
    reversal (virgin curve from rest)."""
    d_star = 1.5 * F_s / k

    def phi(d):
        return F_s * (1.0 - np.clip(1.0 - d / d_star, 0.0, None) ** 1.5)

    f = np.zeros_like(u)
    u_r, f_r, sgn, virgin = u[0], 0.0, 1.0, True
    for i in range(1, u.size):
        step = np.sign(u[i] - u[i - 1])
        if step != 0 and step != sgn:  # reversal at the previous sample
            u_r, f_r, sgn, virgin = u[i - 1], f[i - 1], step, False
        d = abs(u[i] - u_r)
        f[i] = f_r + sgn * (phi(d) if virgin else 2.0 * phi(0.5 * d))
    return f


def _iwan_power(u, k, F_s, chi, share, n=400):
    """Parallel bank of n sliders, stiffness k/n each, slip displacements of density ∝ x^chi on
    (0, x_max] (a fraction 1 − share) and at x_max (share); total slip force F_s."""
    p = (np.arange(n) + 0.5) / n
    q = np.minimum(p / max(1.0 - share, 1e-12), 1.0)
    x = np.where(p < 1.0 - share, q ** (1.0 / (chi + 1.0)), 1.0)
    x = x * F_s / (k * np.mean(x))  # Σ (k/n)·x_i = F_s
    ki = k / n
    fi = np.zeros(n)
    f = np.zeros_like(u)
    for i in range(1, u.size):
        fi = np.clip(fi + ki * (u[i] - u[i - 1]), -ki * x, ki * x)
        f[i] = fi.sum()
    return f


def _hardening(u, k, F_s, h):
    """Stick force g(z) = k·z·(1 + h(kz/F_s)²) of an elastic deflection z ← clip(z + Δu, ±z_L),
    g(z_L) = F_s."""
    r = np.roots([h, 0.0, 1.0, -1.0])  # k z_L / F_s solves h x³ + x = 1
    z_l = float(np.real(r[np.isreal(r)][0])) * F_s / k
    z = _stop(u, 1.0, z_l)
    return k * z * (1.0 + h * (k * z / F_s) ** 2)


def rig(rng):
    """(N0 in N, μ, k in N/m, frequency in Hz, Ā) of one record, drawn from `rng`."""
    return (
        rng.uniform(1.5, 6.0),
        rng.uniform(0.2, 0.45),
        10 ** rng.uniform(6.0, 6.8),
        rng.uniform(7.0, 40.0),
        rng.uniform(1.4, 4.2),
    )


def make_loop_record(spec: LoopRecordSpec, *, with_noise: bool = True) -> tj.HysteresisLoop:
    """The loop record of `spec` (seed spec.seed); `with_noise=False`: the same without noise."""
    rng = np.random.default_rng(spec.seed)
    N0, mu, k, freq, A_bar = rig(rng)
    F_s = mu * N0
    A = A_bar * F_s / k
    omega = 2.0 * np.pi * freq
    n_rec = CYCLES * SPC + SPC // 4 + 1
    fine = np.arange(-SPC * FINE, (n_rec - 1) * FINE + 1)  # one warm-up cycle before t = 0
    t = fine / (SPC * FINE) / freq
    u = A * np.sin(omega * t)
    v = A * omega * np.cos(omega * t)
    e, sh = spec.effect, spec.shape
    f = None
    if e == "microslip" and sh == "mindlin":
        w = rng.uniform(0.5, 0.95)
        f = (1.0 - w) * _stop(u, k, F_s) + w * _mindlin_masing(u, k, F_s)
    elif e == "microslip":
        f = _iwan_power(u, k, F_s, chi=rng.uniform(-0.6, -0.2), share=rng.uniform(0.2, 0.5))
    elif e == "normal_load_variation":
        if sh.startswith("linear"):
            s = 1.0 + rng.choice([-1, 1]) * rng.uniform(0.08, 0.18) * u / A
        else:
            s = 1.0 + rng.choice([-1, 1]) * rng.uniform(0.12, 0.3) * (u / A) ** 2
        k_u = k * s ** rng.uniform(0.45, 1.0) if sh.endswith("stiffness") else k
        f = _stop(u, k_u, F_s * s)
    elif e == "stiffness_hardening":
        f = _hardening(u, k, F_s, rng.uniform(0.5, 1.0))
    elif e == "velocity_weakening":
        r, v_s = rng.uniform(0.75, 0.88), rng.uniform(0.15, 0.5) * A * omega
        f = _stop(u, k, F_s * (r + (1.0 - r) * np.exp(-np.abs(v) / v_s)))
    else:
        f = _stop(u, k, F_s)
    if e == "viscous_damping":
        s_v = rng.uniform(0.05, 0.12) * F_s  # force at the peak velocity
        if sh == "linear":
            f = f + s_v * v / (A * omega)
        else:
            f = f + s_v * np.sign(v) * np.abs(v / (A * omega)) ** 0.6
    keep = slice(SPC * FINE, None, FINE)
    t_rec, u_rec, f_rec = t[keep], u[keep], f[keep]
    if e == "channel_lag":
        tau = rng.uniform(0.01, 0.025) / freq
        f_rec = np.interp(t_rec - tau, t, f)
    elif e == "mains_pickup":
        f_rec = f_rec + rng.uniform(0.02, 0.04) * F_s * np.sin(
            2 * np.pi * 50.0 * t_rec + rng.uniform(0, 2 * np.pi)
        )
    sd = NOISE[spec.noise] * F_s
    f_rec = f_rec + with_noise * rng.normal(0.0, sd, f_rec.size)
    return tj.HysteresisLoop(
        t_rec,
        u_rec,
        f_rec,
        source=spec.label,
        normal_load=N0,
        frequency=freq,
        noise_std=sd if spec.sidecar else None,
    )


def loop_study_specs() -> list[LoopRecordSpec]:
    """The loop records of the study: every in-vocabulary effect × shape at both noise levels,
    with and without sidecar noise; clean records; out-of-vocabulary records."""
    specs, seed = [], 2000
    for e, shapes in IN_VOCAB.items():
        per_shape = 4 if len(shapes) == 2 else 3
        for sh in shapes:
            for j in range(per_shape):
                seed += 1
                specs.append(LoopRecordSpec(e, sh, ("low", "high")[j % 2], j in (0, 3), seed))
    for j in range(6):
        seed += 1
        specs.append(LoopRecordSpec("clean", "-", ("low", "high")[j % 2], j < 3, seed))
    for e in OUT_OF_VOCAB:
        for j in range(3):
            seed += 1
            specs.append(LoopRecordSpec(e, "-", ("low", "high")[j % 2], j != 1, seed))
    return specs
