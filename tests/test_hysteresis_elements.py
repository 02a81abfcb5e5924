"""Jenkins and Mindlin elements: steady loops (wu2015 Eqs 1–2), rate form, time-domain drive."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj

MU, N, KD = 0.3, 2.94, 1.2e6
MUN, A0 = MU * N, MU * N / KD
ELEMENTS = [tj.Jenkins(MU, N, KD), tj.Mindlin(MU, N, KD)]
IDS = ["jenkins", "mindlin"]
loop_fn = jax.jit(jax.vmap(lambda el, th, A: el.steady_loop(th, A), in_axes=(None, 0, None)))


@pytest.mark.parametrize("el", ELEMENTS, ids=IDS)
@pytest.mark.parametrize("Ab", [0.4, 1.0, 1.3, 1.5, 2.0, 5.0])
def test_loop_closes_is_odd_and_continuous(el, Ab):
    A = Ab * A0
    th = jnp.linspace(0.0, 2 * np.pi, 4001)
    f = np.asarray(loop_fn(el, th, A))
    assert f[0] == pytest.approx(f[-1], abs=1e-12 * MUN)  # closes after one cycle
    # odd symmetry f(θ + π) = −f(θ)
    np.testing.assert_allclose(f[2000:], -f[:2001], atol=1e-12 * MUN)
    # continuity: no jump larger than the steepest slope allows (K_d·A·dθ)
    assert np.max(np.abs(np.diff(f))) <= KD * A * float(th[1]) * (1 + 1e-9)
    assert np.max(np.abs(f)) <= MUN * (1 + 1e-14)
    # continuity at θ*, the onset of gross slip, from both sides
    ts = float(el.branch_angle(A))
    if ts < np.pi:
        eps = 1e-9
        left, right = loop_fn(el, jnp.array([ts - eps, ts + eps]), A)
        assert abs(left - right) < 1e-6 * MUN and right == pytest.approx(-MUN, rel=1e-14)


def test_jenkins_branches_match_corrected_eq1():
    el, Ab = ELEMENTS[0], 3.0
    A = Ab * A0
    ts = np.arccos(1 - 2 / Ab)
    th = np.array([0.3 * ts, 0.9 * ts, 0.5 * (ts + np.pi), np.pi + 0.5 * ts, np.pi + ts + 0.1])
    u = A * np.cos(th)
    # wu2015 Eq 1 with the third branch −μN + K_d(u + A) (printed: u − A)
    want = [MUN + KD * (u[0] - A), MUN + KD * (u[1] - A), -MUN, -MUN + KD * (u[3] + A), MUN]
    np.testing.assert_allclose(loop_fn(el, jnp.asarray(th), A), want, rtol=1e-13)


def test_mindlin_loop_peaks_at_fstar_and_matches_koh_form():
    el = ELEMENTS[1]
    for Ab in (0.5, 1.2, 2.5):
        A = Ab * A0
        fstar = MUN * (1 - max(1 - 2 * Ab / 3, 0) ** 1.5)  # f* of wu2015 Section 2
        assert float(el.steady_loop(0.0, A)) == pytest.approx(fstar, rel=1e-14)
        assert float(el.steady_loop(np.pi, A)) == pytest.approx(-fstar, rel=1e-14)
        # Koh form on the falling branch: f* − 2μN[1 − (1 − (A − u)/(3A0))^(3/2)]
        u = A * np.cos(0.4)
        want = fstar - 2 * MUN * (1 - (1 - (A - u) / (3 * A0)) ** 1.5)
        assert float(el.steady_loop(0.4, A)) == pytest.approx(max(want, -MUN), rel=1e-13)
    # initial slope after reversal is K_d (so A0 = μN/K_d)
    A, d = 2.0 * A0, 1e-7 * A0
    slope = (float(el.falling_branch(A, A)) - float(el.falling_branch(A - d, A))) / d
    assert slope == pytest.approx(KD, rel=1e-6)


@pytest.mark.parametrize("el", ELEMENTS, ids=IDS)
def test_time_domain_drive_settles_on_the_steady_loop(el):
    """From rest at u = 0, Masing elements reach the steady loop after the first quarter cycle."""
    A = 2.2 * A0
    th = jnp.linspace(-0.5 * np.pi, 4 * np.pi, 2701)  # u = A cos θ from u = 0, two cycles
    f = tj.drive(el, A * jnp.cos(th))
    steady = loop_fn(el, th, A)
    last = th >= 0.0
    # Jenkins steps exactly; Mindlin's Iwan discretisation (256 elements) interpolates the
    # branches, error ~ (spacing)² · curvature ≈ 1e-5 μN
    tol = 1e-12 if isinstance(el, tj.Jenkins) else 3e-5
    np.testing.assert_allclose(f[last], steady[last], atol=tol * MUN)


@jax.jit
def _euler(el, u, t):
    def step(s, inp):
        du, dt = inp
        s = s + dt * el.state_rate(s, du / dt)
        return s, el.force(s, du / dt)

    s0 = el.initial_state()
    _, f = jax.lax.scan(step, s0, (jnp.diff(u), jnp.diff(t)))
    return jnp.concatenate([el.force(s0, 0.0)[None], f])


@pytest.mark.parametrize("el", ELEMENTS, ids=IDS)
def test_rate_form_agrees_with_increment(el):
    """Explicit Euler on state_rate converges to the exact increment (rate form is consistent)."""
    u = 1.7 * A0 * np.sin(np.linspace(0, 3 * np.pi, 6001))
    t = np.linspace(0, 1.0, 6001)
    exact = tj.drive(el, u)
    forces = _euler(el, jnp.asarray(u), jnp.asarray(t))
    # Euler overshoots a slip limit by at most one step |du| ≤ 1.7 A0·3π/6000: error O(K_d du)
    np.testing.assert_allclose(forces, exact, atol=KD * 1.7 * A0 * 3 * np.pi / 6000 * 1.01)


class Maxwell(tj.AbstractFrictionElement):
    """Test-only rate-dependent element: spring k in series with a dashpot c (state: spring
    deflection). Under u = A cos ωt, K_eq = k(ωτ)²/(1 + (ωτ)²) and ωC_eq = k ωτ/(1 + (ωτ)²),
    τ = c/k: an analytic oracle for the RK4 route of harmonic_response."""

    k: float
    c: float

    def initial_state(self):
        return jnp.zeros(())

    def state_rate(self, state, velocity):
        return velocity - self.k * state / self.c

    def force(self, state, velocity):
        return self.k * state


def test_harmonic_response_rk4_route_matches_maxwell_oracle():
    k, c, omega, A = 1e6, 2e3, 400.0, 1e-6
    wt = omega * c / k
    out = tj.harmonic_response(
        Maxwell(k, c), A, omega, cycles=6, steps_per_cycle=512, K_d=k, A0=1e-6
    )
    # transient decays as exp(−t/τ): 6 cycles = 6·2π/(ωτ) ≈ 47 time constants; RK4 error
    # O((ωh)^4) with ωh = 2π/512 ≈ 1e-2 gives ~1e-8 relative
    assert float(out.K_eq) == pytest.approx(k * wt**2 / (1 + wt**2), rel=1e-7)
    assert float(out.C_eq * omega) == pytest.approx(k * wt / (1 + wt**2), rel=1e-7)
    assert float(out.W) == pytest.approx(np.pi * A**2 * k * wt / (1 + wt**2), rel=1e-7)


@pytest.mark.parametrize("el", ELEMENTS, ids=IDS)
@pytest.mark.usefixtures("storable_programs")
def test_harmonic_response_matches_quadrature(el):
    A = jnp.asarray([0.6, 1.3, 2.4, 4.0]) * A0
    route = jax.jit(jax.vmap(lambda a: tj.harmonic_response(el, a, 100.0)))(A)
    quad = jax.vmap(lambda a: tj.harmonic_balance(el, a, 100.0))(A)
    # rectangle rule over a loop with kinks at θ*: O(n⁻²) = 6e-8 at n = 4096; Mindlin adds
    # the Iwan interpolation error (~5e-5 relative at Ā = 0.6, where C̄ is small)
    tol = 1e-6 if isinstance(el, tj.Jenkins) else 6e-5
    np.testing.assert_allclose(route.K_bar, quad.K_bar, atol=tol)
    np.testing.assert_allclose(route.C_bar, quad.C_bar, atol=tol)


def test_drive_input_checks():
    with pytest.raises(ValueError, match="sample times t"):
        tj.drive(Maxwell(1.0, 1.0), jnp.zeros(3))
    with pytest.raises(ValueError, match="A = -1e-06 m is outside"):
        tj.harmonic_response(ELEMENTS[0], -1e-6, 1.0)
    with pytest.raises(ValueError, match="omega = 0 rad/s is outside"):
        tj.harmonic_response(ELEMENTS[0], 1e-6, 0.0)
    with pytest.raises(ValueError, match="multiple of 4"):
        tj.harmonic_response(ELEMENTS[0], 1e-6, 1.0, steps_per_cycle=1001)
    with pytest.raises(ValueError, match="n_iwan"):
        tj.Mindlin(MU, N, KD, n_iwan=1)


def test_iwan_bank_is_mindlins_rate_form():
    el = tj.Mindlin(0.3, 10.0, 1e6, n_iwan=64)
    bank = tj.IwanBank.mindlin(64, el.A0, el.K_d)
    u = jnp.concatenate([jnp.linspace(0.0, 2.0, 40), jnp.linspace(2.0, -1.0, 60)]) * el.A0
    zs = bank.deflections(u)
    z = el.initial_state()
    for i in range(1, u.shape[0]):
        z = el.increment(z, u[i] - u[i - 1])
    np.testing.assert_allclose(np.asarray(zs[-1]), np.asarray(z), rtol=1e-12, atol=1e-20)
    # the virgin curve is the interpolant of φ at the slip limits
    f = [float(bank.force(zz)) for zz in zs[:40]]
    np.testing.assert_allclose(f, np.asarray(el.virgin_curve(u[:40])), rtol=1e-3, atol=1e-4)
