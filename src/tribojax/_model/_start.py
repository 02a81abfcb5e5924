"""Start values of a slip-run fit from the quasi-static limit of the pre-slip model.

When the body follows the stage, the friction force is F = m·a(t) and, with C_τ's transients
neglected, the bristle law (α = 1) dz/dΔx = 1 − sgn(v)·z/z_max with z = F/K_τ integrates in closed
form:

    Δx(t) = (F_s/K_τ) · Σ_k s_k·[ln(1 − s_k F_{k−1}/F_s) − ln(1 − s_k F_k/F_s)],  s_k = sgn(ΔF_k)

which is linear in 1/K_τ for fixed F_s. F_s comes from a 1-D search (1/K_τ by linear least
squares at each F_s). This is the one start heuristic of the slip-run model (`SlipBaseline`),
which `fit_slip_run` and `discover` share.
"""

from __future__ import annotations

import numpy as np

from .._io._slip_run import SlipRun

_ZETA_START = 0.1  # damping ratio of the C_τ start
# fits start from these multiples of the C_τ start and keep the lowest cost (see slip_run_start)
C_TAU_START_FACTORS = (1.0, 0.1, 10.0)


def _quasi_static_shape(force, F_s):
    """K_τ·Δx of the quasi-static α = 1 model along the force history (see module docstring)."""
    s = np.sign(np.diff(force))
    lo = np.log1p(-s * force[:-1] / F_s)
    hi = np.log1p(-s * force[1:] / F_s)
    return np.concatenate([[0.0], np.cumsum(s * F_s * (lo - hi))])


def quasi_static_fit(force, slip, columns=None):
    """(F_s, K_τ, c) of the quasi-static α = 1 model fitted to `slip` with friction force `force`
    (module docstring), jointly with additive columns (n, k) whose amplitudes c enter linearly:
    F_s searched on a log grid from 1.01 to 100 times max|force|, 1/K_τ and c by linear least
    squares at each F_s. None when no positive stiffness fits."""
    f_max = float(np.max(np.abs(force)))
    cols = np.zeros((len(slip), 0)) if columns is None else np.asarray(columns, dtype=float)
    best = None
    for F_s in f_max * np.geomspace(1.01, 100.0, 120):
        A = np.concatenate([_quasi_static_shape(force, F_s)[:, None], cols], axis=1)
        coef = np.linalg.lstsq(A, slip, rcond=None)[0]
        if not coef[0] > 0:
            continue
        cost = float(np.sum((A @ coef - slip) ** 2))
        if best is None or cost < best[0]:
            best = (cost, float(F_s), 1.0 / float(coef[0]), coef[1:])
    return None if best is None else best[1:]


def slip_run_start(run: SlipRun) -> dict:
    """Data-driven start values {F_s (N), K_τ (N/m), C_τ (N s/m)} for `fit_slip_run`.

    F_s and K_τ from the quasi-static α = 1 model fitted to the slip with F = m·a (module
    docstring, `quasi_static_fit`). C_τ = 2ζ√(K_τ m) with ζ = 0.1: the slip says little about
    C_τ before the fit, and its cost has separate minima in C_τ (docs/fitting.md), so
    `fit_slip_run` starts LM from this C_τ and from 0.1x and 10x it and keeps the lowest cost.
    Raises ValueError when the acceleration is zero throughout or the slip does not follow the
    force (no positive K_τ).
    """
    force = run.mass * run.accel
    if float(np.max(np.abs(force))) == 0:
        raise ValueError(f"{run.source}: the stage acceleration is zero throughout; nothing to fit")
    best = quasi_static_fit(force, run.slip)
    if best is None:
        raise ValueError(
            f"{run.source}: the slip does not follow the friction force m·a (no positive "
            "stiffness fits); check the sign convention Δx = x_stage − x_body and the units"
        )
    F_s, K, _ = best
    return {"F_s": F_s, "K_tau": K, "C_tau": c_tau_start(K, run.mass)}


def c_tau_start(K_tau, mass) -> float:
    """C_τ start 2ζ√(K_τ m), ζ = `_ZETA_START` (N s/m)."""
    return float(2.0 * _ZETA_START * np.sqrt(K_tau * mass))
