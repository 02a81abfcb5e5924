"""YK (wang2022 Eq 1) and W-M (wu2015 Eq 3) synthesis: conventions, spectrum, AD, bad input."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate

import tribojax as tj
from tribojax._roughness._estimate import sf_constant

KEY = jax.random.key(7)
L = 1e-4


def test_wm_profile_is_yk_with_one_ridge():
    # wu2015 Eq 3 with D_p = D - 1 equals wang2022 Eq 1 with M = 1 along x (same phases)
    x = jnp.linspace(0.0, L, 501)
    for D in (2.2, 2.55, 2.9):
        yk = tj.yk_heights(KEY, D, 3e-9, x, L=L, M=1, n_max=18)
        wm = tj.wm_profile(KEY, D - 1.0, 3e-9, x, L=L, n_max=18)
        np.testing.assert_allclose(yk, wm, rtol=1e-12, atol=1e-22)


def test_height_map_of_one_ridge_is_a_corrugation():
    # M = 1: θ = π, the surface depends on x only
    z = tj.synthesize(KEY, 2.5, 1e-9, L=L, n_points=64, ny=5).heights
    np.testing.assert_allclose(z, jnp.broadcast_to(z[0], z.shape), rtol=0, atol=1e-20)


def _discrete_sf(tau, D, G, gamma=1.5):
    """<(z(x+τ)-z(x))²> of Eq 1 (M = 1), summed exactly over 400 modes (1 - cos = 2 sin²)."""
    n = np.arange(-200, 200)
    terms = (
        gamma ** (2 * (D - 3) * n) * 2 * np.sin(np.pi * np.multiply.outer(tau, gamma**n) / L) ** 2
    )
    return L**2 * (G / L) ** (2 * D - 4) * np.log(gamma) * terms.sum(axis=-1)


@pytest.mark.parametrize("D", [2.2, 2.5, 2.8])
def test_discrete_sum_has_the_continuous_structure_function_on_average(D):
    # The discrete sum equals C(D) G^(2D-4) τ^(6-2D) times a log-periodic ripple of period γ in τ
    # (Poisson summation); averaged over one period the ripple vanishes. 400 modes put the band
    # edges ≥ 60 decades away; 512 points per period leave an aliasing error < 3e-4.
    G, gamma = 1e-9, 1.5
    u = np.arange(512) / 512
    for tau0 in (1e-9, 5e-7):
        tau = tau0 * gamma**u
        ratio = _discrete_sf(tau, D, G) / np.asarray(tj.structure_function_model(tau, D, G))
        np.testing.assert_allclose(ratio.mean(), 1.0, rtol=1e-3)


def test_discrete_ripple_grows_towards_D_3():
    # The ripple's first harmonic falls only like (2π/ln γ)^-(α+1/2), α = 6 - 2D: ~0.3 % at
    # D = 2.2 but several % at D = 2.8 — what biases structure-function fits at high D.
    tau = 1e-7 * 1.5 ** (np.arange(256) / 256)

    def ripple(D):
        r = _discrete_sf(tau, D, 1e-9) / np.asarray(tj.structure_function_model(tau, D, 1e-9))
        return r.max() / r.min() - 1

    assert ripple(2.2) < 0.01 < 0.02 < ripple(2.8)


@pytest.mark.parametrize("D", [2.1, 2.5, 2.75, 2.95])
def test_sf_constant_against_quad(D):
    # C(D) = ∫₀^∞ u^(-1-α)(1 - cos 2πu) du by SciPy: [0, 1] directly, [1, ∞) with QAWF.
    a = 6 - 2 * D
    head = integrate.quad(lambda u: u ** (-1 - a) * (1 - np.cos(2 * np.pi * u)), 0, 1)[0]
    tail_cos = integrate.quad(lambda u: u ** (-1 - a), 1, np.inf, weight="cos", wvar=2 * np.pi)[0]
    ref = head + 1 / a - tail_cos
    np.testing.assert_allclose(sf_constant(D), ref, rtol=1e-7)


def test_direction_factor():
    assert float(tj.direction_factor(2.5, 1)) == pytest.approx(1.0)
    # YK original weights, M = 2: ridges at 90° (cos 0 → nothing) and 180° (1) → 1/2
    assert float(tj.direction_factor(2.5, 2, ridge_weights="yk1998")) == pytest.approx(0.5)


def _f(D, G):
    x = jnp.linspace(0.0, L, 33)
    return jnp.sum(tj.yk_heights(KEY, D, G, x, L=L, M=3, n_max=10) ** 2)


@pytest.mark.usefixtures("storable_programs")
def test_gradients_match_finite_differences():
    D, G = 2.6, 2e-9
    gD, gG = jax.grad(_f, argnums=(0, 1))(D, G)
    h = 1e-6
    fdD = (_f(D + h, G) - _f(D - h, G)) / (2 * h)
    fdG = (_f(D, G * (1 + h)) - _f(D, G * (1 - h))) / (2 * h * G)
    np.testing.assert_allclose(gD, fdD, rtol=1e-6)
    np.testing.assert_allclose(gG, fdG, rtol=1e-6)


@pytest.mark.usefixtures("storable_programs")
def test_jit_and_vmap():
    Ds = jnp.array([2.3, 2.6, 2.9])
    eager = jnp.stack([_f(D, 1e-9) for D in Ds])
    np.testing.assert_allclose(jax.vmap(_f, in_axes=(0, None))(Ds, 1e-9), eager, rtol=1e-12)
    np.testing.assert_allclose(jax.jit(_f)(2.3, 1e-9), eager[0], rtol=1e-12)


def test_bad_input():
    x = jnp.linspace(0, L, 8)
    with pytest.raises(ValueError, match="D = 3.1"):
        tj.yk_heights(KEY, 3.1, 1e-9, x, L=L)
    with pytest.raises(ValueError, match="G = -1"):
        tj.yk_heights(KEY, 2.5, -1e-9, x, L=L)
    with pytest.raises(ValueError, match="D = 2.5"):  # wu2015 uses the profile dimension
        tj.wm_profile(KEY, 2.5, 1e-9, x, L=L)
    with pytest.raises(ValueError, match="M = 0"):
        tj.yk_heights(KEY, 2.5, 1e-9, x, L=L, M=0)
    with pytest.raises(ValueError, match="ridge_weights"):
        tj.yk_heights(KEY, 2.5, 1e-9, x, L=L, ridge_weights="x")
    with pytest.raises(Exception, match="D is outside"):  # under jit: equinox.error_if
        eqx.filter_jit(lambda D: tj.yk_heights(KEY, D, 1e-9, x, L=L))(3.5).block_until_ready()
