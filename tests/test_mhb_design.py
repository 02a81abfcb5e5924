"""Design derivatives through the MHB solution (implicit function theorem) against finite
differences, and the optimal normal load against a brute-force sweep (long forms only; the CI
form of the IFT check is test_mhb.py::test_amplitude_gradients_by_implicit_function_theorem)."""

import json
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj

FULL = os.environ.get("TRIBOJAX_FULL") == "1"


def sdof(N, K_d=100.0):
    structure = tj.Structure(1.0, 0.2, 100.0)
    contact = tj.FrictionContact(tj.Jenkins(0.3, N, K_d), 0)
    return tj.FrictionSystem(structure, [contact], tj.Excitation(1, cosine=[1.0]),
                             harmonics=(1, 3), n_time=32)  # fmt: skip


@pytest.mark.slow
@pytest.mark.skipif(not FULL, reason="long form only (TRIBOJAX_FULL=1): ~35 s of compilation")
def test_resonance_peak_derivatives_against_finite_differences():
    # peak frequency and amplitude as functions of (N, K_d): IFT through the MHB solution and
    # through the peak condition ∂a/∂ω = 0, against central differences of the converged peaks
    @eqx.filter_jit
    def peak(p):
        pk = tj.resonance_peak(sdof(p[0], p[1]), 10.7, bracket=(10.0, 12.0))
        return jnp.stack([pk.omega, pk.amplitude]), pk.result

    p = jnp.array([3.0, 100.0])
    J = jax.jacfwd(lambda q: peak(q)[0])(p)
    assert peak(p)[1] == tj.RESULTS.successful
    for i in range(2):
        h = 1e-5 * float(p[i])
        fd = (peak(p.at[i].add(h))[0] - peak(p.at[i].add(-h))[0]) / (2 * h)
        np.testing.assert_allclose(np.asarray(J[:, i]), np.asarray(fd), rtol=2e-4)
    assert J[1, 0] < 0  # below the optimum load: more load, lower peak


@pytest.mark.slow
@pytest.mark.skipif(not FULL, reason="long form only (TRIBOJAX_FULL=1)")
def test_optimal_normal_load_against_sweep():
    grid = jnp.linspace(8.0, 18.0, 26)
    design = tj.minimise_peak(lambda q: sdof(q[0]), [3.0], grid)
    assert design.result == tj.RESULTS.successful
    # brute force: continuation (no IFT, no peak refinement) at loads around the optimum
    loads = np.linspace(3.5, 6.5, 13)
    peaks = [tj.frequency_response(sdof(N), 8.0, 18.0, ds_max=0.02).peak()[1] for N in loads]
    j = int(np.argmin(peaks))
    assert loads[j - 1] <= float(design.params[0]) <= loads[j + 1]
    assert float(design.peak.amplitude) <= min(peaks) * 1.001


@pytest.mark.slow
@pytest.mark.skipif(not FULL, reason="long form only (TRIBOJAX_FULL=1)")
def test_frf_2dof_study(tmp_path):
    from fitting import frf_2dof

    assert frf_2dof.main(["--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "frf_2dof.json").read_text())
    for F in ("0.5", "1.0", "10.0", "25.0", "50.0", "80.0", "100.0", "300.0"):
        c = res[F]
        assert c["result"] == "successful" and len(c["omega"]) == len(c["amplitude"])
        assert max(r["rel_diff"] for r in c["time_check"]) < 0.01
