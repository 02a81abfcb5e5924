"""LuGre (wang2022 Eq 25) and the pre-slip element (Eq 27): limits, gradients, invariance, input."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tribojax as tj
from conftest import make_model
from tribojax.discovery import AugmentedPreSlip

LUGRE = dict(sigma0=1e5, sigma1=300.0, sigma2=0.4, F_c=1.0, F_s=1.5, v_s=1e-3, alpha=1.0)


@pytest.mark.parametrize("v", [-3e-3, -2e-4, 5e-4, 2e-3])
@pytest.mark.parametrize("alpha", [1.0, 0.6])
def test_lugre_constant_velocity_settles_at_steady_friction(v, alpha):
    # Integrate dz/dt at fixed v with SciPy; the force must settle at g(v) sgn(v) + sigma2 v.
    el = tj.LuGre(**dict(LUGRE, alpha=alpha))
    sol = solve_ivp(
        lambda t, z: [float(el.state_rate(z[0], v))], (0, 3.0), [0.0], rtol=1e-10, atol=1e-14
    )
    force = float(el.force(sol.y[0, -1], v))
    g = 1.0 + 0.5 * np.exp(-((v / 1e-3) ** 2))
    expected = g * np.sign(v) + 0.4 * v
    # relaxation rate |v| sigma0 / g >= 13 1/s: after 3 s the residual is < 1e-12 relative for
    # alpha = 1; alpha < 1 reaches the limit in finite time (the bracket is clamped at 0).
    # 1e-6 leaves room for the solver tolerance.
    assert force == pytest.approx(expected, rel=1e-6)
    assert float(el.steady_force(v)) == pytest.approx(expected, rel=1e-12)


def test_stribeck_limits_and_finite_gradient_at_rest():
    el = tj.LuGre(**LUGRE)
    assert float(el.stribeck(0.0)) == pytest.approx(1.5)
    assert float(el.stribeck(1.0)) == pytest.approx(1.0)
    for f in (el.stribeck, lambda v: el.force(1e-6, v), lambda v: el.state_rate(2e-6, v)):
        assert np.isfinite(float(jax.grad(f)(0.0)))


def test_preslip_is_lugre_with_paper_substitution():
    # Eq 27 = Eq 25 with sigma0 = K, sigma1 = C, sigma2 = 0 and g = F_s (F_c = F_s).
    pre = tj.PreSlipLuGre(0.4868, 1.4878e7, 771.0516, 1.3)
    lug = tj.LuGre(1.4878e7, 771.0516, 0.0, 0.4868, 0.4868, 1.0, 1.3)
    for z, v in [(1e-8, 2e-7), (-2e-8, 1e-7), (3e-8, -5e-7), (0.0, 0.0)]:
        assert float(pre.force(z, v)) == pytest.approx(float(lug.force(z, v)), rel=1e-12, abs=1e-18)
    assert float(pre.z_max) == pytest.approx(32.7195e-9, rel=1e-4)  # Table 3: 32.7295 nm (Eq 26)


def test_preslip_from_contact_record():
    params = make_model()(tj.vacuum_to_load(2.0))
    el = tj.PreSlipLuGre.from_contact(params, alpha=1.2)
    assert float(el.K_tau) == float(params.K_tau) and float(el.F_s) == float(params.F_s)
    assert float(el.z_max) == pytest.approx(float(params.z_max), rel=1e-12)


def test_bristle_rate_stops_at_z_max_and_is_stiff_spring_in_stick():
    el = tj.PreSlipLuGre(0.5, 1e7, 500.0, 1.0)
    assert float(el.state_rate(el.z_max, 1e-6)) == pytest.approx(0.0, abs=1e-15)
    assert float(el.state_rate(0.0, 1e-6)) == pytest.approx(1e-6, rel=1e-9)
    assert float(el.state_rate(el.z_max, -1e-6)) == pytest.approx(-2e-6, rel=1e-9)
    # non-integer alpha: bracket clamped at 0 beyond z_max, not NaN
    el2 = tj.PreSlipLuGre(0.5, 1e7, 500.0, 1.5)
    assert float(el2.state_rate(1.1 * el2.z_max, 1e-6)) == 0.0


def test_force_gradient_matches_central_differences():
    def f(p):
        el = tj.PreSlipLuGre(p[0], p[1], p[2], p[3])
        return el.force(2e-8, 3e-7)

    p = jnp.array([0.7, 2e7, 700.0, 1.3])
    g = np.asarray(jax.grad(f)(p))
    for i in range(4):
        h = 1e-5 * float(p[i])
        e = jnp.zeros(4).at[i].set(h)
        fd = (float(f(p + e)) - float(f(p - e))) / (2 * h)
        assert g[i] == pytest.approx(fd, rel=1e-6, abs=1e-12 * abs(float(f(p))) / float(p[i]))


def test_jit_and_vmap_invariance():
    Fs = jnp.array([0.5, 1.0, 2.0])
    els = jax.vmap(lambda f: tj.PreSlipLuGre(f, 2e7, 700.0))(Fs)
    z, v = jnp.array([1e-8, -2e-8, 3e-8]), jnp.array([1e-7, 2e-7, -1e-7])
    batched = jax.vmap(lambda e, a, b: e.force(a, b))(els, z, v)
    loop = [float(tj.PreSlipLuGre(float(f), 2e7, 700.0).force(a, b)) for f, a, b in zip(Fs, z, v)]
    np.testing.assert_allclose(np.asarray(batched), loop, rtol=1e-14)
    el = tj.LuGre(**LUGRE)
    jitted = jax.jit(lambda e, a, b: e.force(a, b))(el, 1e-6, 2e-4)
    assert float(jitted) == pytest.approx(float(el.force(1e-6, 2e-4)), rel=1e-14)


@pytest.mark.parametrize(
    "kw, name",
    [
        (dict(alpha=0.0), "alpha"),
        (dict(alpha=-1.0), "alpha"),
        (dict(K_tau=0.0), "K_tau"),
        (dict(F_s=float("nan")), "F_s"),
        (dict(C_tau=-1.0), "C_tau"),
    ],
)
def test_preslip_bad_input(kw, name):
    args = dict(F_s=0.5, K_tau=1e7, C_tau=500.0, alpha=1.0) | kw
    with pytest.raises(ValueError, match=name):
        tj.PreSlipLuGre(**args)


def test_lugre_bad_input():
    with pytest.raises(ValueError, match="v_s"):
        tj.LuGre(**dict(LUGRE, v_s=0.0))
    with pytest.raises(ValueError, match="alpha"):
        tj.LuGre(**dict(LUGRE, alpha=-0.5))


def test_augmented_preslip_at_null_knobs_is_the_papers_element():
    F_s, K, C = 1.5, 1e5, 300.0
    plain = tj.PreSlipLuGre(F_s, K, C)
    zero = AugmentedPreSlip(F_s, K, C, 0.0, 0.0, 1e-3, 0.0, tj.TrapezoidProfile())
    for z, v in [(2e-6, 1e-3), (-5e-6, -4e-4), (1e-5, 0.0)]:
        assert float(zero.force((z, 0.4), v)) == pytest.approx(float(plain.force(z, v)), rel=1e-14)
        ref = float(plain.state_rate(z, v))
        assert float(zero.state_rate((z, 0.4), v)[0]) == pytest.approx(ref, rel=1e-14)


def test_augmented_preslip_knobs_are_lugre_terms():
    # Stribeck and viscous knobs are LuGre's g(v) (F_c = (1 − δ_b)F_s, β = 2) and σ2 (Eq 25),
    # δ_b = 0.9·tanh(δ/0.9) (the knob bound)
    F_s, K, C, delta = 1.5, 1e5, 300.0, 0.3
    el = AugmentedPreSlip(F_s, K, C, 0.4, delta, 1e-3, 0.0, tj.TrapezoidProfile())
    d_b = 0.9 * np.tanh(delta / 0.9)
    lugre = tj.LuGre(K, C, 0.4, (1 - d_b) * F_s, F_s, 1e-3)
    for z, v in [(2e-6, 1e-3), (-5e-6, -4e-4), (1e-5, 2e-3)]:
        assert float(el.force((z, 0.0), v)) == pytest.approx(float(lugre.force(z, v)), rel=1e-12)
        ref = float(lugre.steady_force(v))
        assert float(el.steady_force(v)) == pytest.approx(ref, rel=1e-12)


def test_augmented_preslip_load_coupling_reads_the_drive_through_a_time_state():
    prof = tj.TrapezoidProfile()
    kappa_g = 0.5  # per g: N/N0 = 1 + 0.9 tanh(κ a/(g 0.9)), K_τ and F_s scale, z_max does not
    el = AugmentedPreSlip(1.5, 1e5, 300.0, 0.0, 0.0, 1e-3, kappa_g, prof)
    z0, tau0 = el.initial_state()
    assert float(z0) == 0.0 and float(tau0) == 0.0
    t = 0.4
    assert float(prof.acceleration(t)) == pytest.approx(1.0)
    m = 1 + 0.9 * np.tanh(kappa_g * 1.0 / (9.8 * 0.9))  # g = 9.8 m/s² (wang2022 Eq 28)
    assert 1.04 < m < 1.06
    plain = tj.PreSlipLuGre(1.5 * m, 1e5 * m, 300.0)
    ref = float(plain.force(2e-6, 1e-4))
    assert float(el.force((2e-6, t), 1e-4)) == pytest.approx(ref, rel=1e-12)
    zdot, taudot = el.state_rate((2e-6, t), 1e-4)
    assert float(taudot) == 1.0
    assert float(zdot) == pytest.approx(float(plain.state_rate(2e-6, 1e-4)), rel=1e-12)
    with pytest.raises(ValueError, match="profile"):
        AugmentedPreSlip(1.5, 1e5, 300.0, 0.0, 0.0, 1e-3, 0.05, None)
    with pytest.raises(ValueError, match="v_s"):
        AugmentedPreSlip(1.5, 1e5, 300.0, 0.0, 0.1, 0.0, 0.0, prof)
    with pytest.raises(TypeError):  # the paper's element has no knobs
        tj.PreSlipLuGre(1.5, 1e5, 300.0, kappa=0.05, drive=prof)
