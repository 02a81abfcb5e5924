"""Fits to user data: parameters recovered from synthetic noisy records within 2 standard errors,
and standard errors calibrated (coverage over seeds)."""

import os

import numpy as np
import pytest

import tribojax as tj

# wang2022 Table 3 at 0.6 kPa (F_s N, K_τ N/m, C_τ N s/m); short records keep CI fast: the
# first second of the cycle (acceleration, hold, ramp down, cruise), sampled at 0.1 ms. The
# sampling must resolve the ~1 kHz ring-down after each jerk kink for C_τ to be determined: at
# 5 ms the cost has two minima in C_τ (≈ 570 and ≈ 7100 N s/m for seed 5, Δχ² ≈ 4).
TRUTH = {"F_s": 0.4868, "K_tau": 1.4878e7, "C_tau": 771.05}
SHORT = dict(n=10001, t_end=1.0)
NOISE = 2e-10  # m, ~1 % of the peak slip
ELEMENT = tj.PreSlipLuGre(*TRUTH.values())


def short_run(seed, alpha=1.0, **kw):
    el = tj.PreSlipLuGre(*TRUTH.values(), alpha)
    return tj.synthetic_slip_run(el, noise=NOISE, seed=seed, **SHORT, **kw)


@pytest.fixture(scope="module")
def run():
    return short_run(101)


def test_start_is_close_to_the_truth(run):
    start = tj.slip_run_start(run)
    assert set(start) == {"F_s", "K_tau", "C_tau"}
    # quasi-static F_s and K_τ within a few %, the damping only to a factor of ~6
    assert start["F_s"] == pytest.approx(TRUTH["F_s"], rel=0.05)
    assert start["K_tau"] == pytest.approx(TRUTH["K_tau"], rel=0.05)
    assert 1 / 8 < start["C_tau"] / TRUTH["C_tau"] < 8


@pytest.mark.slow
def test_fit_slip_run_recovers_parameters(run):
    messages = []
    fit = tj.fit_slip_run(run, alpha=1.0, progress=messages.append)
    assert fit.converged, fit.message
    assert fit.names == ("F_s", "K_tau", "C_tau") and fit.fixed == {"alpha": 1.0}
    truth = np.array(list(TRUTH.values()))
    z = (fit.values - truth) / fit.std_errors
    assert np.all(np.abs(z) < 2), z
    # the noise is known (run.noise_std): residuals in units of σ, chi² per point ≈ 1 ± 0.2
    assert np.mean(fit.residuals**2) == pytest.approx(1.0, abs=0.2)
    # F_s and K_τ to better than 0.2 %, C_τ to ~10 %
    assert np.all(fit.std_errors[:2] / truth[:2] < 2e-3) and fit.std_errors[2] / truth[2] < 0.2
    assert any(m.startswith("LM:") for m in messages) and messages[0].startswith("start")
    assert fit.result == tj.RESULTS.successful and fit.as_dict()["result"] == "successful"


@pytest.mark.slow
def test_fit_slip_run_with_free_alpha():
    run = short_run(7, alpha=1.2)
    fit = tj.fit_slip_run(run, alpha=None)
    assert fit.converged, fit.message
    assert fit.names == ("F_s", "K_tau", "C_tau", "alpha") and fit.fixed == {}
    truth = np.array([*TRUTH.values(), 1.2])
    z = (fit.values - truth) / fit.std_errors
    assert np.all(np.abs(z) < 2), z
    assert fit.values[3] == pytest.approx(1.2, abs=0.1)


@pytest.mark.slow
def test_slip_fit_coverage_short_form(run):
    """8 seeds: each parameter within 2 se in ≥ 6/8 (binomial, p = 0.95: P(≤ 5 of 8) = 0.6 %).

    One stated C_τ start (within 2x of the truth) instead of the default three: this checks the
    standard errors, not the start heuristic (tested above), at a third of the cost."""
    truth = np.array(list(TRUTH.values()))
    hits = []
    for seed in range(8):
        fit = tj.fit_slip_run(short_run(seed), alpha=1.0, start={"C_tau": 500.0})
        assert fit.converged, (seed, fit.message)
        hits.append(np.abs(fit.values - truth) <= 2 * fit.std_errors)
    cover = np.mean(hits, axis=0)
    assert np.all(cover >= 6 / 8), cover


def test_bad_input_to_the_slip_fit(run):
    few = tj.SlipRun(run.t[:3], run.accel[:3], run.slip[:3], mass=0.321)
    with pytest.raises(ValueError, match=r"3 slip samples are too few to fit 3 parameters"):
        tj.fit_slip_run(few, alpha=1.0)
    with pytest.raises(ValueError, match=r"alpha = -1 is outside the allowed range"):
        tj.fit_slip_run(run, alpha=-1.0)
    with pytest.raises(ValueError, match=r"sigma = 0 m is outside"):
        tj.fit_slip_run(run, alpha=1.0, sigma=0.0)
    with pytest.raises(ValueError, match=r"unknown key\(s\) \['Fs'\]"):
        tj.fit_slip_run(run, alpha=1.0, start={"Fs": 1.0})
    still = tj.SlipRun(run.t, np.zeros_like(run.t), run.slip, mass=0.321)
    with pytest.raises(ValueError, match="acceleration is zero throughout"):
        tj.slip_run_start(still)


@pytest.mark.slow  # a program of its own (the step budget is a shape); the engine's own check of
# the same message is in the fast tier (test_fit.py, test_a_fit_stopped_by_max_steps_says_so)
def test_a_slip_fit_out_of_steps_says_so(run):
    # a start far off with a tiny step budget: not converged, said so (throw=False: no exception)
    fit = tj.fit_slip_run(
        run, alpha=1.0, start={"F_s": 2.0, "K_tau": 3e6, "C_tau": 3e4}, max_steps=2, throw=False
    )
    assert not fit.converged and "max_steps = 2" in fit.message
    assert fit.result == tj.RESULTS.nonlinear_max_steps_reached


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get("TRIBOJAX_FULL") != "1", reason="long form: TRIBOJAX_FULL=1")
def test_slip_fit_coverage_long_form():
    """24 seeds: each parameter within 2 se in ≥ 20/24 (binomial p = 0.95: P(≤ 19) = 0.8 %)."""
    truth = np.array(list(TRUTH.values()))
    hits = []
    for seed in range(100, 124):
        fit = tj.fit_slip_run(short_run(seed), alpha=1.0)
        assert fit.converged, (seed, fit.message)
        hits.append(np.abs(fit.values - truth) <= 2 * fit.std_errors)
    cover = np.mean(hits, axis=0)
    assert np.all(cover >= 20 / 24), cover


def _loop_coverage(cls, seeds, A_bar=2.5):
    el = cls(MU_LOOP, N_LOOP, KD_LOOP)
    A = A_bar * MU_LOOP * N_LOOP / KD_LOOP
    truth = np.array([MU_LOOP * N_LOOP, KD_LOOP])
    sigma = 0.01 * MU_LOOP * N_LOOP
    hits, z = [], []
    for seed in seeds:
        loop = tj.synthetic_loop(
            el, A, 2 * np.pi * 22, cycles=2, samples_per_cycle=200, noise=sigma, seed=seed
        )
        # σ from the record's noise_std
        fit = tj.fit_loop(loop, cls.__name__.lower(), model="steady")
        assert fit.converged
        hits.append(np.abs(fit.values - truth) <= 2 * fit.std_errors)
        z.append((fit.values - truth) / fit.std_errors)
    return np.mean(hits, axis=0), np.asarray(z)


MU_LOOP, N_LOOP, KD_LOOP = 0.3, 2.94, 1.2e6


@pytest.mark.slow
@pytest.mark.parametrize("cls", [tj.Jenkins, tj.Mindlin], ids=["jenkins", "mindlin"])
def test_loop_fit_coverage(cls):
    """Cheap (one compilation per element), so always the long form. 100 seeds: coverage of
    the 2-se interval in [0.89, 0.99] (binomial 99 % band at p = 0.954) and the z-scores'
    standard deviation 1 ± 0.2."""
    cover, z = _loop_coverage(cls, range(1000, 1100))
    assert np.all((cover >= 0.89) & (cover <= 0.99)), cover
    assert np.all(np.abs(np.std(z, axis=0) - 1) < 0.2), np.std(z, axis=0)


SURFACE = (2.8821, 4.3636e-8, 0.1416)  # D, G (m), μ_t of the Table 3 calibration (σ_s 1.893 GPa)


def test_surface_fit_refuses_bad_input(run):
    with pytest.raises(ValueError, match=r"normal_load_N is required"):
        tj.fit_surface_from_runs([run, run])
    loaded = short_run(1, normal_load=3.69)
    with pytest.raises(ValueError, match=r"1 run\(s\) give 3 data for 3 parameters"):
        tj.fit_surface_from_runs([loaded])


@pytest.mark.slow
@pytest.mark.skipif(os.environ.get("TRIBOJAX_FULL") != "1", reason="long form: TRIBOJAX_FULL=1")
def test_surface_fit_recovers_D_G_mu():
    import jax
    import jax.numpy as jnp

    from tribojax._model._surface_runs import surface_contact_model

    loads = (3.6912, 9.5088, 21.3258)
    out = jax.vmap(surface_contact_model(*SURFACE))(jnp.asarray(loads))
    runs = [
        tj.synthetic_slip_run(
            tj.PreSlipLuGre(F, K, C), noise=NOISE, seed=40 + i, normal_load=L, **SHORT
        )
        for i, (L, F, K, C) in enumerate(zip(loads, out.F_s, out.K_tau, out.C_tau))
    ]
    fit = tj.fit_surface_from_runs(runs, start=(2.85, 3e-8, 0.16))
    assert fit.converged and fit.names == ("D", "G_m", "mu_t")
    z = (fit.values - np.array(SURFACE)) / fit.std_errors
    assert np.all(np.abs(z) < 2), z
