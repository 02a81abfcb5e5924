"""The diffrax slip simulation against an independent SciPy solve_ivp implementation (3 loads).

The reference is written here from wang2022 Eq 27 (docs/reproduction.md's reading) with the exact
sgn(v), state in nm, integrated segment by segment between the profile's kinks with Radau at
rtol 1e-11; the window means come from dense output integrated with quad.
"""

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

import tribojax as tj

KINKS = np.array([0.1, 0.25, 0.6, 0.75, 1.5, 1.65, 2.0, 2.15])
LEVELS = np.array([0, 1, 1, 0, 0, -1, -1, 0.0])
WINDOWS = [(0.25, 0.6), (0.73, 1.5), (1.65, 2.0)]
MASS = 0.321
T3 = tj.wang2022_table(3)


def reference(F_s, K, C, alpha=1.0):
    """Returns (dense solution pieces, [T4..T7] in nm)."""
    zmax = F_s / K * 1e9  # nm

    def rhs(t, y):
        x, v, z = y  # nm, nm/s, nm
        bracket = max(1.0 - np.sign(v) * z / zmax, 0.0)
        zdot = v * bracket**alpha
        force = K * z * 1e-9 + C * zdot * 1e-9  # N
        return [v, np.interp(t, KINKS, LEVELS) * 1e9 - force / MASS * 1e9, zdot]

    pieces, y = [], np.zeros(3)
    edges = np.concatenate([[0.0], KINKS, [2.3]])
    for a, b in zip(edges[:-1], edges[1:]):
        s = solve_ivp(
            rhs, (a, b), y, method="Radau", rtol=1e-11, atol=[1e-9, 1e-6, 1e-9], dense_output=True
        )
        assert s.success
        pieces.append((a, b, s.sol))
        y = s.y[:, -1]

    def slip(t):
        for a, b, sol in pieces:
            if a <= t <= b:
                return sol(t)[0]

    def mean(lo, hi):
        pts = [k for k in KINKS if lo < k < hi]
        return quad(slip, lo, hi, points=pts or None, limit=400, epsabs=1e-12)[0] / (hi - lo)

    m = [mean(*w) for w in WINDOWS]
    return slip, np.array([m[0] - slip(0.0), m[1] - m[0], m[2] - m[1], slip(2.3) - m[2]])


CASES = [(0, "rodas4"), (2, "rodas4"), (5, "rodas4"), (2, "kvaerno5")]


@pytest.mark.slow
@pytest.mark.parametrize("row,solver", CASES, ids=["0.6kPa", "4kPa", "20kPa", "4kPa-kvaerno5"])
def test_phase_averages_match_scipy_radau(row, solver):
    F_s, K, C = (float(T3[k][row]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))
    slip_ref, phases_ref = reference(F_s, K, C)
    el = tj.PreSlipLuGre(F_s, K, C)
    phases = np.asarray(tj.slip_phase_averages(el, solver=solver)) * 1e9
    # default tolerances (rtol 1e-6; atol 1e-15 m for Rodas4, 1e-16 m for Kvaerno5; velocity
    # atol x1e3) and the smooth sign (eps 1e-12 m/s, bias ~3e-8). Measured: Rodas4 1.5e-8 to
    # 6.1e-7 relative at Table 3's 0.6, 4, 20 kPa and alpha 1, 1.26, jitted or not (the issue's
    # bound is 1e-6); Kvaerno5 1.9e-7 to 9.7e-7 (3e-6 bounds it).
    np.testing.assert_allclose(phases, phases_ref, rtol=1e-6 if solver == "rodas4" else 3e-6)
    ts = np.array([0.2, 0.4, 0.7, 1.0, 1.6, 1.9, 2.1, 2.3])
    sol = tj.simulate_slip(el, ts=ts, solver=solver)
    want = np.array([slip_ref(t) for t in ts])
    # measured max |difference| 2.6e-5 nm (Rodas4), 3.1e-5 nm (Kvaerno5) at 0.6 kPa against slips
    # of 2-40 nm, i.e. ~1e-6 of the slip; 1e-4 nm bounds it (the phase averages above are the
    # accuracy-critical output)
    np.testing.assert_allclose(np.asarray(sol.slip) * 1e9, want, atol=1e-4)
