"""Long records (issue 18, point 4): the block reduction of `decimate_record` and its noise model.

Timing is in benchmarks/long_records.py; here: the reduced values follow the signal within the
stated bias, the stated noise is the noise of the reduced samples, and a fit on the reduced record
agrees with the fit on every sample within the standard errors.
"""

import dataclasses
import json

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._main import main

MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22


def _record(n=200_000, sigma=None, seed=3):
    """A ring-down on a ramp (not a model of the package), white noise of sd `sigma` (or 0)."""
    t = np.linspace(0.0, 2.0, n)
    w = 2 * np.pi * 40.0
    x = 1e-7 * np.exp(-t) * np.sin(w * t) + 3e-8 * t
    noise = 0.0 if sigma is None else sigma * np.random.default_rng(seed).standard_normal(n)
    run = tj.SlipRun(t, np.cos(w * t), x + noise, mass=0.3, noise_std=sigma)
    return run, x, w


def test_reduced_values_follow_the_signal_within_the_stated_bias():
    run, x, w = _record(sigma=1e-12)  # noise only to give a stated sd; values checked noiseless
    clean = dataclasses.replace(run, slip=x, noise_std=1e-12)
    for factor in (10, 100):
        red, info = tj.decimate_record(clean, factor)
        h = run.t[factor - 1] - run.t[0]
        # module docstring: bias ≈ 2.2e-4·h⁴·|x''''|, x'''' ≤ 1e-7·(1 + ω)⁴ here
        bound = 2.2e-4 * h**4 * 1e-7 * (1 + w) ** 4
        centre = 1e-7 * np.exp(-red.t) * np.sin(w * red.t) + 3e-8 * red.t
        err = np.max(np.abs(red.slip - centre))
        assert err <= 1.5 * bound and err < 1e-3 * 1e-7
        # a plain block mean would be off by h²·x''/24, far more
        mean = x[: red.t.size * factor].reshape(-1, factor).mean(axis=1)
        assert np.max(np.abs(mean - centre)) > 20 * err
        assert info.samples == len(run) // factor and info.samples_used == info.samples * factor
    np.testing.assert_array_equal(red.profile().times, clean.t)  # the drive is not reduced


@pytest.mark.parametrize("stated", [True, False])
def test_the_stated_noise_is_the_noise_of_the_reduced_samples(stated):
    sigma = 2e-10
    run, x, w = _record(sigma=sigma)
    if not stated:
        run = dataclasses.replace(run, noise_std=None)
    red, info = tj.decimate_record(run, 50)
    centre = 1e-7 * np.exp(-red.t) * np.sin(w * red.t) + 3e-8 * red.t
    r = red.slip - centre
    # 4000 reduced samples: their sd is known to ±1.1 % (1 sd); g ≈ 9/(4·50)
    assert np.std(r) == pytest.approx(info.noise_std, rel=0.04)
    assert info.noise_std / sigma == pytest.approx(np.sqrt(9 / 200), rel=0.05)
    assert red.noise_std == info.noise_std
    if stated:
        assert info.block_chi2 == pytest.approx(1.0, abs=0.01) and info.blocks_follow_signal
    else:
        assert info.noise_std_original == pytest.approx(sigma, rel=0.01)
        assert info.block_chi2 is None and "scatter" in info.noise_source


def test_blocks_too_long_for_the_signal_are_flagged():
    run, _, _ = _record(sigma=1e-11)
    _, info = tj.decimate_record(run, 2000)  # blocks of 0.02 s against a 25 ms period
    assert info.block_chi2 > 100 and info.blocks_follow_signal is False


def test_bad_factors_name_the_parameter():
    run, _, _ = _record(n=100)
    for bad in (0, 2.5, True, "2"):
        with pytest.raises(ValueError, match="factor"):
            tj.decimate_record(run, bad)
    with pytest.raises(ValueError, match="leaves 3 samples"):
        tj.decimate_record(run, 30)
    assert tj.decimate_record(run)[1].factor == 1  # short: untouched


def _long_loop(noise=0.004):
    el, A = tj.Jenkins(MU, N, KD), 3 * MU * N / KD
    return tj.synthetic_loop(
        el, A, OMEGA, cycles=3, samples_per_cycle=2048, noise=noise, seed=11, normal_load=N
    )


def test_loop_fit_on_the_reduced_record_agrees_with_the_full_fit():
    loop = _long_loop()
    red, info = tj.decimate_record(loop, max_samples=500)
    assert info.factor == 8  # 256 reduced samples per cycle at least (not ceil(6657/500) = 14)
    full, fit = tj.fit_loop(loop, model="steady"), tj.fit_loop(red, model="steady")
    # the reduced estimate = the full one + independent scatter of sd √(σ_red² − σ_full²)
    spread = np.sqrt(fit.std_errors**2 - full.std_errors**2)
    assert np.all(np.abs(fit.values - full.values) < 2.5 * spread)
    # ≈ 1.5 = √(9/4): a block quadratic's centre value keeps 4/9 of the block's information
    assert np.all(fit.std_errors < 1.7 * full.std_errors)
    assert fit.noise_consistent and abs(fit.reduced_chi2 - 1) < 5 * np.sqrt(2 / len(red.t))


@pytest.mark.slow
def test_cli_fit_states_the_reduction(tmp_path, capsys):
    src = tmp_path / "long.csv"
    tj.write_loop(_long_loop(), src)
    out = tmp_path / "o"
    # 1,000: every cycle kept (with 500 the first whole cycles that fit, as discover keeps them,
    # would be less than one)
    assert main(["fit", str(src), "--out", str(out), "--max-samples", "1000"]) == 0
    stdout = capsys.readouterr().out
    assert "samples reduced to" in stdout and "on all" in stdout
    d = json.loads((out / "fit.json").read_text())
    dec, full = d["decimation"], d["full_record"]
    assert dec["factor"] > 1 and dec["method"]
    # the loop model compares the samples from the first reversal after the first upward
    # crossing on (the virgin loading and the lead-in are not fitted): less than two cycles fewer
    per_cycle = 2048 // dec["factor"]  # `_long_loop`: 2,048 samples a cycle
    assert dec["samples"] - 2 * per_cycle < d["n_data"] < dec["samples"]
    assert dec["noise_std"] < dec["noise_std_original"] == 0.004
    assert full["n_data"] > 6000 and full["reduced_chi2"] == pytest.approx(1.0, abs=0.05)
    assert d["noise_consistent"] is True
    assert main(["fit", str(src), "--out", str(tmp_path / "p"), "--decimate", "0"]) == 2
    assert "--decimate = 0" in capsys.readouterr().err
