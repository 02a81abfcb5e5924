"""Benchmarks of wu2015's harmonic balance (K̄, C̄ of Jenkins and Mindlin loops) against SciPy.

    python benchmarks/hysteresis.py            # prints the table
    (also run by benchmarks/run.py, which includes these entries in benchmarks.json)

Case: K̄ and C̄ at 1,000 amplitudes Ā ∈ [0.05, 10] with `jax.vmap(tj.harmonic_balance)` under
`jax.jit`, warm (compiled and run once before timing; median of repeated calls, each ending in
`block_until_ready`). Baseline: the loop a SciPy user would write — for each amplitude,
`scipy.integrate.quad` of f·cos θ and f·sin θ over the falling branch, split at θ*, the same
split and loop symmetry as tribojax. Both sides compute the same 1,000 (K̄, C̄) pairs and the
largest difference is recorded.
"""

import math
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np
from scipy import integrate

import tribojax as tj
from timing import median_time

MU, N, KD = 0.3, 2.94, 1.2e6
N_AMPLITUDES = 1000


def _scipy_kc(branch, span, Ab):
    """K̄, C̄ by quad on [0, θ*] and [θ*, π] (branch in units of μN, as a function of θ)."""
    ts = math.acos(1 - span / Ab) if Ab > span / 2 else math.pi
    ic = is_ = 0.0
    for lo, hi in ((0.0, ts), (ts, math.pi)):
        if hi > lo:
            ic += integrate.quad(lambda t: branch(t, Ab) * math.cos(t), lo, hi, epsabs=1e-13)[0]
            is_ += integrate.quad(lambda t: branch(t, Ab) * math.sin(t), lo, hi, epsabs=1e-13)[0]
    return 2 / math.pi * ic / Ab, -2 * is_ / Ab


def _jenkins_branch(t, Ab):
    return max(min(Ab, 1.0) + Ab * (math.cos(t) - 1), -1.0)


def _mindlin_branch(t, Ab):
    def phi(x):  # virgin curve / μN, x in units of A0
        return 1 - max(1 - x / 1.5, 0.0) ** 1.5

    return max(phi(Ab) - 2 * phi(0.5 * Ab * (1 - math.cos(t))), -1.0)


def run(quick: bool = False) -> list[dict]:
    """Benchmark entries in the benchmarks/run.py schema."""
    A_bar = np.linspace(0.05, 10.0, N_AMPLITUDES)
    batch = jax.jit(jax.vmap(tj.harmonic_balance, in_axes=(None, 0)))
    results = []
    cases = (
        ("jenkins", tj.Jenkins, _jenkins_branch, 2.0),
        ("mindlin", tj.Mindlin, _mindlin_branch, 3.0),
    )
    for name, cls, branch, span in cases:
        el = cls(MU, N, KD)
        A = jnp.asarray(A_bar) * el.A0
        t0 = time.perf_counter()
        jax.block_until_ready(batch(el, A))
        compile_s = time.perf_counter() - t0
        tj_s = median_time(lambda: batch(el, A), 20 if quick else 200)
        out = batch(el, A)
        ref_times = []
        for _ in range(1 if quick else 3):
            t0 = time.perf_counter()
            ref = np.array([_scipy_kc(branch, span, a) for a in A_bar])
            ref_times.append(time.perf_counter() - t0)
        ref_s = statistics.median(ref_times)
        diff = max(
            float(np.max(np.abs(np.asarray(out.K_bar) - ref[:, 0]))),
            float(np.max(np.abs(np.asarray(out.C_bar) - ref[:, 1]))),
        )
        results.append(
            {
                "name": f"hysteresis_{name}_1000_amplitudes_vmap",
                "tribojax_s": tj_s,
                "baseline": "scipy.integrate.quad loop, same 1,000 amplitudes (split at θ*)",
                "baseline_s": ref_s,
                "baseline_note": f"median of {len(ref_times)} full SciPy loops",
                "ratio": ref_s / tj_s,
                "target": "<= 5 ms warm for 1,000 amplitudes and >= 100x the SciPy quad loop",
                "meets_target": bool(tj_s <= 5e-3 and ref_s / tj_s >= 100),
                "compile_s": compile_s,
                "max_abs_diff_vs_scipy": diff,
            }
        )
    return results


if __name__ == "__main__":
    for r in run():
        print(
            f"{r['name']:40s} tribojax {r['tribojax_s'] * 1e3:7.3f} ms   scipy "
            f"{r['baseline_s']:7.3f} s   ratio {r['ratio']:8.0f}   met {r['meets_target']}   "
            f"max |diff| {r['max_abs_diff_vs_scipy']:.1e}"
        )
