"""The LuGre pre-slip element (wang2022 Eq 27) under harmonic displacement (issue: hysteresis).

Reference: for α = 1 the bristle law is linear in z on each monotone half-cycle,
dz/du = 1 − s·z/z_max (s = sgn v), so the steady loop is known exactly: on the falling branch
(u = A cos θ, θ ∈ [0, π)) z = −z_max + (z_A + z_max)·exp((u − A)/z_max) with the turning value
z_A = z_max·tanh(A/z_max), and F = K_τ z + C_τ dz/dt. Its first harmonic is computed here with
SciPy quad, independently of tribojax's time-domain route.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad

import tribojax as tj

F_S, K_TAU, C_TAU = 0.4868, 1.4878e7, 771.0  # wang2022 Table 3, 0.6 kPa row (N, N/m, N s/m)
Z_MAX = F_S / K_TAU
OMEGA = 2 * np.pi * 22.0  # rad/s, wu2015's 22 Hz drive


def exact_first_harmonic(A, omega=OMEGA, K=K_TAU, C=C_TAU, z_max=Z_MAX):
    z_A = z_max * np.tanh(A / z_max)

    def force(theta):  # falling branch, v = −Aω sin θ ≤ 0
        u, v = A * np.cos(theta), -A * omega * np.sin(theta)
        z = -z_max + (z_A + z_max) * np.exp((u - A) / z_max)
        return K * z + C * v * (1.0 + z / z_max)

    # odd symmetry F(θ + π) = −F(θ): full-cycle integrals are twice the half-cycle ones
    tol = dict(epsabs=1e-13 * (K + C * omega) * A, epsrel=1e-10, limit=200)
    f_c = 2 / np.pi * quad(lambda t: force(t) * np.cos(t), 0, np.pi, **tol)[0]
    f_s = 2 / np.pi * quad(lambda t: force(t) * np.sin(t), 0, np.pi, **tol)[0]
    return f_c / A, -f_s / (A * omega)  # K_eq, C_eq


def cycles_needed(A):
    # The start-up transient contracts by exp(−4A/z_max) per cycle (dz/du = 1 − s·z/z_max); run
    # until it is below 1e-8 (at least 3 cycles).
    return max(3, int(np.ceil(np.log(1e8) * Z_MAX / (4 * A))) + 1)


def response(A, C=C_TAU, omega=OMEGA, cycles=None):
    element = tj.PreSlipLuGre(F_S, K_TAU, C, 1.0)
    cycles = cycles_needed(float(A)) if cycles is None else cycles
    return tj.harmonic_response(element, A, omega, cycles=cycles, K_d=K_TAU, A0=Z_MAX)


@pytest.mark.parametrize("abar", [0.3, 1.0, 2.0, 5.0])
def test_lugre_loop_matches_exact_solution(abar):
    A = abar * Z_MAX
    K_eq, C_eq = exact_first_harmonic(A)
    out = response(A)
    # RK4 at 4096 samples per cycle; the loop has a slope kink at each reversal, so the
    # rectangle rule converges as O(n⁻²): ~1e-6 relative here.
    assert float(out.K_eq) == pytest.approx(K_eq, rel=2e-5)
    assert float(out.C_eq) == pytest.approx(C_eq, rel=2e-5)


def test_lugre_limits():
    # small amplitude: a linear spring-dashpot, K_eq → K_τ and C_eq → C_τ (exact steady loop; the
    # bristle hysteresis adds a damping ∝ K_τ·A/(z_max·ω), 1.4e-4·C_τ at Ā = 1e-6)
    K_eq, C_eq = exact_first_harmonic(1e-6 * Z_MAX)
    assert K_eq == pytest.approx(K_TAU, rel=1e-5)
    assert C_eq == pytest.approx(C_TAU, rel=1e-3)
    # large amplitude: Coulomb-like macroslip at F_s, W → 4 F_s A, K̄ falls like Jenkins' K̄
    A = 50 * Z_MAX
    big = response(A, C=0.0)
    assert float(big.W) == pytest.approx(4 * F_S * A, rel=0.05)
    assert float(big.K_bar) < 0.1
    # dissipation is positive at every amplitude
    for abar in (0.1, 1.0, 10.0):
        assert float(response(abar * Z_MAX).W) > 0


@pytest.mark.usefixtures("storable_programs")
def test_lugre_harmonic_gradient_and_vmap():
    def c_eq(F_s):
        element = tj.PreSlipLuGre(F_s, K_TAU, C_TAU, 1.0)
        out = tj.harmonic_response(element, 2 * Z_MAX, OMEGA, cycles=4, K_d=K_TAU, A0=Z_MAX)
        return out.C_bar

    g = jax.grad(c_eq)(F_S)
    h = 1e-6 * F_S
    fd = (c_eq(F_S + h) - c_eq(F_S - h)) / (2 * h)
    assert np.isfinite(float(g)) and float(g) == pytest.approx(float(fd), rel=1e-5)

    amplitudes = jnp.array([0.5, 1.0, 3.0]) * Z_MAX
    batched = jax.vmap(lambda a: response(a, cycles=8).K_eq)(amplitudes)
    looped = jnp.stack([response(a, cycles=8).K_eq for a in amplitudes])
    np.testing.assert_allclose(batched, looped, rtol=1e-12)


def test_cli_hysteresis_lugre(tmp_path):
    from tribojax._cli._main import main

    out = tmp_path / "lugre"
    argv = ["hysteresis", "--element", "lugre", "--mu", "0.3", "--N", str(F_S / 0.3)]
    argv += ["--K-d", str(K_TAU), "--C-tau", str(C_TAU), "--abar", "0.5", "4", "--n", "3"]
    assert main(argv + ["--out", str(out)]) == 0
    table = np.loadtxt(out / "hysteresis.csv", delimiter=",", comments="#", skiprows=2)
    assert table.shape == (3, 7)
    for A, K_eq, C_eq in table[:, [0, 2, 3]]:
        # 1024 samples per cycle in the CLI: O(n⁻²) rectangle-rule error, ~2e-5 relative
        K_ref, C_ref = exact_first_harmonic(A)
        assert K_eq == pytest.approx(K_ref, rel=1e-4)
        assert C_eq == pytest.approx(C_ref, rel=1e-4)
    assert (out / "hysteresis.png").exists()
    # a loop fit needs a rate-independent element: refused, nothing written
    loop_out = tmp_path / "refused"
    refused = ["hysteresis", "--element", "lugre", "--loop", "x.csv", "--out", str(loop_out)]
    assert main(refused) == 2
    assert not loop_out.exists()
