"""Benchmarks of the multi-harmonic balance forced response (issue 16) against a NumPy/SciPy HBM.

    python benchmarks/frf.py [--quick]     # prints the table
    (also run by benchmarks/run.py, which includes these entries in benchmarks.json)

Cases (tribojax warm: compiled once, then the median of repeated calls; `compile_s` is the
first call's wall time, compilation plus one run):

1. SDOF Jenkins (M = 1, C = 1, K = 100, μN = 1, K_d = 100, F = 1), H = 5, ω 6–18 rad/s,
   pseudo-arclength continuation with ~200 points and Hill stability (`tj.frequency_response`);
2. the 2-DOF elastic dry-friction benchmark (`tj.frf_2dof_system`), its eight curves, H = 8;
3. the design curve: resonant amplitude at `N_DESIGN_LOADS` normal loads, `tj.peak_on_grid`
   (SDOF Jenkins, H = 3, 24-point grid and a bracketing refinement) vmapped over chunks of
   `DESIGN_CHUNK` loads (`jax.lax.map(..., batch_size=DESIGN_CHUNK)`): every solve's while loop
   runs until its slowest lane has converged, so one vmap over all 1,000 loads pays the slowest
   load's Newton count at every solve (558 trust-region steps per load against 311 averaged over
   chunks of 100 and 178 alone), and smaller batches also stay in cache (same results);
   `n_stationary_peaks` counts the loads whose peak is a stationary point (result successful;
   the others lie on a kink of the sampled-AFT amplitude curve, see `peak_on_grid`).

Baseline: the way NumPy/SciPy HBM codes work: the residual in NumPy with FFT AFT (the contact's
return map stepped in a Python loop over the time samples), `scipy.optimize.root` (hybr, finite-
difference Jacobian), each solution started from the previous one, at the same frequencies as
tribojax's branch (natural continuation: no turning points on these curves). The largest relative
difference of the first-harmonic amplitudes is recorded as the check that both solve the same
problem.
"""

import sys
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from scipy import optimize

import tribojax as tj

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import median_time  # noqa: E402

N_DESIGN_LOADS = 1000
DESIGN_CHUNK = 50


def sdof_system(N=1.0, H=5):
    structure = tj.Structure(1.0, 1.0, 100.0)
    contact = tj.FrictionContact(tj.Jenkins(1.0, N, 100.0), 0)
    return tj.FrictionSystem(structure, [contact], tj.Excitation(1, cosine=[1.0]), H=H)


class NumpyHBM:
    """NumPy/SciPy MHB of a FrictionSystem's data (independent code: loops, FFT, hybr)."""

    def __init__(self, system):
        s, ex = system.structure, system.excitation
        self.M, self.C, self.K = (np.asarray(a) for a in (s.M, s.C, s.K))
        self.static, self.cos = np.asarray(ex.static), np.asarray(ex.cosine)
        self.H, self.n = max(system.harmonics), system.n_time
        self.contacts = []
        for c in system.contacts:
            el = c.element
            if isinstance(c, tj.DryFrictionContact2D):
                p = (float(el.k_t), float(el.k_n), float(el.mu), float(el.n0))
                self.contacts.append(("2d", c.tangential_dof, c.normal_dof, p))
            else:
                self.contacts.append(("jenkins", c.dof, None, (float(el.K_d), float(el.A0))))
        self.nd = self.M.shape[0]

    def forces(self, x):
        f = np.zeros_like(x)
        for kind, d0, d1, p in self.contacts:
            if kind == "2d":
                k_t, k_n, mu, n0 = p
                w, ut, un = 0.0, x[:, d0], x[:, d1]
                for _ in range(2):
                    for j in range(self.n):
                        fn = max(k_n * un[j] + n0, 0.0)
                        ft = min(max(k_t * (ut[j] - w), -mu * fn), mu * fn)
                        w = ut[j] - ft / k_t
                        f[j, d0], f[j, d1] = ft, fn
            else:
                kd, a0 = p
                z, u_old, u = 0.0, 0.0, x[:, d0]
                for _ in range(2):
                    for j in range(self.n):
                        z = min(max(z + u[j] - u_old, -a0), a0)
                        u_old = u[j]
                        f[j, d0] = kd * z
        return f

    def residual(self, v, w):
        H, n, nd = self.H, self.n, self.nd
        a0, a, b = v[:nd], v[nd : nd * (H + 1)].reshape(H, nd), v[nd * (H + 1) :].reshape(H, nd)
        spec = np.zeros((n // 2 + 1, nd), complex)
        spec[0], spec[1 : H + 1] = n * a0, n / 2 * (a - 1j * b)
        x = np.fft.irfft(spec, n, axis=0)
        F = np.fft.rfft(self.forces(x), axis=0)
        fa0, fa, fb = F[0].real / n, 2 / n * F[1 : H + 1].real, -2 / n * F[1 : H + 1].imag
        r0 = self.K @ a0 + fa0 - self.static
        ra, rb = np.empty((H, nd)), np.empty((H, nd))
        for k in range(1, H + 1):
            Z = self.K - (k * w) ** 2 * self.M
            ra[k - 1] = Z @ a[k - 1] + k * w * self.C @ b[k - 1] + fa[k - 1] - (k == 1) * self.cos
            rb[k - 1] = Z @ b[k - 1] - k * w * self.C @ a[k - 1] + fb[k - 1]
        return np.concatenate([r0, ra.ravel(), rb.ravel()])

    def branch(self, omegas, v0=None):
        v = np.zeros(self.nd * (2 * self.H + 1)) if v0 is None else v0
        amps = []
        for w in omegas:
            sol = optimize.root(self.residual, v, args=(w,), method="hybr", tol=1e-10)
            v = sol.x
            a = v[self.nd : 2 * self.nd]
            b = v[self.nd * (self.H + 1) : self.nd * (self.H + 2)]
            amps.append(np.hypot(a, b))
        return np.array(amps)


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def entry(name, tribojax_s, baseline, baseline_s, target, meets, **extra):
    return {
        "name": name,
        "tribojax_s": tribojax_s,
        "baseline": baseline,
        "baseline_s": baseline_s,
        "ratio": baseline_s / tribojax_s,
        "target": target,
        "meets_target": bool(meets),
        **extra,
    }


def run(quick: bool = False) -> list[dict]:
    results = []
    reps = 1 if quick else 3
    # 1. SDOF Jenkins, H = 5, ~200 points
    system = sdof_system()
    opts = dict(ds=0.005, ds_max=0.02, max_points=400)
    fr, compile_s = _timed(lambda: tj.frequency_response(system, 6.0, 18.0, **opts))
    t = median_time(lambda: tj.frequency_response(system, 6.0, 18.0, **opts), reps, block=False)
    ref = NumpyHBM(system)
    amps, base_s = _timed(lambda: ref.branch(fr.omega))
    diff = float(np.max(np.abs(amps[:, 0] / fr.amplitude[:, 0] - 1)))
    results.append(
        entry(
            "frf_sdof_jenkins_H5",
            t,
            "NumPy FFT-AFT + scipy.optimize.root (hybr), same points",
            base_s,
            "<= 1 s warm on 2 cores",
            t <= 1.0,
            n_points=len(fr.omega),
            compile_s=compile_s,
            max_rel_amplitude_diff=diff,
        )
    )
    # 2. the 2-DOF benchmark, eight curves
    Fs = tj.FRF_2DOF["F"]
    systems = [tj.frf_2dof_system(F) for F in Fs]
    w0, w1 = tj.FRF_2DOF["omega_range"]

    def eight():
        return [tj.frequency_response(s, w0, w1, ds_max=0.1, max_points=1000) for s in systems]

    curves, compile_s = _timed(eight)
    t = median_time(eight, 1, block=False)
    base_curves = (0, 4, 7) if quick else range(len(Fs))
    base_s, diff = 0.0, 0.0
    for i in base_curves:
        amps, s = _timed(lambda i=i: NumpyHBM(systems[i]).branch(curves[i].omega))
        base_s += s
        diff = max(diff, float(np.max(np.abs(amps[:, 0] / curves[i].amplitude[:, 0] - 1))))
    note = "" if len(base_curves) == len(Fs) else f" (baseline: curves {list(base_curves)})"
    results.append(
        entry(
            "frf_2dof_eight_curves",
            t,
            "NumPy FFT-AFT + scipy.optimize.root (hybr)" + note,
            base_s,
            "<= 5 s warm on 2 cores",
            t <= 5.0,
            compile_s=compile_s,
            n_points=[len(c.omega) for c in curves],
            max_rel_amplitude_diff=diff,
        )
    )
    # 3. design curve: 1,000 normal loads in one vmap
    grid = jnp.linspace(8.0, 16.0, 24)
    loads = jnp.linspace(0.5, 8.0, N_DESIGN_LOADS)

    @eqx.filter_jit
    def design(Ns):
        return jax.lax.map(
            lambda N: tj.peak_on_grid(sdof_system(N, H=3), grid), Ns, batch_size=DESIGN_CHUNK
        )

    peaks, compile_s = _timed(lambda: jax.block_until_ready(design(loads)).amplitude)
    t = median_time(lambda: design(loads), reps)
    codes = np.asarray(design(loads).result._value)
    sub = np.asarray(loads[:: len(loads) // (10 if not quick else 4)])
    t0 = time.perf_counter()
    ref_peaks = [
        NumpyHBM(sdof_system(float(N), H=3)).branch(np.asarray(grid))[:, 0].max() for N in sub
    ]
    per_load = (time.perf_counter() - t0) / len(sub)
    results.append(
        entry(
            f"frf_design_curve_{len(loads)}_loads",
            t,
            "NumPy HBM on the same grid, per load x n",
            per_load * len(loads),
            "1,000 loads <= 10 s warm on 2 cores (scaled linearly)",
            t * 1000 / len(loads) <= 10.0,
            compile_s=compile_s,
            n_loads=len(loads),
            chunk=DESIGN_CHUNK,
            baseline_note=f"baseline timed on {len(sub)} loads and scaled to {len(loads)} (grid "
            "maximum only, no refinement)",
            n_stationary_peaks=int(np.sum(codes == 0)),
            max_rel_peak_diff_vs_grid_max=float(
                np.max(np.asarray(ref_peaks) / np.asarray(peaks)[:: len(loads) // len(sub)] - 1)
            ),
        )
    )
    return results


if __name__ == "__main__":
    for r in run("--quick" in sys.argv):
        print({k: v for k, v in r.items() if k != "environment"})
