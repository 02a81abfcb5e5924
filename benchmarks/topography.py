"""Benchmarks for surface characterisation: YK synthesis (jitted JAX vs a NumPy loop over modes)
and the PSD estimate (tribojax vs scipy.signal.welch + numpy.polyfit on a fixed band)."""

import jax
import numpy as np

import tribojax as tj
from timing import median_time


def run() -> list[dict]:
    from scipy import signal

    L, N, D, G = 1e-4, 4096, 2.5, 1e-9
    x = np.arange(N) * L / N
    key = jax.random.key(0)
    n_max = 19
    f = jax.jit(lambda D: tj.yk_heights(key, D, G, x, L=L, n_max=n_max))
    t_jax = median_time(lambda: f(D), 5)
    phi = np.asarray(jax.random.uniform(key, (1, n_max + 1), maxval=2 * np.pi))[0]

    def numpy_loop():
        z = np.zeros(N)
        for n in range(n_max + 1):
            k = 2 * np.pi * 1.5**n / L
            z += 1.5 ** ((D - 3) * n) * (np.cos(phi[n]) - np.cos(-k * x + phi[n]))
        return L * (G / L) ** (D - 2) * np.sqrt(np.log(1.5)) * z

    t_np = median_time(numpy_loop, 5)
    topo = tj.synthesize(key, D, G, L=L, n_points=N)
    t_est = median_time(lambda: tj.estimate_fractal(topo, "psd").D, 5)
    z = np.asarray(topo.heights)

    def welch_fit():
        fw, p = signal.welch(z, fs=N / L, nperseg=N // 4)
        sel = (fw > 4 / L) & (fw < N / (8 * L))
        return np.polyfit(np.log10(fw[sel]), np.log10(p[sel]), 1)

    t_welch = median_time(welch_fit, 5)
    return [
        dict(
            name="yk_heights profile 4096x20 modes",
            tribojax_s=t_jax,
            baseline="numpy loop",
            baseline_s=t_np,
            ratio=t_np / t_jax,
            target=None,  # issue 7 sets no speed target; reported for users choosing a path
            meets_target=None,
        ),
        dict(
            name="estimate_fractal psd (auto band) 4096",
            tribojax_s=t_est,
            baseline="scipy welch + polyfit, fixed band",
            baseline_s=t_welch,
            ratio=t_welch / t_est,
            target=None,
            meets_target=None,
        ),
    ]


if __name__ == "__main__":
    for row in run():
        print(row)
