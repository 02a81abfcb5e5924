"""Harmonic balance of the wu2015 elements: closed forms, SciPy oracle, gradients, invariance."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate

import tribojax as tj

MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22
JENKINS = tj.Jenkins(MU, N, KD)
MINDLIN = tj.Mindlin(MU, N, KD)
A0 = MU * N / KD


@jax.jit
def _batch(element, A):
    return jax.vmap(lambda a: tj.harmonic_balance(element, a, OMEGA))(A)


def jenkins_closed(Ab):
    """wu2015 Eq 1 loop: K̄ = (θ* − sin 2θ*/2)/π, C̄ = 4(Ā − 1)/Ā² (no slip: 1, 0)."""
    ts = np.arccos(np.clip(1 - 2 / Ab, -1, 1))
    K = np.where(Ab > 1, (ts - np.sin(2 * ts) / 2) / np.pi, 1.0)
    return K, np.where(Ab > 1, 4 * (Ab - 1) / Ab**2, 0.0)


def mindlin_cbar_closed(Ab):
    """Mindlin C̄ = W/(K_d A²): gross slip 4(Ā − 1.2)/Ā²; partial slip from the Masing loop area
    W = μN[4A + 4A(1 − A/Y)^1.5 − 3.2Y(1 − (1 − A/Y)^2.5)], Y = 1.5 A0 (derived by hand).
    Written with log1p/expm1: the bracket cancels to O(Ā³), so 1 − p^2.5 must keep its digits."""
    lp = np.log1p(-np.where(Ab < 1.5, 2 * Ab / 3, 0.5))  # gross slip: not used
    partial = (4 * Ab + 4 * Ab * np.exp(1.5 * lp) + 4.8 * np.expm1(2.5 * lp)) / Ab**2
    return np.where(Ab >= 1.5, 4 * (Ab - 1.2) / Ab**2, partial)


def test_jenkins_closed_forms_to_1e10():
    Ab = np.linspace(1e-3, 10, 4001)
    out = _batch(JENKINS, jnp.asarray(Ab * A0))
    K, C = jenkins_closed(Ab)
    assert np.max(np.abs(out.K_bar - K)) < 1e-10  # the acceptance tolerance
    assert np.max(np.abs(out.C_bar - C)) < 1e-10
    np.testing.assert_allclose(out.A_bar, Ab, rtol=1e-14)


def test_mindlin_cbar_gross_and_partial_slip_to_1e10():
    Ab = np.concatenate([np.linspace(1e-3, 1.499, 1500), [1.5], np.linspace(1.5001, 10, 1500)])
    out = _batch(MINDLIN, jnp.asarray(Ab * A0))
    assert np.max(np.abs(out.C_bar - mindlin_cbar_closed(Ab))) < 1e-10


def test_mindlin_kbar_against_scipy_quad():
    """Independent oracle: quad of the printed-then-corrected Eq 2 branch, f* start, per θ*."""

    def kbar(Ab):
        fstar = 1 - max(1 - 2 * Ab / 3, 0) ** 1.5  # in units of μN

        def branch(th):  # f/μN on the falling branch
            x = Ab * (1 - np.cos(th)) / 3
            return max(fstar - 2 * (1 - (1 - x) ** 1.5), -1.0) if x < 1 else -1.0

        ts = np.arccos(1 - 3 / Ab) if Ab > 1.5 else np.pi
        c = integrate.quad(lambda th: branch(th) * np.cos(th), 0, ts, epsabs=1e-14)[0]
        c += integrate.quad(lambda th: -np.cos(th), ts, np.pi, epsabs=1e-14)[0]
        return 2 / np.pi * c / Ab

    Ab = np.array([0.05, 0.7, 1.2, 1.49, 1.5, 1.6, 2.4, 4.5, 9.0])
    out = _batch(MINDLIN, jnp.asarray(Ab * A0))
    np.testing.assert_allclose(out.K_bar, [kbar(a) for a in Ab], rtol=0, atol=1e-10)


@pytest.mark.usefixtures("storable_programs")
def test_limits_peaks_and_energy():
    small = jnp.asarray([1e-3, 1e-2]) * A0
    m = _batch(MINDLIN, small)
    # small-amplitude expansion (docs/reproduction.md): K̄ ≈ 1 − Ā/6, C̄ ≈ 2Ā/9, errors O(Ā²)
    assert np.all(np.abs(m.K_bar - (1 - m.A_bar / 6)) < m.A_bar**2)
    assert np.all(np.abs(m.C_bar - 2 * m.A_bar / 9) < m.A_bar**2)
    # (the C̄ peaks are checked in test_wu2015.py, through the comparison that reports them)
    Ab = jnp.linspace(0.01, 8, 200)
    for el in (JENKINS, MINDLIN):
        out = _batch(el, Ab * A0)
        # W >= 0 (exactly 0 without slip, up to rounding); K̄ falls with Ā
        assert np.all(out.W >= -1e-14 * MU * N * A0) and np.all(np.diff(out.K_bar) <= 1e-15)
        np.testing.assert_allclose(out.C_bar, out.W / (KD * (Ab * A0) ** 2), rtol=1e-12)
    assert np.all(_batch(MINDLIN, Ab * A0).W > 0)  # microslip dissipates at every amplitude


def test_kbar_cbar_independent_of_frequency_and_load_scale():
    a = 2.2 * A0
    hb = jax.jit(tj.harmonic_balance)
    ref = hb(MINDLIN, a, OMEGA)
    other = hb(tj.Mindlin(2 * MU, 3 * N, 6 * KD), a, 5 * OMEGA)
    np.testing.assert_allclose([other.K_bar, other.C_bar], [ref.K_bar, ref.C_bar], rtol=1e-13)
    np.testing.assert_allclose(other.C_eq * 5 * OMEGA, 6 * ref.C_eq * OMEGA, rtol=1e-13)


def _params(x, cls):
    el = cls(x[0], x[1], x[2])
    out = tj.harmonic_balance(el, x[3], OMEGA)
    return jnp.stack([out.K_eq, out.C_eq])


_f = jax.jit(_params, static_argnums=1)
_jf = jax.jit(jax.jacfwd(_params), static_argnums=1)
_jr = jax.jit(jax.jacrev(_params), static_argnums=1)


@pytest.mark.parametrize("cls", [tj.Jenkins, tj.Mindlin], ids=["jenkins", "mindlin"])
@pytest.mark.parametrize("Ab", [0.5, 0.999, 1.001, 1.499, 1.501, 2.0, 4.0])
@pytest.mark.usefixtures("storable_programs")
def test_gradients_match_central_differences(cls, Ab):
    x = np.array([MU, N, KD, Ab * A0])
    J = np.asarray(_jf(jnp.asarray(x), cls))
    # elasticity scale |y|/x of each entry: derivatives that vanish (K_eq = K_d without slip)
    # come out as rounding noise of about 1e-15 of it
    S = np.abs(np.asarray(_f(jnp.asarray(x), cls)))[:, None] / x[None, :]
    np.testing.assert_allclose(_jr(jnp.asarray(x), cls), J, rtol=1e-9, atol=1e-12 * S.max())
    h = 1e-6 * x
    for j in range(4):
        e = np.zeros(4)
        e[j] = h[j]
        fd = (np.asarray(_f(x + e, cls)) - np.asarray(_f(x - e, cls))) / (2 * h[j])
        # central FD: truncation ~ h^2 f''' ~ 1e-12 relative, rounding ~ 1e-16/1e-6 = 1e-10
        np.testing.assert_allclose(J[:, j], fd, rtol=1e-6, atol=1e-7 * S[:, j].max())


@pytest.mark.parametrize("cls", [tj.Jenkins, tj.Mindlin], ids=["jenkins", "mindlin"])
def test_gradients_finite_at_branch_onsets(cls):
    for Ab in (1.0, 1.5):  # gross-slip onset of Jenkins and Mindlin: θ* = π, arccos'(−1) = ∞
        J = _jf(jnp.array([MU, N, KD, Ab * A0]), cls)
        assert np.all(np.isfinite(J)), (Ab, J)
        g = jax.grad(lambda a: tj.harmonic_balance(cls(MU, N, KD), a, OMEGA).C_bar)(Ab * A0)
        assert np.isfinite(g)


@pytest.mark.usefixtures("storable_programs")
def test_jit_vmap_and_grad_under_vmap():
    A = jnp.asarray([0.3, 1.0, 1.5, 2.7]) * A0
    hb = jax.jit(tj.harmonic_balance)
    eager = tj.harmonic_balance(MINDLIN, A[2], OMEGA)
    assert float(hb(MINDLIN, A[2], OMEGA).C_bar) == pytest.approx(float(eager.C_bar), rel=1e-14)
    loop = [hb(MINDLIN, a, OMEGA) for a in A]
    batch = _batch(MINDLIN, A)
    np.testing.assert_allclose(batch.K_bar, [float(e.K_bar) for e in loop], rtol=1e-14)
    np.testing.assert_allclose(batch.C_eq, [float(e.C_eq) for e in loop], rtol=1e-14)

    def cbar(el, a):
        return tj.harmonic_balance(el, a, OMEGA).C_bar

    grad = jax.jit(jax.grad(cbar, argnums=1))
    g = jax.jit(jax.vmap(jax.grad(cbar, argnums=1), in_axes=(None, 0)))(MINDLIN, A)
    np.testing.assert_allclose(g, [grad(MINDLIN, a) for a in A], rtol=1e-12)
    # a batch of elements (vmap over μ) with eqx.filter_vmap
    els = eqx.filter_vmap(lambda m: tj.Mindlin(m, N, KD))(jnp.asarray([0.2, 0.3]))
    out = eqx.filter_vmap(lambda el: tj.harmonic_balance(el, A[1], OMEGA))(els)
    assert float(out.K_eq[1]) == pytest.approx(float(loop[1].K_eq), rel=1e-13)


@pytest.mark.parametrize("bad", [dict(A=0.0), dict(A=-1e-6), dict(omega=0.0), dict(omega=-3.0)])
def test_bad_drive_is_refused(bad):
    kw = dict(A=1e-6, omega=OMEGA) | bad
    name = next(iter(bad))
    with pytest.raises(ValueError, match=rf"{name} = .* outside the allowed range \(0, inf\)"):
        tj.harmonic_balance(JENKINS, kw["A"], kw["omega"])
    with pytest.raises(Exception, match=rf"{name} is outside the allowed range"):
        jax.jit(tj.harmonic_balance)(JENKINS, jnp.asarray(kw["A"]), jnp.asarray(kw["omega"]))


@pytest.mark.parametrize("field, value", [("mu", 0.0), ("N", -1.0), ("K_d", 0.0)])
def test_bad_element_is_refused(field, value):
    kw = dict(mu=MU, N=N, K_d=KD) | {field: value}
    for cls in (tj.Jenkins, tj.Mindlin):
        with pytest.raises(ValueError, match=rf"{field} = .* outside the allowed range \(0, inf\)"):
            cls(**kw)
    with pytest.raises(TypeError, match="harmonic_response"):
        tj.harmonic_balance(object(), 1e-6)
