"""wu2015's loop analysis of a measured hysteresis loop (`analyse_loop`: ω, A, K_eq and C_eq from
the first harmonics over whole cycles, wu2015 Section 5.3; K_d by wu2015 Eq 6)."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._checks import check_range
from .._friction._rate_independent import Jenkins, Mindlin
from .._io._hysteresis_loop import HysteresisLoop, cycle_starts

_ELEMENTS = {"jenkins": Jenkins, "mindlin": Mindlin}


@dataclasses.dataclass(frozen=True)
class LoopAnalysis:
    """wu2015's quantities of a loop (SI units): see `analyse_loop`."""

    cycles: int
    omega: float
    A: float
    mu_N: float
    k1: float
    k2: float
    K_d: float
    K_eq: float
    C_eq: float
    K_bar: float
    C_bar: float
    A_bar: float
    W: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def analyse_loop(loop: HysteresisLoop, *, window: float = 0.05) -> LoopAnalysis:
    """Amplitude, μN, K_d (wu2015 Eq 6), K_eq and C_eq (first harmonic) of a measured loop.

    Only whole cycles (between the first and last upward mean-crossing of u) are used.
    - ω = 2π·cycles/duration; A and the phase φ from the first harmonic of u, u ≈ A cos(ωt − φ).
    - K_eq = F_c/A, C_eq = −F_s/(Aω) from the force's first harmonic F_c cos θ + F_s sin θ,
      θ = ωt − φ; K̄ = K_eq/K_d, C̄ = πωC_eq/K_d (wu2015 Section 5.3).
    - k2 (unloading from u_max) and k1 (loading from u_min): slope at the reversal of a quadratic
      fitted to the samples within `window`·(peak-to-peak u) after it, averaged over cycles;
      K_d = (k1 + k2)/2 (wu2015 Eq 6). The quadratic removes the first-order bias of a chord on a
      curved (Mindlin) branch; the window must stay inside the stick zone (Jenkins: Ā < 1/window).
    - μN = half the mean peak-to-peak force per cycle (exact in gross slip; f* < μN in partial
      slip, and noise biases it up by about the noise amplitude).
    - W = ∮ f du over the whole cycles, per cycle (J).
    """
    check_range(window, "window", 0.0, 0.5)
    for name, x, unit in (("force", loop.f, "N"), ("displacement", loop.u, "m")):
        if np.ptp(x) == 0.0:
            raise ValueError(
                f"{loop.source}: the {name} is constant ({x[0]:g} {unit}) over the whole record; "
                "a hysteresis loop needs a varying displacement and force"
            )
    starts = cycle_starts(loop.t, loop.u)
    cycles = len(starts) - 1
    omega = 2.0 * np.pi * cycles / (starts[-1] - starts[0])
    keep = (loop.t >= starts[0]) & (loop.t <= starts[-1])
    t, u, f = loop.t[keep], loop.u[keep], loop.f[keep]
    basis = np.stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)], axis=1)
    cu = np.linalg.lstsq(basis, u, rcond=None)[0]
    cf = np.linalg.lstsq(basis, f, rcond=None)[0]
    A = float(np.hypot(cu[1], cu[2]))
    phi = np.arctan2(cu[2], cu[1])
    F_c = cf[1] * np.cos(phi) + cf[2] * np.sin(phi)
    F_s = -cf[1] * np.sin(phi) + cf[2] * np.cos(phi)
    edges = np.searchsorted(loop.t, starts)
    k1, k2, swings = [], [], []
    span = window * (u.max() - u.min())
    for a, b in zip(edges[:-1], edges[1:]):
        uu, ff = loop.u[a:b], loop.f[a:b]
        swings.append(ff.max() - ff.min())
        k2.append(_reversal_slope(loop.u, loop.f, a + int(np.argmax(uu)), span))
        k1.append(_reversal_slope(loop.u, loop.f, a + int(np.argmin(uu)), span))
    # a reversal the record ends on (no samples after it) gives no slope
    k1, k2 = ([k for k in ks if k is not None] for ks in (k1, k2))
    if not k1 or not k2:
        raise ValueError(
            f"{loop.source}: no reversal with samples after it to measure the "
            "stiffness K_d (wu2015 Eq 6)"
        )
    k1, k2 = float(np.mean(k1)), float(np.mean(k2))
    K_d = 0.5 * (k1 + k2)
    mu_N = 0.5 * float(np.mean(swings))
    if not (K_d > 0.0 and mu_N > 0.0):
        raise ValueError(
            f"{loop.source}: the reversal slopes give K_d = {K_d:g} N/m (wu2015 Eq 6) and the "
            f"force swing mu_N = {mu_N:g} N; both must be positive for a friction hysteresis loop"
        )
    K_eq = float(F_c / A)
    C_eq = float(-F_s / (A * omega))
    W = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u))) / cycles
    return LoopAnalysis(
        cycles=cycles,
        omega=float(omega),
        A=A,
        mu_N=mu_N,
        k1=k1,
        k2=k2,
        K_d=K_d,
        K_eq=K_eq,
        C_eq=C_eq,
        K_bar=K_eq / K_d,
        C_bar=float(np.pi * omega * C_eq / K_d),
        A_bar=A * K_d / mu_N,
        W=W,
    )


def _reversal_slope(u, f, r, span) -> float:
    """df/du at the reversal sample r, from a quadratic over the following samples within span;
    None when the record ends inside the span with fewer than 4 samples after r."""
    j = r + 1
    while j < len(u) and abs(u[j] - u[r]) <= span:
        j += 1
    du, df = u[r:j] - u[r], f[r:j]
    if len(du) < 4 and j == len(u):
        return None
    if len(du) < 4:
        raise ValueError(
            f"only {len(du)} samples within the slope window after the reversal at sample {r}; "
            "increase `window` or the sampling rate"
        )
    return float(np.polyfit(du, df, 2)[1])


def _loop_phase(loop: HysteresisLoop, analysis: LoopAnalysis):
    """Velocity sign of each sample of the steady loop, from the phase of u's first harmonic."""
    t = loop.t
    basis = np.stack([np.ones_like(t), np.cos(analysis.omega * t), np.sin(analysis.omega * t)], 1)
    cu = np.linalg.lstsq(basis, loop.u, rcond=None)[0]
    theta = np.mod(analysis.omega * t - np.arctan2(cu[2], cu[1]), 2.0 * np.pi)
    return np.where(theta < np.pi, -1.0, 1.0)
