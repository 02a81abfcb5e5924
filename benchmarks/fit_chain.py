"""Benchmark: the full-chain fit of wang2022's 24 measured slips (issue 5 point 7).

tribojax: `fit_measured_slips()` (D, G, μ_t free; optimistix LM, forward mode through the custom-JVP
contact and diffrax), timed warm: the fit is run once to compile, then timed from the same start.
Baseline: the same chain written with NumPy/SciPy — `reference_contact` (tests/scipy_reference.py,
quad + brentq) at the six loads, the slip ODE by `solve_ivp` Radau (benchmarks/slip.py's
`scipy_phases`, exact sgn, stopped at the kinks) at the loosest rtol of a ladder whose phase
slips are within the JAX fit's own accuracy (5e-4 relative) of a tight JAX solution — inside
`scipy.optimize.least_squares` (MINPACK LM, default tolerances, forward differences: p + 1 chain
evaluations per Jacobian) over the same unconstrained coordinates θ as the JAX fit. Full mode
runs that SciPy fit from the same start to its own stop (it reaches the same optimum); --quick
times two SciPy chain evaluations and extrapolates by the evaluations a forward-difference LM
needs for the JAX fit's step count, (steps + 1)·(p + 1); the entry says which
("baseline_mode").
"""

import sys
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import scipy_reference as ref  # noqa: E402
import tribojax as tj  # noqa: E402
from slip import scipy_phases  # noqa: E402

FREE = tj.CHAIN_DEFAULT_FREE
DEFAULTS = dict(tj.CHAIN_DEFAULTS)
TARGET_S = 10.0
TARGET_RATIO = 20.0
# reference_contact refuses D > 2.9 for the plastic integral down to a' = 0 (its quad in ln a'
# overflows below the smallest double); the fitted D is 2.93. For D > 2.9 the benchmark starts
# that integral at 1e-250 of its upper limit: the part left out is (1e-250)^((3-D)/2) of it,
# measured against tribojax at Table 3's lightest and heaviest load: F_s, K_tau, C_tau within
# 2.1e-9 at D = 2.93 and 1.2e-5 at D = 2.96, far below the Radau slips' 1e-4.
PLASTIC_CUT = 1e-250
_distribution_integral = ref.distribution_integral


def _distribution_integral_cut(func, lo, hi, a_l, D):
    if lo is None and D > ref.MAX_D_LOWER_LIMIT_ZERO:
        lo = (a_l if hi is None else min(hi, a_l)) * PLASTIC_CUT
    return _distribution_integral(func, lo, hi, a_l, D)


ref.distribution_integral = _distribution_integral_cut  # this script only


def _reference_inputs():
    pair = tj.wang2022_pair(sigma_s=DEFAULTS["sigma_s_Pa"])
    return dict(
        M=1.0,
        gamma=1.5,
        E_star=float(pair.E_star),
        G_star=float(pair.G_star),
        H=float(pair.H),
        nu=float(pair.nu),
        sigma_s=DEFAULTS["sigma_s_Pa"],
        tangential_load=tj.WANG2022_TANGENTIAL_LOAD_N,
        mass=tj.WANG2022_RETICLE_MASS_KG,
    )


def scipy_chain(theta, rtol, loads, measured, kw):
    """SciPy residuals (model/measured − 1) for theta = (D, G, μ_t) at α = 1."""
    D, G, mu_t = theta
    rows = []
    for load in loads:
        c = ref.reference_contact(D=D, G=G, mu_t=mu_t, load=float(load), **kw)
        ph, _ = scipy_phases(c["F_s"], c["K_tau"], c["C_tau"], "Radau", rtol)
        rows.append(ph)
    return (np.array(rows) / measured - 1.0).ravel()


FD_STEP = 1e-2  # forward-difference step in θ: well above the Radau slips' 1e-4 noise


def scipy_fit(start, rtol, loads, measured, kw):
    """The SciPy fit: MINPACK LM over the same θ as `fit_measured_slips` (logit D and log G in
    the same box, μ_t > T/P), so that trial points stay inside the model's domain (in physical
    coordinates MINPACK steps to μ_t < T/P, where Mindlin's law fails). Jacobian by forward
    differences (step `FD_STEP` in θ), reusing the residual at the current point.
    Returns (OptimizeResult, chain evaluations, physical optimum)."""
    from scipy.optimize import least_squares

    mu_min = tj.chain_mu_min(loads)
    full0 = tj.chain_theta(
        [start.get(k, DEFAULTS[k]) for k in tj.CHAIN_PARAMETERS], tj.CHAIN_PARAMETERS, mu_min
    )
    n_free = len(FREE)

    def physical(th):
        full = np.concatenate([th, full0[n_free:]])
        phys = tj.chain_physical(jnp.asarray(full), tj.CHAIN_PARAMETERS, mu_min)
        return np.asarray(phys)[:n_free]

    cache, count = {}, [0]

    def f(th):
        key = th.tobytes()
        if key not in cache:
            count[0] += 1
            cache.clear()
            cache[key] = scipy_chain(physical(th), rtol, loads, measured, kw)
        return cache[key]

    def jac(th):
        r0 = f(th)
        cols = [
            (scipy_chain(physical(th + FD_STEP * e), rtol, loads, measured, kw) - r0) / FD_STEP
            for e in np.eye(th.size)
        ]
        count[0] += th.size
        return np.stack(cols, axis=1)

    sol = least_squares(f, full0[:n_free], jac=jac, method="lm")
    return sol, count[0], physical(sol.x)


def _matched_rtol(params, kw, loads):
    """Loosest Radau rtol within 5e-4 of a tight JAX solution at the lightest-damped load."""
    tight, _ = tj.chain_phase_slips(
        jnp.asarray(params), jnp.asarray(loads[-1:]), atol=1e-17, rtol=1e-9, max_steps=400_000
    )
    tight = np.asarray(tight)[0]
    D, G, mu_t = params[:3]
    c = ref.reference_contact(D=D, G=G, mu_t=mu_t, load=float(loads[-1]), **kw)
    for rtol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8):
        ph, _ = scipy_phases(c["F_s"], c["K_tau"], c["C_tau"], "Radau", rtol)
        err = float(np.max(np.abs(ph / tight - 1)))
        if err <= 5e-4:
            break
    return rtol, err


def run(quick=False):
    start = {k: DEFAULTS[k] for k in FREE}
    t0 = time.perf_counter()
    tj.fit_measured_slips(start)  # compile
    cold_s = time.perf_counter() - t0
    fit = tj.fit_measured_slips(start)
    warm_s = fit.wall_s
    steps, p = fit.fit.steps, len(FREE)
    loads = np.asarray(tj.wang2022_loads())
    measured = tj.wang2022_measured_slips()
    kw = _reference_inputs()
    params = np.array([DEFAULTS[k] for k in tj.CHAIN_PARAMETERS])
    rtol, scipy_err = _matched_rtol(params, kw, loads)
    if quick:
        x0 = np.array([start[k] for k in FREE])
        times = []
        for _ in range(2):
            t = time.perf_counter()
            scipy_chain(x0, rtol, loads, measured, kw)
            times.append(time.perf_counter() - t)
        n_eval = (steps + 1) * (p + 1)
        base_s = float(np.median(times)) * n_eval
        mode = f"extrapolated: median of 2 chain evaluations x {n_eval} = (steps+1)(p+1)"
        scipy_info = {}
    else:
        t = time.perf_counter()
        sol, nfev, x = scipy_fit(start, rtol, loads, measured, kw)
        base_s = time.perf_counter() - t
        mode = (
            "measured: scipy.optimize.least_squares (MINPACK lm, default tolerances) in the JAX "
            f"fit's coordinates from the same start, forward differences with step {FD_STEP} in θ"
        )
        scipy_info = {
            "scipy_chain_evaluations": nfev,
            "scipy_x": x.tolist(),
            "scipy_rms_rel": float(np.sqrt(np.mean(sol.fun**2))),
            "scipy_message": str(sol.message),
            "scipy_success": bool(sol.success),
        }
    common = dict(
        steps=steps,
        residual_evaluations=fit.evaluations,
        converged=fit.converged,
        rms_relative_residual=fit.rms_relative_residual,
        cold_s=cold_s,
        free=list(FREE),
    )
    return [
        dict(
            name="fit_chain_measured_warm",
            tribojax_s=warm_s,
            baseline="target 10 s",
            baseline_s=TARGET_S,
            ratio=TARGET_S / warm_s,
            target="<= 10 s warm (24 measured slips, D, G, mu_t free)",
            meets_target=bool(warm_s <= TARGET_S),
            **common,
        ),
        dict(
            name="fit_chain_vs_scipy_radau",
            tribojax_s=warm_s,
            baseline=f"scipy least_squares + reference_contact + solve_ivp Radau rtol {rtol:g}",
            baseline_s=base_s,
            ratio=base_s / warm_s,
            target=f"ratio >= {TARGET_RATIO:g}",
            meets_target=bool(base_s / warm_s >= TARGET_RATIO),
            baseline_mode=mode,
            scipy_max_rel_err_vs_tight=scipy_err,
            **common,
            **scipy_info,
        ),
    ]


if __name__ == "__main__":
    import json

    jax.config.update("jax_enable_x64", True)
    print(json.dumps(run(quick="--quick" in sys.argv), indent=2))
