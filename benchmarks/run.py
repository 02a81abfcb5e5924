"""Benchmarks of the tribojax fractal contact model against the SciPy reference.

    python benchmarks/run.py --out DIR

writes DIR/benchmarks.json (a list of {"name", "tribojax_s", "baseline", "baseline_s", "ratio",
"target", "meets_target", ...}; ratio = baseline_s / tribojax_s) and prints a table. Every number
comes from this one run. Timings are warm: each jitted function is compiled (and run once)
before timing, then the median of many calls is taken, each call ending in
`jax.block_until_ready`. The baseline is the independent quad + brentq implementation in
tests/scipy_reference.py (imported from the repository's tests/ folder).

Inputs: the calibrated-like wang2022 contact (docs/reproduction.md, "wang2022: Table 3
calibration"): D = 2.8821, G = 7e-8 m, M = 2, γ = 1.5, the Table 2 pair with σ_s = 1.9 GPa,
μ_t = 0.14, tangential load 0.321 N, mass 0.321 kg.
"""

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import tribojax as tj

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import scipy_reference as ref  # noqa: E402
from timing import median_time  # noqa: E402

D, G, M, GAMMA = 2.8821, 7e-8, 2.0, 1.5
SIGMA_S = 1.9e9
MU_T, TANGENTIAL_LOAD, MASS = 0.14, 0.321, 0.321
LOAD = 6.7818  # N, the 4 kPa row of wang2022 Table 3
LOAD_RANGE = (3.69, 21.3)  # N, Table 3's 0.6–20 kPa
N_LOADS = 10_000
N_REF_SUBSAMPLE = 50


def make_model():
    pair = tj.wang2022_pair(sigma_s=SIGMA_S)
    surface = tj.FractalSurface(D, G, M, gamma=GAMMA)
    return tj.FractalContact(surface, pair, mu_t=MU_T, tangential_load=TANGENTIAL_LOAD, mass=MASS)


def reference_kwargs(model):
    pair = model.pair
    return dict(
        D=D,
        G=G,
        M=M,
        gamma=GAMMA,
        E_star=float(pair.E_star),
        G_star=float(pair.G_star),
        H=float(pair.H),
        nu=float(pair.nu),
        sigma_s=float(pair.sigma_s),
        mu_t=MU_T,
        tangential_load=TANGENTIAL_LOAD,
        mass=MASS,
    )


def compile_time(fn):
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    return time.perf_counter() - t0


def with_params(model, theta):
    """The model with (D, G, μ_t) replaced by the entries of theta."""
    return eqx.tree_at(
        lambda m: (m.surface.D, m.surface.G, m.mu_t), model, (theta[0], theta[1], theta[2])
    )


def outputs(theta, model, load):
    res = with_params(model, theta)(load)
    return jnp.stack([res.F_s, res.K_tau, res.C_tau])


def entry(name, tribojax_s, baseline, baseline_s, target, meets_target, **extra):
    return {
        "name": name,
        "tribojax_s": tribojax_s,
        "baseline": baseline,
        "baseline_s": baseline_s,
        "ratio": baseline_s / tribojax_s,
        "target": target,
        "meets_target": bool(meets_target),
        **extra,
    }


def run(quick=False):
    t_start = time.perf_counter()
    rep = (lambda n: max(3, n // 20)) if quick else (lambda n: n)
    model = make_model()
    rkw = reference_kwargs(model)
    load = jnp.asarray(LOAD)
    results = []

    # 1. one load, jitted, model passed as an argument (not closed over)
    call = jax.jit(lambda m, f: m(f))
    fwd_compile = compile_time(lambda: call(model, load))
    fwd_s = median_time(lambda: call(model, load), rep(2000))
    ref_one_s = median_time(lambda: ref.reference_contact(**rkw, load=LOAD), rep(40), block=False)
    check = call(model, load)
    want = ref.reference_contact(**rkw, load=LOAD)
    agree = max(abs(float(getattr(check, k)) / want[k] - 1) for k in ("F_s", "K_tau", "C_tau"))
    results.append(
        entry(
            "contact_one_load",
            fwd_s,
            "reference_contact (scipy quad + brentq), same load and inputs",
            ref_one_s,
            "<= 50 us per warm jitted call",
            fwd_s <= 50e-6,
            compile_s=fwd_compile,
            max_rel_diff_vs_reference=agree,
        )
    )

    # 2. 10,000 loads with vmap, jitted
    loads = jnp.linspace(*LOAD_RANGE, N_LOADS)
    batch = jax.jit(lambda m, f: jax.vmap(m)(f))
    vmap_compile = compile_time(lambda: batch(model, loads))
    vmap_s = median_time(lambda: batch(model, loads), rep(30))
    sub = np.linspace(*LOAD_RANGE, N_REF_SUBSAMPLE)
    ref_sub = [ref.reference_contact(**rkw, load=float(f)) for f in sub]
    ref_loop_s = median_time(
        lambda: [ref.reference_contact(**rkw, load=float(f)) for f in sub], 3, block=False
    )
    batch_out = batch(model, jnp.asarray(sub))
    agree_b = max(
        abs(float(getattr(batch_out, k)[i]) / r[k] - 1)
        for i, r in enumerate(ref_sub)
        for k in ("F_s", "K_tau", "C_tau")
    )
    results.append(
        entry(
            "contact_10000_loads_vmap",
            vmap_s,
            "reference_contact in a Python loop",
            ref_loop_s * N_LOADS / N_REF_SUBSAMPLE,
            "<= 50 ms for 10,000 loads (warm, jitted vmap)",
            vmap_s <= 50e-3,
            baseline_note=(
                f"reference loop over {N_REF_SUBSAMPLE} loads linspace{LOAD_RANGE} N timed "
                f"(median of 3 loops, {ref_loop_s:.3f} s) and scaled linearly by "
                f"{N_LOADS // N_REF_SUBSAMPLE} to {N_LOADS} loads"
            ),
            compile_s=vmap_compile,
            max_rel_diff_vs_reference=agree_b,
        )
    )

    # 3. Jacobian of (F_s, K_tau, C_tau) w.r.t. (D, G, mu_t), jitted
    theta = jnp.array([D, G, MU_T])
    jac_fwd = jax.jit(jax.jacfwd(outputs))
    jac_rev = jax.jit(jax.jacrev(outputs))
    fwd_jac_compile = compile_time(lambda: jac_fwd(theta, model, load))
    rev_jac_compile = compile_time(lambda: jac_rev(theta, model, load))
    jf_s = median_time(lambda: jac_fwd(theta, model, load), rep(1000))
    jr_s = median_time(lambda: jac_rev(theta, model, load), rep(1000))
    # like-for-like forward: the same function (tree_at + call, 3 outputs) without derivatives.
    # The full-record call of benchmark 1 returns 15 arrays, and at this size per-call dispatch
    # (pytree flattening, output buffers), not arithmetic, dominates the time.
    fwd3 = jax.jit(outputs)
    compile_time(lambda: fwd3(theta, model, load))
    fwd3_s = median_time(lambda: fwd3(theta, model, load), rep(2000))
    J = np.asarray(jac_fwd(theta, model, load))
    J_rev = np.asarray(jac_rev(theta, model, load))
    fwd_note = (
        "baseline = jit(outputs)(theta, model, load): the same (D, G, mu_t) -> (F_s, K_tau, "
        "C_tau) function without derivatives; the full ContactParameters call of "
        "contact_one_load is recorded as full_record_forward_s"
    )
    results.append(
        entry(
            "contact_grad_D_G_mu",
            jf_s,
            "tribojax forward call",
            fwd3_s,
            "jacfwd of (F_s, K_tau, C_tau) wrt (D, G, mu_t) <= 5x one forward call",
            jf_s <= 5 * fwd3_s,
            grad_over_forward=jf_s / fwd3_s,
            full_record_forward_s=fwd_s,
            baseline_note=fwd_note,
            compile_s=fwd_jac_compile,
            mode="jax.jacfwd (3 tangents)",
        )
    )
    results.append(
        entry(
            "contact_grad_D_G_mu_jacrev",
            jr_s,
            "tribojax forward call",
            fwd3_s,
            "jacrev of (F_s, K_tau, C_tau) wrt (D, G, mu_t) <= 5x one forward call",
            jr_s <= 5 * fwd3_s,
            grad_over_forward=jr_s / fwd3_s,
            full_record_forward_s=fwd_s,
            baseline_note=fwd_note,
            compile_s=rev_jac_compile,
            mode="jax.jacrev (3 cotangents)",
            max_abs_diff_vs_jacfwd_elasticity=float(
                np.max(
                    np.abs(J_rev - J)
                    * np.asarray(theta)[None, :]
                    / np.abs(np.asarray(outputs(theta, model, load)))[:, None]
                )
            ),
        )
    )

    # 3a. the arithmetic cost ratio, free of per-call dispatch: the Jacobian at 10,000 loads
    batch3 = jax.jit(jax.vmap(outputs, in_axes=(None, None, 0)))
    batch_jac = jax.jit(jax.vmap(jax.jacfwd(outputs), in_axes=(None, None, 0)))
    compile_time(lambda: batch3(theta, model, loads))
    compile_time(lambda: batch_jac(theta, model, loads))
    b3_s = median_time(lambda: batch3(theta, model, loads), rep(30))
    bj_s = median_time(lambda: batch_jac(theta, model, loads), rep(30))
    results.append(
        entry(
            "contact_grad_D_G_mu_10000_loads_vmap",
            bj_s,
            "tribojax forward, 10,000 loads (vmap)",
            b3_s,
            "vmapped jacfwd <= 5x the vmapped forward (same function, 3 outputs)",
            bj_s <= 5 * b3_s,
            grad_over_forward=bj_s / b3_s,
        )
    )

    # 3b. the same Jacobian by SciPy-side central finite differences (7 reference calls)
    base = np.array([D, G, MU_T])
    steps = 1e-6 * base

    def fd_jacobian():
        def f(th):
            kw = dict(rkw, D=th[0], G=th[1], mu_t=th[2])
            r = ref.reference_contact(**kw, load=LOAD)
            return np.array([r["F_s"], r["K_tau"], r["C_tau"]])

        y0 = f(base)  # the 7th evaluation: the values themselves
        cols = []
        for j in range(3):
            e = np.zeros(3)
            e[j] = steps[j]
            cols.append((f(base + e) - f(base - e)) / (2 * steps[j]))
        return y0, np.stack(cols, axis=1)

    fd_s = median_time(fd_jacobian, rep(20), block=False)
    y0, J_fd = fd_jacobian()
    # compare elasticities d ln y / d ln theta (dF_s/dmu_t is exactly 0 in AD)
    elast_diff = float(np.max(np.abs(J_fd - J) * base[None, :] / np.abs(y0)[:, None]))
    results.append(
        entry(
            "contact_grad_D_G_mu_vs_scipy_fd",
            jf_s,
            "scipy central finite differences of reference_contact (7 evaluations)",
            fd_s,
            "jitted jacfwd faster than SciPy finite differences (ratio >= 1)",
            fd_s >= jf_s,
            fd_relative_step=1e-6,
            max_abs_elasticity_diff_ad_vs_fd=elast_diff,
        )
    )

    import hysteresis  # benchmarks/hysteresis.py: wu2015 harmonic balance (issue #4)

    results += hysteresis.run(quick)

    device = jax.devices()[0]
    env = {
        "device": f"{device.platform}:{getattr(device, 'device_kind', '')}",
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "jax": jax.__version__,
        "tribojax": tj.__version__,
    }
    import frf  # benchmarks/frf.py: MHB forced response (issue 16)

    results.extend(frf.run(quick))
    import topography as _topography  # benchmarks/topography.py (surface characterisation)

    results.extend(_topography.run())
    for r in results:
        r["environment"] = env
    return results, time.perf_counter() - t_start


def fmt_s(s):
    if s is None:
        return "-"
    if s < 1e-3:
        return f"{s * 1e6:.1f} us"
    if s < 1:
        return f"{s * 1e3:.2f} ms"
    return f"{s:.2f} s"


def print_table(results, total_s):
    print(f"{'name':34s} {'tribojax':>11s} {'baseline':>11s} {'ratio':>9s}  target met")
    for r in results:
        met = {None: "-", True: "yes", False: "NO"}[r["meets_target"]]  # None: no target set
        print(
            f"{r['name']:34s} {fmt_s(r['tribojax_s']):>11s} {fmt_s(r['baseline_s']):>11s} "
            f"{'-' if r['ratio'] is None else format(r['ratio'], '9.3g'):>9s}  {met}   "
            f"({r['baseline'] or 'no baseline'})"
        )
    for r in results:
        if "baseline_note" in r:
            print(f"note [{r['name']}]: {r['baseline_note']}")
        if "grad_over_forward" in r:
            print(f"note [{r['name']}]: gradient / forward = {r['grad_over_forward']:.2f}")
        if "max_abs_elasticity_diff_ad_vs_fd" in r:
            print(
                f"note [{r['name']}]: max |d ln y/d ln theta| difference AD vs FD = "
                f"{r['max_abs_elasticity_diff_ad_vs_fd']:.1e}"
            )
    env = results[0]["environment"]
    print(f"environment: {env}; total benchmark time {total_s:.1f} s")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="directory for benchmarks.json")
    parser.add_argument("--quick", action="store_true", help="few repeats (smoke test)")
    args = parser.parse_args(argv)
    results, total_s = run(quick=args.quick)
    import slip as slip_benchmarks  # benchmarks/slip.py (issue 3)

    results += slip_benchmarks.run(quick=args.quick)
    import fit_chain  # benchmarks/fit_chain.py (issue 5: full-chain fit of Tables 4-7)

    results += fit_chain.run(quick=args.quick)
    import fit_slip  # benchmarks/fit_slip.py (issue 13: slip-run fit on the one engine)

    results += fit_slip.run(quick=args.quick)

    import discovery as discovery_benchmarks  # benchmarks/discovery.py (issue 6)

    results += discovery_benchmarks.run(quick=args.quick)
    import long_records  # benchmarks/long_records.py (issue 18: records of 10^6 samples)

    results += long_records.run(quick=args.quick)
    import real_data  # benchmarks/real_data.py (issue 15: history fits of a measured record)

    results += real_data.run(quick=args.quick)
    import predict  # benchmarks/predict.py (issues 29/30: a saved model on a 28 s history)

    results += predict.run(quick=args.quick)
    import cold_start  # benchmarks/cold_start.py (issue 31: fresh processes, the cache, SciPy)

    results += cold_start.run(quick=args.quick)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "benchmarks.json").write_text(json.dumps(results, indent=2) + "\n")
    print_table(results, total_s)
    print(f"wrote {out / 'benchmarks.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
