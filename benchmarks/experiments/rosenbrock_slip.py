"""Experiment (issue 3): tolerance ladder of `tribojax.Rodas4` (simulate_slip's default) and
Kvaerno5 + chord (`solver="kvaerno5"`) on the slip problem.

For Table 3's 0.6, 4 and 20 kPa rows and alpha 1 and 1.26: worst relative error of the four phase
averages against SciPy Radau (rtol 1e-11, exact sign; tests/test_slip_scipy.py), warm time per
cycle (median), accepted/rejected steps; then the six loads vmapped.
Run: python benchmarks/experiments/rosenbrock_slip.py [--quick] [variants...]
"""

import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import tribojax as tj

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from test_slip_scipy import reference  # noqa: E402
from timing import median_time  # noqa: E402

T3 = tj.wang2022_table(3)
CACHE = Path("/tmp/rosenbrock_slip_ref.npz")


def params(row):
    return tuple(float(T3[k][row]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))


def refs(cases):
    store = dict(np.load(CACHE)) if CACHE.exists() else {}
    for row, alpha in cases:
        key = f"{row}_{alpha}"
        if key not in store:
            store[key] = reference(*params(row), alpha)[1]
    np.savez(CACHE, **store)
    return store


VARIANTS = {
    "kvaerno5 rtol1e-6 atol1e-16": dict(solver="kvaerno5"),
    "rodas4 rtol1e-6 atol3e-16": dict(atol=3e-16),
    "rodas4 rtol1e-6 atol5e-16": dict(atol=5e-16),
    "rodas4 rtol1e-6 atol1e-15 (default)": dict(),
    "rodas4 rtol1e-5 atol3e-16": dict(rtol=1e-5),
}


def main(quick=False):
    n = 5 if quick else 11
    cases = [(0, 1.0), (2, 1.0), (5, 1.0), (0, 1.26), (2, 1.26), (5, 1.26)]
    ref = refs(cases)
    names = [a for a in sys.argv[1:] if not a.startswith("--")] or list(VARIANTS)
    for name in names:
        kw = VARIANTS[name]
        fwd = jax.jit(lambda e, kw=kw: tj.slip_phase_averages(e, **kw))
        sim = jax.jit(lambda e, kw=kw: tj.simulate_slip(e, ts=jnp.array([2.3]), **kw).stats)
        for row, alpha in cases:
            el = tj.PreSlipLuGre(*params(row), alpha)
            ph = np.asarray(fwd(el)) * 1e9
            err = float(np.max(np.abs(ph / ref[f"{row}_{alpha}"] - 1)))
            t = median_time(lambda: fwd(el), n)
            st = sim(el)
            print(
                f"{name:36s} row {row} a {alpha:4}: {t * 1e3:6.2f} ms  err {err:.1e}  "
                f"acc {int(st['num_accepted_steps'])} rej {int(st['num_rejected_steps'])}",
                flush=True,
            )
        els = jax.vmap(lambda f, k, c: tj.PreSlipLuGre(f, k, c))(
            *(jnp.asarray(T3[k]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))
        )
        six = jax.jit(jax.vmap(lambda e, kw=kw: tj.slip_phase_averages(e, **kw)))
        print(
            f"{name:36s} six loads vmapped: {median_time(lambda: six(els), 5) * 1e3:6.1f} ms",
            flush=True,
        )


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
