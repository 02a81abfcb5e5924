"""Measured loops: validated loading, wu2015 Eq 6 K_d, first-harmonic K_eq/C_eq, fit recovery."""

import json
import re

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._main import main

MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22
MUN, A0 = MU * N, MU * N / KD


@pytest.mark.parametrize("cls", [tj.Jenkins, tj.Mindlin], ids=["jenkins", "mindlin"])
@pytest.mark.parametrize("Ab", [0.6, 3.0])
def test_analysis_of_an_exact_loop(cls, Ab):
    el = cls(MU, N, KD)
    A = Ab * A0
    loop = tj.synthetic_loop(el, A, OMEGA, cycles=3, samples_per_cycle=800)
    a = tj.analyse_loop(loop)
    hb = tj.harmonic_balance(el, A, OMEGA)
    assert a.cycles == 3 and a.omega == pytest.approx(OMEGA, rel=1e-12)
    assert a.A == pytest.approx(A, rel=1e-12)
    # Eq 6 is exact on a Jenkins stick branch; on a Mindlin branch the quadratic over 5 % of
    # the stroke leaves a cubic-term bias ~ (window/A0)² ≲ 1e-3
    assert a.K_d == pytest.approx(KD, rel=1e-12 if cls is tj.Jenkins else 1e-3)
    # first harmonic from samples vs the quadrature: the slope jumps at the reversals and θ*
    # limit sampled sums to O((2π/n)²) = 6e-5 times the jump's weight (C̄ is small at Ā = 0.6)
    assert a.K_eq == pytest.approx(float(hb.K_eq), rel=1e-5)
    assert a.C_eq == pytest.approx(float(hb.C_eq), rel=5e-4, abs=1e-6 * KD / OMEGA)
    assert a.W == pytest.approx(float(hb.W), rel=5e-4, abs=1e-8 * MUN * A)
    fmax = MUN if (Ab >= 1.5 or (cls is tj.Jenkins and Ab >= 1)) else float(el.steady_loop(0, A))
    assert a.mu_N == pytest.approx(fmax, rel=1e-9)


@pytest.mark.parametrize("cls", [tj.Jenkins, tj.Mindlin], ids=["jenkins", "mindlin"])
def test_fit_recovers_parameters_from_noisy_loops(cls):
    el = cls(MU, N, KD)
    sigma = 0.01 * MUN  # 1 % force noise
    loop = tj.synthetic_loop(el, 2.5 * A0, OMEGA, cycles=3, noise=sigma, seed=2024)
    fit = tj.fit_loop(loop, cls.__name__.lower(), sigma=sigma, model="steady")
    assert fit.converged and fit.names == ("mu_N", "K_d")
    truth = np.array([MUN, KD])
    z = (fit.values - truth) / fit.std_errors
    assert np.all(np.abs(z) < 4), z  # within 4 standard errors (seeded: deterministic)
    assert np.all(np.abs(fit.values / truth - 1) < 0.01)
    # residuals scaled by sigma: chi² per point ≈ 1
    assert np.mean(fit.residuals**2) == pytest.approx(1.0, abs=0.15)


def test_read_loop_round_trip_and_cli(tmp_path):
    el = tj.Mindlin(MU, N, KD)
    loop = tj.synthetic_loop(el, 3 * A0, OMEGA, noise=0.005 * MUN, seed=7)
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path, comment="synthetic Mindlin loop\nseed 7")
    back = tj.read_loop(path)
    np.testing.assert_array_equal(back.f, loop.f)
    drive = back.profile()  # the measured displacement history drives the element
    np.testing.assert_array_equal(np.asarray(drive.displacements), loop.u)
    np.testing.assert_array_equal(np.asarray(drive.times), loop.t)
    out = tmp_path / "out"
    rc = main(
        [
            "hysteresis",
            "--element",
            "mindlin",
            "--K-d",
            str(KD),
            "--loop",
            str(path),
            "--n",
            "20",
            "--out",
            str(out),
        ]
    )
    assert rc == 0
    table = tj.read_table(out / "hysteresis.csv", columns=("A_m", "K_bar", "C_bar"))
    assert len(table["A_m"]) == 20 and np.all(np.diff(table["K_bar"]) < 0)  # K̄ falls
    res = json.loads((out / "loop_fit.json").read_text())
    assert res["fit"]["converged"] and res["fit"]["parameters"]["K_d"] == pytest.approx(KD, 0.01)
    assert main(["hysteresis", "--loop", str(path), "--out", str(tmp_path)]) == 2  # over input


def _write(tmp_path, rows, name="bad.csv"):
    path = tmp_path / name
    path.write_text("# a loop\nt_s,u_m,f_N\n" + "\n".join(rows) + "\n")
    return path


def test_bad_loop_files_are_refused(tmp_path):
    t = np.linspace(0, 2.5, 251)
    good = [f"{a},{np.sin(2 * np.pi * a)},{np.cos(2 * np.pi * a)}" for a in t]
    rows = list(good)
    rows[5] = "0.05,nan,1"
    path = _write(tmp_path, rows)
    with pytest.raises(tj.DataFileError, match=re.escape(str(path)) + ", line 8: column 'u_m'"):
        tj.read_loop(path)
    rows = list(good)
    rows[10] = rows[9]
    path = _write(tmp_path, rows)
    with pytest.raises(tj.DataFileError, match=re.escape(str(path)) + ", line 13: time t_s"):
        tj.read_loop(path)
    path = _write(tmp_path, good[10:110])  # t = 0.1 .. 1.09: one upward crossing only
    with pytest.raises(tj.DataFileError, match=re.escape(str(path)) + ": fewer than one whole"):
        tj.read_loop(path)
    with pytest.raises(ValueError, match="same length"):
        tj.HysteresisLoop(t, np.sin(2 * np.pi * t), np.zeros(3))
    with pytest.raises(ValueError, match="element must be one of"):
        tj.fit_loop(tj.HysteresisLoop(t, np.sin(2 * np.pi * t), np.zeros_like(t)), "lugre")


@pytest.mark.slow
def test_history_fit_handles_a_drifting_amplitude():
    """Driven through the measured history, the element fits a non-periodic record."""
    el = tj.Jenkins(MU, N, KD)
    t = np.linspace(0, 3.25, 1301) * 2 * np.pi / OMEGA
    u = 2.5 * A0 * (1 + 0.3 * t / t[-1]) * np.sin(OMEGA * t)  # amplitude grows by 30 %
    sigma = 0.01 * MUN
    rng = np.random.default_rng(11)
    f = np.asarray(tj.drive(el, u)) + sigma * rng.standard_normal(len(t))
    loop = tj.HysteresisLoop(t, u, f)
    fit = tj.fit_loop(loop, "jenkins", sigma=sigma, model="history")
    assert fit.converged
    z = (fit.values - np.array([MUN, KD])) / fit.std_errors
    assert np.all(np.abs(z) < 4), z
    with pytest.raises(ValueError, match="model must be"):
        tj.fit_loop(loop, "jenkins", model="transient")


@pytest.mark.parametrize("eps", [1e-12, -1e-12, 3e-9])
def test_whole_cycles_do_not_hang_on_the_last_bits_of_a_sample_at_the_mean(eps):
    # a record that starts on its mean (a sine from u = 0): whether the first sample is a
    # crossing must not turn on its last bits (issue 68: the study's loop s2003, moved by 1e-3 of
    # its noise, lost a whole cycle, 601 -> 401 samples fitted, and its verdict)
    from tribojax._io._hysteresis_loop import cycle_starts

    w, n = 2 * np.pi * 5.0, 3 * 200 + 50 + 1
    t = np.arange(n) / 200 / 5.0
    u = 1e-6 * np.sin(w * t)
    f = 2.0 * np.tanh(u / 2e-7)
    moved = u.copy()
    moved[0] += eps * 1e-6
    a, b = cycle_starts(t, u), cycle_starts(t, moved)
    assert len(a) == len(b) == 4 and np.allclose(a, b, atol=1e-9)
    la = tj.analyse_loop(tj.HysteresisLoop(t, u, f))
    lb = tj.analyse_loop(tj.HysteresisLoop(t, moved, f))
    assert la.omega == pytest.approx(w, rel=1e-6) and lb.omega == pytest.approx(la.omega, rel=1e-9)
