"""The residuals of the full-chain fit of wang2022's measured slips (`fit_measured_slips`):
per cell (model − measured)/σ·√w, or in log form, through the Student-t ψ of the robust fit;
and, for a fit that shows its progress, the run that counts and reports its evaluations."""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import sys
import time

import diffrax as dfx
import jax
import jax.numpy as jnp

from .._chain import chain_phase_slips, to_physical
from .._fit._engine import FAILED_RESIDUAL
from ._student_t import student_t_residuals

PARAMETERS = ("D", "G_m", "mu_t", "sigma_s_Pa", "alpha")
"""Parameters of the full chain, in order: D, G (m), μ_t, σ_s (Pa) of the contact model (wang2022
Eqs 5–24) and the bristle exponent α of the pre-slip element (Eq 27)."""


# Each fit that shows its progress opens a run (`_shown_run`) whose number the residuals receive
# as an argument (a run-time value): its evaluations are counted and reported there, and fits
# side by side keep apart.
_RUNS: dict[int, dict] = {}
_NEXT_RUN = itertools.count(1)


@contextlib.contextmanager
def _shown_run(progress, size):
    """The run number of a fit showing `progress` (True: stderr; a callable: each line) over
    `size` cells, and its record ("n" evaluations, "last" trial point)."""
    number = next(_NEXT_RUN)
    _RUNS[number] = run = {"n": 0, "t0": time.perf_counter(), "size": size, "sink": progress}
    try:
        yield number, run
    finally:
        del _RUNS[number]


def _report(number, rss, phys):
    run = _RUNS.get(int(number))
    if run is None:
        return
    run["n"] += 1
    values = ", ".join(f"{k} {v:.6g}" for k, v in zip(PARAMETERS, phys.tolist()))
    line = (
        f"  fit_measured: evaluation {run['n']:3d}, RMS rel. residual "
        f"{math.sqrt(float(rss) / run['size']):.5f} at {values}; "
        f"{time.perf_counter() - run['t0']:.1f} s"
    )
    if callable(run["sink"]):
        run["sink"](line)
    else:
        print(line, file=sys.stderr, flush=True)


def _last_point(number, phys):
    run = _RUNS.get(int(number))
    if run is not None:
        run["last"] = phys.tolist()


def _residuals(theta, args, adjoint, shown=False, lu="lapack"):
    # ψ (`student_t_residuals`; identity at inv_nu = 0, s = 1) of (model − y)/σ·√w per cell, or of
    # (ln|model| − ln|y|)/σ·√w: the robust fit's σ, form, w or (ν, s) (one compiled solve for all)
    theta_full0, idx, mu_min_, y, sigma, sqrt_w, log_form, inv_nu, t_scale, loads, run = args
    phys = to_physical(theta_full0.at[idx].set(theta), PARAMETERS, mu_min_)
    if shown:  # host callbacks (never cached); "last" names the trial point if the chain raises
        jax.debug.callback(_last_point, run, jax.lax.stop_gradient(phys))
    slips, ok = chain_phase_slips(phys, loads, adjoint=adjoint, lu=lu)
    safe = jnp.where(slips == 0, 1.0, slips)  # double-where: ln|0| is not used
    d = jnp.where(log_form > 0.5, jnp.log(jnp.abs(safe)) - jnp.log(jnp.abs(y)), slips - y)
    psi = student_t_residuals(sqrt_w * d / sigma, t_scale, inv_nu)
    r = jnp.where(ok[:, None], psi, FAILED_RESIDUAL).ravel()
    if shown:
        jax.debug.callback(_report, run, jax.lax.stop_gradient(r @ r), jax.lax.stop_gradient(phys))
    return r


CHAIN_LU = ("lapack", "auto")
"""The slip solver's factorisations the chain fit offers (`Rodas4.lu`): LAPACK's LU (the
default) and the unrolled one (another rounding of the same arithmetic)."""

# The residual functions by (jac, progress shown, LU): module-level objects, so each compiles
# once; the quiet ones hold no host callback and are kept in the persistent compilation cache.
_RESIDUALS = {
    (jac, shown, lu): functools.partial(_residuals, adjoint=adjoint, shown=shown, lu=lu)
    for jac, adjoint in (("fwd", dfx.ForwardMode()), ("bwd", dfx.RecursiveCheckpointAdjoint()))
    for shown in (False, True)
    for lu in CHAIN_LU
}
