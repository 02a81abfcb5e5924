"""Multi-harmonic balance of friction-damped structures: AFT, continuation, Hill stability, checks
against independent references (first-harmonic quadrature, diffrax and fixed-step time
integration) and bad input."""

import diffrax
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj


def sdof(N=1.0, F=0.5, H=7, K_d=100.0, n_time=None):
    structure = tj.Structure(1.0, 1.0, 100.0)  # ω_n = 10 rad/s, ζ = 0.05
    contact = tj.FrictionContact(tj.Jenkins(1.0, N, K_d), 0)  # A0 = μN/K_d = 0.01 m at N = 1
    return tj.FrictionSystem(structure, [contact], tj.Excitation(1, cosine=[F]), H=H, n_time=n_time)


@pytest.mark.parametrize("element", [tj.Jenkins(0.3, 10.0, 1e3), tj.Mindlin(0.3, 10.0, 1e3)])
@pytest.mark.usefixtures("storable_programs")
def test_single_harmonic_aft_equals_harmonic_balance(element):
    # H = {1}: the AFT's first harmonic of the element's steady loop is K_eq·A and −C_eq·A·ω of
    # the quadrature route `harmonic_balance` (no FFT there), stick to gross slip
    system = tj.FrictionSystem(
        tj.Structure(1.0, 0.0, 1.0), [tj.FrictionContact(element, 0)], harmonics=(1,), n_time=4096
    )
    for A_bar in (0.5, 1.5, 3.0, 20.0):
        A = A_bar * float(element.A0)
        f = np.asarray(system.contact_forces(jnp.array([[A, 0.0]]), 2.0))[0]
        hb = tj.harmonic_balance(element, A, 2.0)
        K_bar, C_bar = f[0] / A / float(element.K_d), -np.pi * f[1] / A / float(element.K_d)
        # Jenkins' kinks: O(n_time⁻²); Mindlin's rate form is a 256-element Iwan bank
        tol = 2e-5 if isinstance(element, tj.Jenkins) else 2e-3
        assert K_bar == pytest.approx(float(hb.K_bar), abs=tol)
        assert C_bar == pytest.approx(float(hb.C_bar), abs=tol)


def _diffrax_amplitude(F, omega, N=1.0, K_d=100.0, periods=60):
    """Steady first-harmonic amplitude of the SDOF Jenkins system by adaptive diffrax (Tsit5)
    integration of the element's rate form (ż = v unless sliding) from rest."""
    el = tj.Jenkins(1.0, N, K_d)

    def rhs(t, y, args):
        x, v, z = y
        a = F * jnp.cos(omega * t) - 1.0 * v - 100.0 * x - el.force(z, v)
        return jnp.stack([v, a, el.state_rate(z, v)])

    T = 2 * jnp.pi / omega
    ts = (periods - 1) * T + T * jnp.arange(256) / 256
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        diffrax.Tsit5(),
        0.0,
        periods * T,
        1e-3,
        jnp.zeros(3),
        saveat=diffrax.SaveAt(ts=ts),
        max_steps=400_000,
        stepsize_controller=diffrax.PIDController(rtol=1e-9, atol=1e-12),
    )
    x = sol.ys[:, 0]
    th = omega * ts
    return jnp.hypot(2 * jnp.mean(x * jnp.cos(th)), 2 * jnp.mean(x * jnp.sin(th)))


# (F, ω): stick (A < A0), stick–slip (A ~ 2–3 A0) and gross slip (A ~ 40 A0), around each peak
CASES = [(0.1, 13.5), (0.1, 14.2), (1.0, 11.5), (1.0, 12.5), (5.0, 9.8), (5.0, 10.3)]


@pytest.mark.slow
def test_sdof_jenkins_against_diffrax():
    Fs, ws = (jnp.array(v) for v in zip(*CASES))
    ref = np.asarray(jax.jit(jax.vmap(_diffrax_amplitude))(Fs, ws))
    for (F, w), a_ref in zip(CASES, ref):
        sol = tj.solve_hbm(sdof(F=F), w)
        assert bool(sol.converged)
        a = float(sdof(F=F).amplitude(sol.X)[0])
        regime = a / 0.01
        print(f"F={F} ω={w} A/A0={regime:.3f} rel.diff={abs(a / a_ref - 1):.2e}")
        assert a == pytest.approx(a_ref, rel=0.01), (F, w, regime)
    assert ref[0] < 0.01 and 1.2 < ref[3] / 0.01 < 5 and ref[5] > 0.2  # the three regimes


@pytest.mark.slow
def test_continuation_passes_resonance_and_matches_time_stepping():
    system = sdof(F=0.5, H=5)
    fr = tj.frequency_response(system, 6.0, 18.0)
    assert fr.converged and fr.omega[0] == 6.0 and fr.omega[-1] <= 18.0
    assert fr.omega[-1] > 17.0 and np.all(fr.stable)
    w_peak, a_peak = fr.peak()
    # resonance between slip (10 rad/s) and stick (√200 = 14.1 rad/s), slipping (A > A0)
    assert 10.0 < w_peak < 14.1 and a_peak > 0.01
    x = np.asarray(tj.integrate_steady(system, w_peak, 80, 1024))
    th = 2 * np.pi * np.arange(1024) / 1024
    a_t = np.hypot(2 * np.mean(x[:, 0] * np.cos(th)), 2 * np.mean(x[:, 0] * np.sin(th)))
    assert a_peak == pytest.approx(a_t, rel=5e-3)
    d = fr.to_dict()
    assert d["result"] == "successful" and len(d["omega"]) == len(d["stable"])


@pytest.mark.usefixtures("storable_programs")
def test_hill_exponents_of_a_linear_structure():
    # no contact: x = e^{λt}, λ = −ζω_n ± iω_d; Hill's method gives Re λ = −C/(2M) exactly
    for C in (1.0, -0.4):
        system = tj.FrictionSystem(
            tj.Structure(2.0, C, 50.0), [], tj.Excitation(1, cosine=[1.0]), H=4
        )
        X = tj.solve_hbm(system, 3.0).X
        lam = tj.floquet_exponents(system, X, 3.0)
        assert np.allclose(lam.real, -C / 4.0, atol=1e-9)
        # imaginary parts are defined up to multiples of ω: compare modulo ω
        w_d = np.sqrt(25.0 - C**2 / 16.0)

        def dist(x):
            return np.abs((x + 1.5) % 3.0 - 1.5)

        assert np.all(np.minimum(dist(lam.imag - w_d), dist(lam.imag + w_d)) < 1e-9)


@pytest.mark.usefixtures("storable_programs")
def test_amplitude_gradients_by_implicit_function_theorem():
    def amp(p):
        N, mu, K_d, k = p
        structure = tj.Structure(1.0, 1.0, k)
        contact = tj.FrictionContact(tj.Jenkins(mu, N, K_d), 0)
        system = tj.FrictionSystem(structure, [contact], tj.Excitation(1, cosine=[1.0]), H=3)
        return tj.amplitude_at(system, 12.0)

    p = jnp.array([1.0, 1.0, 100.0, 100.0])
    g = np.asarray(jax.jit(jax.grad(amp))(p))
    f = jax.jit(amp)
    for i in range(4):
        h = 1e-5 * float(p[i])
        fd = (float(f(p.at[i].add(h))) - float(f(p.at[i].add(-h)))) / (2 * h)
        assert g[i] == pytest.approx(fd, rel=1e-5, abs=1e-12)
    assert g[0] < 0  # at 12 rad/s (slipping, above the slip resonance) more load, less motion


def test_bad_input():
    with pytest.raises(ValueError, match="positive definite"):
        tj.Structure([[1.0, 0.0], [0.0, -1.0]], np.zeros((2, 2)), np.eye(2))
    with pytest.raises(ValueError, match="H = 0"):
        sdof(H=0)
    with pytest.raises(ValueError, match="DOF 3"):
        tj.FrictionSystem(
            tj.Structure(1.0, 1.0, 1.0), [tj.FrictionContact(tj.Jenkins(1, 1, 1), 3)], H=2
        )
    with pytest.raises(ValueError, match="frequency range"):
        tj.frequency_response(sdof(H=2), -1.0, 5.0)
    with pytest.raises(ValueError, match="frequency range"):
        tj.frequency_response(sdof(H=2), 5.0, 5.0)
    with pytest.raises(ValueError, match="n_time"):
        sdof(H=8, n_time=16)
    fr = tj.frequency_response(sdof(H=2), 6.0, 18.0, max_points=5, stability=False)
    assert fr.result == tj.RESULTS.continuation_incomplete and not fr.converged
    assert len(fr.omega) == 5 and np.all(np.isfinite(fr.amplitude))
