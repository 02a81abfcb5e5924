"""Profile likelihoods of the robust full-chain fit: what the measured slips determine.

For a chain parameter p_k and a grid of values, the profile log-likelihood is
ℓ_P(p_k) = max ℓ over the other free parameters and the scale with p_k held at the value (the
Student-t ℓ of `tribojax._reproduce._robust_fit`). Each grid point starts from its
neighbour's optimum with the robust optimum's EM weights (where the chain cannot be evaluated
at that start, from the optimum half-way to it first, up to `CONTINUATION_STEPS` times), then
takes a few rounds of the maximisation (`student_t_ml`). By Wilks' theorem 2(ℓ̂ − ℓ_P) is
approximately χ²₁, so the 95 % interval is where it stays below 3.84; a side where it never
gets there inside the grid is open: the data do not bound the parameter there.
A parameter that was fixed in the robust fit is profiled with the fit's free parameters free
(its ℓ_P then tells whether freeing it would pay).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from .._results import RESULTS
from ._chain_fit import fit_measured_slips
from ._chain_result import rms_relative
from ._robust_fit import RobustChainFit, residual_form, robust_fit_measured_slips

CHI2_95 = float(stats.chi2.ppf(0.95, 1))  # 3.84
CONTINUATION_STEPS = 3  # halvings towards a grid value the neighbour's optimum cannot reach


def _crossing(x, d, level):
    """The x where the piecewise-linear d(x) first reaches `level` walking away from d's
    minimum along `x` (sorted outward); None if it never does."""
    for i in range(1, len(x)):
        if d[i] >= level > d[i - 1]:
            return float(x[i - 1] + (level - d[i - 1]) * (x[i] - x[i - 1]) / (d[i] - d[i - 1]))
    return None


def profile_likelihood(
    robust: RobustChainFit,
    name: str,
    values,
    *,
    em_iterations: int = 3,
    target=None,
    loads=None,
    **fit_kw,
) -> dict:
    """Profile log-likelihood of chain parameter `name` over `values` (module docstring).

    Args:
        robust: the robust fit (noise model, ν, weights, optimum).
        name: a chain parameter ("D", "G_m", "mu_t", "sigma_s_Pa", "alpha").
        values: grid of physical values (need not contain the optimum; it is added).
        em_iterations: rounds of `student_t_ml` per grid point after the weighted fit.
        target, loads: as for the robust fit (default wang2022 Tables 4–7).
        fit_kw: passed to `fit_measured_slips`.
    Returns:
        dict: "parameter", "values" (sorted), "log_likelihood", "delta_2ll" (2(ℓ̂ − ℓ_P)),
        "rms_relative_residual_unflagged" (over the robust fit's unflagged cells), "converged",
        "interval_95" ([lo, hi], None for an open side), "determined" (both sides closed),
        "free" (the parameters refitted at each point).
    """
    if name not in robust.parameters:
        raise ValueError(f"name = {name!r} is not a chain parameter {tuple(robust.parameters)}")
    others = tuple(p for p in robust.free if p != name)
    if not others:
        raise ValueError("profiling needs at least one other free parameter")
    best = float(robust.parameters[name])
    grid = np.unique(np.append(np.asarray(values, dtype=float), best))
    y = robust.target_nm if target is None else np.asarray(target, dtype=float)
    form = residual_form(y, robust.noise, robust.floor_nm)
    keep = ~robust.flagged
    points = {best: (robust.log_likelihood, robust, True)}

    def weighted(at, value):
        return fit_measured_slips(
            dict(at, **{name: float(value)}),
            free=others,
            target=y,
            loads=loads,
            **form,
            weights=robust.weights,
            **fit_kw,
        )

    for side in (grid[grid > best], grid[grid < best][::-1]):  # outward from the optimum
        start = dict(robust.parameters)
        for v in side:
            first, here = weighted(start, v), start[name]
            for _ in range(CONTINUATION_STEPS):
                if first.result != RESULTS.model_failed_at_start:
                    break
                # the neighbour's optimum is outside the chain's domain at v: half-way first
                here = 0.5 * (here + float(v))
                half = weighted(start, here)
                if not half.converged:
                    break
                start = dict(half.parameters)
                first = weighted(start, v)
            fit = robust_fit_measured_slips(
                free=others,
                noise=robust.noise,
                floor_nm=robust.floor_nm,
                nu=robust.nu,
                target=y,
                loads=loads,
                initial=first,
                max_iterations=em_iterations,
                **fit_kw,
            )
            ok = bool(first.converged and fit.chain.converged)
            points[float(v)] = (fit.log_likelihood, fit, ok)
            start = dict(fit.parameters)
    x = np.array(sorted(points))
    ll = np.array([points[v][0] for v in x])
    d = 2.0 * (robust.log_likelihood - ll)
    rms = [rms_relative(points[v][1].model_nm, y, keep) for v in x]
    i0 = int(np.argmin(np.abs(x - best)))
    hi = _crossing(x[i0:], d[i0:], CHI2_95)
    lo = _crossing(x[: i0 + 1][::-1], d[: i0 + 1][::-1], CHI2_95)
    return {
        "parameter": name,
        "values": x.tolist(),
        "log_likelihood": ll.tolist(),
        "delta_2ll": d.tolist(),
        "rms_relative_residual_unflagged": rms,
        "converged": [points[v][2] for v in x],
        "interval_95": [lo, hi],
        "determined": lo is not None and hi is not None,
        "free": list(others),
        "best": best,
    }
