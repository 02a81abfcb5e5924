"""Multi-harmonic balance beyond the force-driven Jenkins SDOF: base excitation, a rate-dependent
LuGre contact and continuation in the normal load. Each is checked against adaptive diffrax
integration of the equations of motion written here independently of `tribojax._dynamics`
(absolute coordinates for the base-driven case; the LuGre ODE integrated with the structure)."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj

M, C, K = 1.0, 1.0, 100.0  # ω_n = 10 rad/s, ζ = 0.05


def _steady_amplitude(rhs, n_state, omega, signal, periods=60):
    """First-harmonic amplitude of `signal(t, y)` over the last period of a diffrax Tsit5 run."""
    T = 2 * jnp.pi / omega
    ts = (periods - 1) * T + T * jnp.arange(512) / 512
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        diffrax.Tsit5(),
        0.0,
        periods * T,
        1e-3,
        jnp.zeros(n_state),
        saveat=diffrax.SaveAt(ts=ts),
        max_steps=500_000,
        stepsize_controller=diffrax.PIDController(rtol=1e-9, atol=1e-12),
    )
    x = jax.vmap(signal)(ts, sol.ys)
    th = omega * ts
    return jnp.hypot(2 * jnp.mean(x * jnp.cos(th)), 2 * jnp.mean(x * jnp.sin(th)))


def _jenkins_base_reference(B, omega, N=1.0, K_d=100.0):
    # absolute displacement y; the ground moves as x_b = B cos ωt; the spring, damper and the
    # Jenkins contact act on y − x_b; amplitude of the relative motion
    el = tj.Jenkins(1.0, N, K_d)

    def rhs(t, s, args):
        y, v, z = s
        x_b, v_b = B * jnp.cos(omega * t), -B * omega * jnp.sin(omega * t)
        v_rel = v - v_b
        a = (-C * v_rel - K * (y - x_b) - el.force(z, v_rel)) / M
        return jnp.stack([v, a, el.state_rate(z, v_rel)])

    return _steady_amplitude(rhs, 3, omega, lambda t, s: s[0] - B * jnp.cos(omega * t))


@pytest.mark.slow
@pytest.mark.parametrize("B, omega, slips", [(0.5 / 81.0, 9.0, False), (3.0 / 144.0, 12.0, True)])
def test_base_excitation_against_absolute_coordinates(B, omega, slips):
    contact = tj.FrictionContact(tj.Jenkins(1.0, 1.0, 100.0), 0)
    system = tj.FrictionSystem(tj.Structure(M, C, K), [contact], tj.Excitation(1, base=[B]), H=7)
    sol = tj.solve_hbm(system, omega)
    assert bool(sol.converged)
    a = float(system.amplitude(sol.X)[0])
    a_ref = float(jax.jit(_jenkins_base_reference)(B, omega))
    assert a == pytest.approx(a_ref, rel=0.01)
    assert (a > 0.01) == slips  # A0 = μN/K_d = 0.01 m: one case sticks, one slips


LUGRE = dict(sigma0=1e3, sigma1=30.0, sigma2=0.5, F_c=0.3, F_s=0.45, v_s=0.02)


def _lugre_reference(F, omega):
    el = tj.LuGre(**LUGRE)

    def rhs(t, s, args):
        x, v, z = s
        a = (F * jnp.cos(omega * t) - C * v - K * x - el.force(z, v)) / M
        return jnp.stack([v, a, el.state_rate(z, v)])

    return _steady_amplitude(rhs, 3, omega, lambda t, s: s[0])


def _lugre_amplitude(F, omega, H, n_time):
    contact = tj.FrictionContact(tj.LuGre(**LUGRE), 0, cycles=3, substeps=4)
    system = tj.FrictionSystem(
        tj.Structure(M, C, K), [contact], tj.Excitation(1, cosine=[F]), H=H, n_time=n_time
    )
    sol = tj.solve_hbm(system, omega)
    assert bool(sol.converged)
    return float(system.amplitude(sol.X)[0])


@pytest.mark.slow
def test_lugre_contact_against_time_integration():
    # gross sliding: H = 7 within 2 %; near stick (sharp force reversals) the truncation error
    # falls with H (measured: 2.3 % at H = 7, 1.1 % at 15, 0.25 % at 31)
    ref = jax.jit(_lugre_reference)
    assert _lugre_amplitude(2.0, 10.5, 7, 256) == pytest.approx(float(ref(2.0, 10.5)), rel=0.02)
    a_ref = float(ref(0.6, 9.0))
    err = [abs(_lugre_amplitude(0.6, 9.0, H, 2 * n) / a_ref - 1) for H, n in ((7, 128), (15, 256))]
    assert err[1] < 0.6 * err[0] and err[1] < 0.015, err


@pytest.mark.slow
def test_normal_load_continuation_against_time_integration():
    # at ω = 11 rad/s (between the slip resonance 10 and the stick one √200): the amplitude falls
    # as the load rises from gross slip towards stick
    def make(N):
        contact = tj.FrictionContact(tj.Jenkins(1.0, N, 100.0), 0)
        return tj.FrictionSystem(
            tj.Structure(M, C, K), [contact], tj.Excitation(1, cosine=[1.0]), H=5
        )

    fr = tj.parameter_response(make, 0.2, 3.0, 11.0)
    assert fr.converged and fr.parameter[0] == 0.2 and fr.parameter[-1] > 2.5
    assert np.all(fr.omega == 11.0)
    a = fr.amplitude[:, 0]
    assert a[-1] < 0.5 * a[0]
    el = tj.Jenkins  # the reference at two loads off the continuation's points

    def reference(N):
        e = el(1.0, N, 100.0)

        def rhs(t, s, args):
            x, v, z = s
            acc = (jnp.cos(11.0 * t) - C * v - K * x - e.force(z, v)) / M
            return jnp.stack([v, acc, e.state_rate(z, v)])

        return _steady_amplitude(rhs, 3, 11.0, lambda t, s: s[0])

    for N in (0.7, 2.2):
        a_branch = np.interp(N, fr.parameter, a)
        a_ref = float(jax.jit(reference)(N))
        assert a_branch == pytest.approx(a_ref, rel=0.01), N
