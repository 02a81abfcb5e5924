"""Benchmark: `fit_slip_run` on a synthetic slip run (issue 13: one fit engine, today's speed).

The record is `tribojax.synthetic_slip_run` of wang2022 Table 3's 0.6 kPa element (F_s, K_τ, C_τ)
over the first second of the cycle at 0.1 ms (10001 samples, noise 2e-10 m), as in
tests/test_fit_user.py. Timed warm (one untimed fit compiles): the α-fixed fit from the default
start (three C_τ starts) and the α-free fit. No baseline: the entry records the time, the LM steps
and whether the fit converged; compare entries taken in the same run.
"""

import sys
import time

import jax

import tribojax as tj

TRUTH = (0.4868, 1.4878e7, 771.05)  # F_s N, K_τ N/m, C_τ N s/m (wang2022 Table 3, 0.6 kPa)


def _timed(fn, repeats):
    fn()  # compile
    best = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        fit = fn()
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return best, fit


def run(quick=False):
    repeats = 1 if quick else 3
    out = []
    for name, alpha, truth_alpha in (
        ("fit_slip_run_alpha_fixed", 1.0, 1.0),
        ("fit_slip_run_alpha_free", None, 1.2),
    ):
        el = tj.PreSlipLuGre(*TRUTH, truth_alpha)
        run_ = tj.synthetic_slip_run(el, noise=2e-10, seed=7, n=10001, t_end=1.0)
        t0 = time.perf_counter()
        wall, fit = _timed(lambda: tj.fit_slip_run(run_, alpha=alpha, throw=False), repeats)
        out.append(
            dict(
                name=name,
                tribojax_s=wall,
                baseline=None,
                baseline_s=None,
                ratio=None,
                target=None,
                meets_target=None,
                steps=fit.steps,
                converged=bool(fit.converged),
                samples=len(run_),
                total_s=time.perf_counter() - t0,
            )
        )
    return out


if __name__ == "__main__":
    import json

    jax.config.update("jax_enable_x64", True)
    print(json.dumps(run(quick="--quick" in sys.argv), indent=2))
