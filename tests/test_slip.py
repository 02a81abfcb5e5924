"""The reticle slip simulation (wang2022 Eq 27): limits, gradients, invariance and bad input."""

import diffrax as dfx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj

ROW = dict(F_s=0.7372, K_tau=2.1478e7, C_tau=708.8274)  # wang2022 Table 3, 2 kPa


@pytest.mark.parametrize("F_s", [3.21, 6.42])
@pytest.mark.usefixtures("storable_programs")
def test_steady_acceleration_slip_matches_quasistatic_limit(F_s):
    # alpha = 1, a = const: z = m a / K and dz/dx = 1 - z/z_max give
    # slip = -z_max ln(1 - m a / F_s); m a / F_s = 0.1 and 0.05 here (at 0.321 the ratchet
    # below is 1.4e-3).
    el = tj.PreSlipLuGre(F_s, 2e7, 700.0, 1.0)
    sol = tj.simulate_slip(el, ts=jnp.array([0.5]))
    zmax = F_s / 2e7
    expected = -zmax * np.log(1 - 0.321 / F_s)
    # the ring-down after the ramp's end ratchets the slip by ~1e-4 of it (hysteresis);
    # 5e-4 bounds that, the quasi-static formula ignores it.
    assert float(sol.slip[0]) == pytest.approx(expected, rel=5e-4)
    assert float(sol.z[0]) == pytest.approx(0.321 / 2e7, rel=1e-6)  # force balance K z = m a
    assert float(sol.friction[0]) == pytest.approx(0.321, rel=1e-6)


@pytest.mark.slow
def test_symmetric_cycle_and_load_ordering():
    p = jax.vmap(lambda f, k, c: tj.slip_phase_averages(tj.PreSlipLuGre(f, k, c)))(
        *(jnp.asarray(tj.wang2022_table(3)[k]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))
    )
    p = np.asarray(p)
    # a -> -a symmetry of the model: T4 ~ -T6 and T5 ~ -T7 (to ~1 %, the first half-cycle
    # starts from z = 0, the second from the z left after the first)
    np.testing.assert_allclose(p[:, 0], -p[:, 2], rtol=0.02)
    np.testing.assert_allclose(p[:, 1], -p[:, 3], rtol=0.02)
    assert np.all(np.diff(p[:, 0]) < 0)  # slip falls with the vacuum level (Table 4's trend)


def _phases(theta, **kw):
    """wang2022's phase averages (nm) of the element (F_s, K_τ, C_τ, α) = θ."""
    el = tj.PreSlipLuGre(theta[0], theta[1], theta[2], theta[3])
    return tj.slip_phase_averages(el, rtol=1e-8, atol=1e-18, **kw) * 1e9


_phases_jit = jax.jit(_phases)  # one program for the tests below


@pytest.mark.usefixtures("storable_programs")
def test_gradients_of_phase_averages_match_finite_differences():
    phases, f = _phases, _phases_jit
    theta = jnp.array([ROW["F_s"], ROW["K_tau"], ROW["C_tau"], 1.2])
    J = np.asarray(jax.jit(jax.jacrev(phases))(theta))  # default adjoint
    for i in range(4):
        h = 1e-4 * float(theta[i])
        e = jnp.zeros(4).at[i].set(h)
        fd = (np.asarray(f(theta + e)) - np.asarray(f(theta - e))) / (2 * h)
        scale = np.abs(np.asarray(f(theta))) / float(theta[i])  # |T| / |theta|
        # elasticities d ln T / d ln theta are O(0.1-1); FD truncation (h^2) and the solver
        # tolerance (rtol 1e-8 over a 1e-4 step) allow ~1e-3 of the scale (measured 3e-6 of
        # the largest elasticity)
        np.testing.assert_allclose(J[:, i], fd, atol=2e-3 * scale.max())
    assert np.all(np.isfinite(J))


@pytest.mark.slow
def test_reverse_and_forward_phase_averages_agree_to_rounding():
    def phases(theta):
        el = tj.PreSlipLuGre(theta[0], theta[1], theta[2], theta[3])
        return tj.slip_phase_averages(el, rtol=1e-8, atol=1e-18) * 1e9

    theta = jnp.array([ROW["F_s"], ROW["K_tau"], ROW["C_tau"], 1.2])
    J = np.asarray(jax.jit(jax.jacrev(phases))(theta))
    J_fwd = np.asarray(jax.jit(jax.jacfwd(phases))(theta))
    # Rodas4's derivatives come from forward mode in both directions (simulate_slip's
    # custom_jvp): reverse and forward agree to rounding (measured 2e-16 of the largest
    # elasticity), which a recomputing reverse pass does not achieve (6e-3, see Rodas4)
    elasticity = np.abs(J_fwd * np.asarray(theta)).max()
    np.testing.assert_allclose(
        J * np.asarray(theta), J_fwd * np.asarray(theta), atol=1e-9 * elasticity
    )


@pytest.mark.slow
def test_derivatives_wrt_mass_profile_and_save_times():
    # Through the forward-mode rule: mass, a profile parameter and the save times (dy/dts = f)
    el = tj.PreSlipLuGre(**ROW)

    def out(p):
        prof = tj.TrapezoidProfile(a_max=p[1])
        ts = jnp.array([0.2, 0.3]) + p[2]
        sol = tj.simulate_slip(el, prof, p[0], ts=ts, t_end=0.4, rtol=1e-9, atol=1e-18)
        return jnp.concatenate([sol.slip, sol.velocity]) * 1e9

    p = jnp.array([0.321, 1.0, 0.0])
    jr = np.asarray(jax.jit(jax.jacrev(out))(p))
    jf = np.asarray(jax.jit(jax.jacfwd(out))(p))
    np.testing.assert_allclose(jr, jf, rtol=1e-12, atol=1e-12 * np.abs(jf).max())
    f = jax.jit(out)
    # (steps of 1e-4 in m and a_max: at 1e-5 the adaptive solver's rtol 1e-9 over the step left
    # 1.1e-4 of FD noise in the a_max column with jax 0.10.2 / diffrax 0.7.2; at 1e-4: 1.2e-6)
    for i, h in enumerate((1e-4, 1e-4, 1e-6)):
        e = jnp.zeros(3).at[i].set(h)
        fd = (np.asarray(f(p + e)) - np.asarray(f(p - e))) / (2 * h)
        # FD truncation and solver noise: 1e-4 of the column's scale
        np.testing.assert_allclose(jf[:, i], fd, atol=1e-4 * np.abs(fd).max())
    assert np.all(np.abs(jf[:2, 0]) > 0) and np.all(np.abs(jf[:2, 1]) > 0)


@pytest.mark.usefixtures("storable_programs")
def test_jit_and_vmap_invariance():
    thetas = jnp.array([[f, ROW["K_tau"], ROW["C_tau"], 1.0] for f in (0.6, 0.9)])
    batched = np.asarray(jax.vmap(_phases)(thetas))
    loop = [np.asarray(_phases(theta)) for theta in thetas]
    # vmapped adaptive stepping takes the union of the steps: agreement to the tolerance
    np.testing.assert_allclose(batched, np.stack(loop), rtol=1e-5)
    # an outer jit changes XLA's fusion and rounding; the adaptive steps then differ, so the
    # results agree to the solver tolerance (measured 2e-6), not to rounding
    np.testing.assert_allclose(np.asarray(_phases_jit(thetas[0])), loop[0], rtol=1e-5)


@pytest.mark.slow
def test_forward_mode_with_forward_adjoint():
    def t4(alpha, adjoint=dfx.RecursiveCheckpointAdjoint()):
        el = tj.PreSlipLuGre(ROW["F_s"], ROW["K_tau"], ROW["C_tau"], alpha)
        return tj.slip_phase_averages(el, adjoint=adjoint)[0]

    d_fwd = float(jax.jacfwd(lambda a: t4(a, dfx.ForwardMode()))(1.2))
    d_rev = float(jax.grad(t4)(1.2))
    # with Rodas4 both directions use forward mode (the adjoint only picks the primal solve)
    assert d_fwd == pytest.approx(d_rev, rel=1e-9)
    assert d_fwd > 0  # a larger alpha softens the bristle law: more slip


def test_bad_input():
    el = tj.PreSlipLuGre(**ROW)
    with pytest.raises(ValueError, match="mass"):
        tj.simulate_slip(el, mass=0.0)
    with pytest.raises(ValueError, match="mass"):
        tj.simulate_slip(el, mass=-1.0)
    with pytest.raises(ValueError, match="ts must be non-decreasing"):
        tj.simulate_slip(el, ts=jnp.array([0.0, 1.0, 0.5]))
    with pytest.raises(ValueError, match="NaN"):
        tj.simulate_slip(el, tj.PiecewiseLinearProfile([0.0, 1.0], [0.0, float("nan")]))
    with pytest.raises(ValueError, match="alpha"):
        tj.PreSlipLuGre(**ROW, alpha=0.0)
    with pytest.raises(ValueError, match="rtol"):
        tj.simulate_slip(el, rtol=0.0)
    with pytest.raises(ValueError, match="solver"):
        tj.simulate_slip(el, solver="euler")


def test_solver_failure_is_reported():
    el = tj.PreSlipLuGre(**ROW)
    with pytest.raises(Exception, match="max_steps"):
        tj.simulate_slip(el, max_steps=20)
    sol = tj.simulate_slip(el, max_steps=20, throw=False)
    assert not bool(sol.ok)
    assert "max_steps" in sol.message


@pytest.mark.slow
def test_forward_jacobian_adjoint_with_kvaerno5():
    # the adjoint object also gives reverse mode through a solver other than Rodas4
    adj = tj.ForwardJacobianAdjoint()

    def t4(alpha):
        el = tj.PreSlipLuGre(ROW["F_s"], ROW["K_tau"], ROW["C_tau"], alpha)
        ts = jnp.array([0.3, 0.6])
        return tj.simulate_slip(el, ts=ts, t_end=0.7, solver="kvaerno5", adjoint=adj).slip[-1]

    assert float(jax.grad(t4)(1.2)) == pytest.approx(float(jax.jacfwd(t4)(1.2)), rel=1e-12)
    with pytest.raises(ValueError, match="adjoint"):
        tj.simulate_slip(tj.PreSlipLuGre(**ROW), adjoint="forward")
