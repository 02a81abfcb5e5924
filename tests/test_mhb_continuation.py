"""Pseudo-arclength continuation through turning points: a hardening (Duffing) oscillator whose
forced response folds, against SciPy time integration and the single-harmonic Duffing equation,
with Hill stability on the three branches inside the fold."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tribojax as tj

C, K3, F = 0.1, 0.1, 0.3  # m = k = 1: ζ = 0.05, cubic spring k3 x³ (N/m³), force F cos ωt (N)
W_FOLD = 1.18  # rad/s, inside the fold (turning points at ≈ 1.153 and ≈ 1.213 rad/s)


class CubicSpring(tj.AbstractContact):
    """A history-free hardening spring f = k3·x[dof]³ (N) against the ground."""

    k3: jax.Array  # N/m³, >= 0
    dof: int = eqx.field(static=True)

    def dofs(self):
        return (self.dof,)

    def forces(self, x, period):
        return jnp.zeros_like(x).at[:, self.dof].set(self.k3 * x[:, self.dof] ** 3)

    def initial_state(self, n_dof):
        return ()

    def step(self, state, x):
        return state, jnp.zeros_like(x).at[self.dof].set(self.k3 * x[self.dof] ** 3)


def _steady_amplitude(omega, x0, v0, periods=40):
    """First-harmonic amplitude of x over the last of `periods` periods of ẍ + C ẋ + x + K3 x³ =
    F cos ωt from (x0, v0) (SciPy DOP853, rtol 1e-10): an independent time integration."""

    def rhs(t, y):
        return [y[1], F * np.cos(omega * t) - C * y[1] - y[0] - K3 * y[0] ** 3]

    T = 2 * np.pi / omega
    ts = (periods - 1) * T + T * np.arange(256) / 256
    sol = solve_ivp(
        rhs, (0.0, periods * T), [x0, v0], method="DOP853", rtol=1e-10, atol=1e-12, t_eval=ts
    )
    th = omega * ts
    return np.hypot(2 * np.mean(sol.y[0] * np.cos(th)), 2 * np.mean(sol.y[0] * np.sin(th)))


@pytest.mark.usefixtures("storable_programs")
def test_continuation_passes_the_folds_of_a_duffing_response():
    # harmonics 1 and 3 of a symmetric cubic; n_time = 16 is alias-free for x³ (harmonics <= 9)
    spring = CubicSpring(jnp.asarray(K3), 0)
    system = tj.FrictionSystem(
        tj.Structure(1.0, C, 1.0),
        [spring],
        tj.Excitation(1, cosine=[F]),
        harmonics=(1, 3),
        n_time=16,
    )
    fr = tj.frequency_response(system, 0.5, 2.0)
    assert fr.converged and fr.omega[-1] > 1.8
    w = fr.omega
    dw = np.sign(np.diff(w))
    turns = np.flatnonzero(dw[1:] != dw[:-1]) + 1  # points where ω reverses: the two folds
    assert len(turns) == 2
    lo, hi = w[turns[1]], w[turns[0]]
    assert 1.14 < lo < W_FOLD < hi < 1.23  # the hardening fold leans right
    # Hill: stable up to the upper fold, unstable between the folds, stable after the lower one
    # (one point of slack at each fold, where the Floquet exponent crosses zero)
    assert np.all(fr.stable[: turns[0]]) and np.all(fr.stable[turns[1] + 1 :])
    assert not np.any(fr.stable[turns[0] + 1 : turns[1]])

    # three branch points at ω = W_FOLD: upper, middle, lower
    cross = np.flatnonzero(np.diff(np.sign(w - W_FOLD)) != 0)
    assert len(cross) == 3
    upper, middle, lower = cross
    assert fr.stable[upper] and not fr.stable[middle + 1] and fr.stable[lower + 1]
    # the single-harmonic Duffing equation a²[(1 − ω² + ¾k3a²)² + (Cω)²] = F² (three roots)
    r = np.roots(
        [
            (0.75 * K3) ** 2,
            1.5 * K3 * (1 - W_FOLD**2),
            (1 - W_FOLD**2) ** 2 + (C * W_FOLD) ** 2,
            -(F**2),
        ]
    )
    backbone = np.sort(np.sqrt(r.real))[::-1]
    ks = np.array([1, 1, 3, 3])
    sine = np.array([False, True, False, True])
    for branch, i, ref_1h in zip(("upper", "middle", "lower"), cross, backbone):
        s = (W_FOLD - w[i]) / (w[i + 1] - w[i])
        sol = tj.solve_hbm(system, W_FOLD, fr.X[i] + s * (fr.X[i + 1] - fr.X[i]))
        assert bool(sol.converged)
        a_hbm = float(system.amplitude(sol.X)[0])
        # H = {1}'s equation omits the third harmonic: 1 % (it is 3 % of a on the upper branch)
        assert a_hbm == pytest.approx(ref_1h, rel=1e-2), branch
        if branch == "middle":
            continue
        # time integration from the HBM state stays on that branch (stable): the truncation
        # to harmonics 1 and 3 costs < 1e-5 relative (measured 5e-6 upper, 3e-9 lower)
        X = np.asarray(sol.X[0])
        x0, v0 = X[~sine].sum(), (ks[sine] * W_FOLD * X[sine]).sum()
        a_ref = _steady_amplitude(W_FOLD, x0, v0)
        print(f"{branch}: HBM {a_hbm:.6f}, SciPy {a_ref:.6f}, single-harmonic {ref_1h:.6f}")
        assert a_hbm == pytest.approx(a_ref, rel=1e-4), branch
