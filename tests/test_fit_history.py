"""History (time-domain) fits of friction elements: recovery on data made by independent code,
and a fit of each model to a short excerpt of the measured friction-damper data."""

import dataclasses
import json
import os
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import tribojax as tj

REAL = Path(__file__).resolve().parents[1] / "data" / "real"


def _ramped_sine(n=3000, fs=1024.0, A=0.02, f=1.0):
    t = np.arange(n) / fs
    ramp = np.minimum(1.0, t / 1.0)
    return t, A * ramp * np.sin(2 * np.pi * f * t)


def _numpy_jenkins(F=8.0e3, K=3.0e6, f0=500.0, noise=50.0, seed=15, noise_std=None, frequency=1.0):
    t, u = _ramped_sine()
    z, force = 0.0, np.zeros_like(u)
    for i in range(1, len(u)):  # elastic predictor, return to the slip limit: no tribojax code
        z = min(max(z + u[i] - u[i - 1], -F / K), F / K)
        force[i] = K * z
    rng = np.random.default_rng(seed)
    return tj.HysteresisLoop(
        t,
        u,
        force + f0 + noise * rng.standard_normal(len(u)),
        noise_std=noise_std,
        frequency=frequency,
    )


def test_jenkins_recovered_from_numpy_stepping():
    F, K, f0 = 8.0e3, 3.0e6, 500.0
    loop = _numpy_jenkins(F, K, f0)
    h = tj.fit_history(loop, "jenkins")
    assert h.fit.converged
    for value, se, true in zip(h.fit.values, h.fit.std_errors, (F, K, f0)):
        assert abs(value - true) < 4 * se + 1e-9 * abs(true)
    assert h.nrmse == pytest.approx(50.0 / np.std(loop.f), rel=0.1)


def test_held_parameters_stay_and_the_others_are_fitted():
    # a calibration with most parameters held (`fixed=`): the held value is kept exactly, the
    # free ones recovered, the prediction and the saved model use both; the user's dict untouched
    F, K, f0 = 8.0e3, 3.0e6, 500.0
    loop = _numpy_jenkins(F, K, f0)
    held = {"K_d": K}
    h = tj.fit_history(loop, "jenkins", fixed=held)
    assert held == {"K_d": K} and h.fit.names == ("mu_N", "f0") and h.fit.fixed == held
    assert h.names == ("mu_N", "K_d", "f0") and h.values[1] == K
    for value, se, true in zip(h.fit.values, h.fit.std_errors, (F, f0)):
        assert abs(value - true) < 4 * se
    assert tj.predict_history(h, loop)[1] == pytest.approx(h.nrmse, rel=1e-9)
    assert tj.fitted_model(h).parameters["K_d"] == K
    off = tj.fit_history(loop, "jenkins", fixed={"K_d": 0.5 * K})  # held wrong: a worse fit
    assert off.nrmse > 1.5 * h.nrmse
    with pytest.raises(ValueError, match=r"fixed\['K_d'\] = -1"):
        tj.fit_history(loop, "jenkins", fixed={"K_d": -1.0})
    with pytest.raises(ValueError, match=r"fixed has unknown key\(s\) \['k'\]"):
        tj.fit_history(loop, "jenkins", fixed={"k": 1.0})


@pytest.mark.parametrize(
    "stated, chi2, consistent",
    [
        (50.0, 1.0, True),  # the noise the record states is its noise
        (50.0 / 4.8, 4.8**2, False),  # a residual 4.8x the stated noise: contradicted
        (50.0 * 5, 1 / 25, False),  # 5x below it: an overstated noise (errors 5x too large)
        (None, 1.0, True),  # none stated: the first-difference estimate of the residual
    ],
)
def test_a_history_fit_judges_its_residual_by_the_one_noise_rule(stated, chi2, consistent):
    # issue 72 row 7: the history route reported reduced chi2 = NRMSE² (~4e-4 here) whatever the
    # record stated, and noise_consistent null
    h = tj.fit_history(_numpy_jenkins(noise_std=stated), "jenkins")
    assert h.fit.reduced_chi2 == pytest.approx(chi2, rel=0.1)
    assert h.fit.noise_consistent is consistent
    plain = tj.fit_history(_numpy_jenkins(), "jenkins")  # the same fit, the noise estimated
    np.testing.assert_allclose(h.fit.values, plain.fit.values, rtol=1e-12)
    # standard errors from the stated noise when the residual agrees with it, else from the
    # residual (within the estimate's scatter of each other), but never below the stated
    # noise's: an overstated noise keeps its larger errors (and says so)
    ratio = max(1.0, np.sqrt(1.0 / chi2))
    np.testing.assert_allclose(h.fit.std_errors, ratio * plain.fit.std_errors, rtol=0.1)


def test_the_history_route_of_the_command_uses_the_stated_noise(tmp_path, capsys):
    # row 7 through `tribojax fit --model jenkins`: a sidecar noise 4.8x below the residual is
    # contradicted (was: reduced chi2 ~4e-4, noise_consistent null)
    from tribojax._cli._main import main

    path, out = tmp_path / "loop.csv", tmp_path / "f"
    tj.write_loop(_numpy_jenkins(noise_std=50.0 / 4.8), path)
    assert main(["fit", str(path), "--model", "jenkins", "--out", str(out)]) == 0
    d = json.loads((out / "fit.json").read_text())
    assert d["reduced_chi2"] == pytest.approx(4.8**2, rel=0.1) and d["noise_consistent"] is False
    assert d["sigma_source"] == "sidecar noise_std_N"
    assert "contradict the stated noise" in capsys.readouterr().err


@pytest.mark.slow
def test_bouc_wen_recovered_from_solve_ivp():
    t, u = _ramped_sine(n=2500)
    K, F, n = 2.0e6, 6.0e3, 1.5
    z_y = F / K
    ui = lambda s: np.interp(s, t, u)  # noqa: E731
    v = np.gradient(u, t)

    def rhs(s, z):
        vel = np.interp(s, t, v)
        return [vel * (1 - (0.5 * np.sign(vel * z[0]) + 0.5) * abs(z[0] / z_y) ** n)]

    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0], t_eval=t, rtol=1e-9, atol=1e-14, max_step=1e-3)
    assert ui(0.0) == 0.0
    rng = np.random.default_rng(16)
    loop = tj.HysteresisLoop(t, u, K * sol.y[0] + 30.0 * rng.standard_normal(len(t)))
    h = tj.fit_history(loop, "bouc_wen")
    assert h.fit.converged
    # the data's velocity is a central difference, the model's the chord: a small model error
    np.testing.assert_allclose(h.fit.values[:3], (K, F, n), rtol=0.03)
    assert abs(h.fit.values[3]) < 100.0


FULL = os.environ.get("TRIBOJAX_FULL") == "1"
long_form = [pytest.mark.slow, pytest.mark.skipif(not FULL, reason="long form: TRIBOJAX_FULL=1")]


@pytest.mark.slow
@pytest.mark.parametrize(
    "model",
    ["bouc_wen"] + [pytest.param(m, marks=long_form) for m in ("jenkins", "mindlin", "lugre")],
)
def test_fit_measured_damper_excerpt(model):
    loop = tj.read_record(REAL / "brfd" / "2Hz30lbtension0.5amplitude.csv")
    h = tj.fit_history(loop, model, decimate=2)
    assert h.fit.converged, h.fit.message
    p = dict(zip(h.fit.names, h.fit.values))
    slip = p.get("mu_N", p.get("F_y", p.get("F_c")))
    # the damper slips at 8-13 kN (≈ 2-3 kip each way; Bouc-Wen's F_y is an asymptote) with an
    # offset of ≈ +1.2 kN (the measured force swings from -2.4 to +3.0 kip at reversal)
    assert 7e3 < slip < 15e3 and 0.5e3 < p["f0"] < 2e3
    assert np.all(np.isfinite(h.fit.std_errors))
    assert 0.1 < h.nrmse < 0.5  # backlash and rig oscillation are not in these models
    pred, nrmse = tj.predict_history(h, loop)
    assert nrmse == pytest.approx(h.nrmse, rel=1e-6) and pred.shape == loop.f[::2].shape


def test_a_joint_fit_of_records_far_apart_is_refused_unless_asked(tmp_path, capsys):
    # issue 72 row 8: records whose force scales are 10^4 apart (a unit slip: kN logged as N)
    # were fitted together without a word, the small one worse than a constant
    from tribojax._cli._main import main

    big = _numpy_jenkins()
    small = _numpy_jenkins(F=0.8, K=300.0, f0=0.05, noise=0.005, seed=16)
    with pytest.raises(ValueError, match=r"loops\[0\].*1e\+04 times that of loops\[1\]"):
        tj.fit_history([big, small], "jenkins")
    paths = [tmp_path / "big.csv", tmp_path / "small.csv"]
    for loop, path in zip((big, small), paths):
        tj.write_loop(loop, path)
    cmd = ["fit", *map(str, paths), "--model", "jenkins", "--out", str(tmp_path / "f")]
    assert main(cmd) == 2
    assert "--mixed-scales" in capsys.readouterr().err
    # asked: fitted, and the record the joint model fits worse than a constant is named
    assert main([*cmd, "--mixed-scales"]) in (0, 1)
    d = json.loads((tmp_path / "f" / "fit.json").read_text())
    worse = [r["source"] for r in d["records"] if r["nrmse"] >= 1.0]
    err = capsys.readouterr().err
    assert worse and all(f"{w}: NRMSE" in err and "worse than its mean" in err for w in worse)


@pytest.mark.parametrize("gain, converged", [(0.3, True), (50.0, False)])
def test_a_restart_that_gains_less_than_a_residual_variance_is_a_stationary_stop(
    monkeypatch, gain, converged
):
    # the rule, on the solver's outcomes: every solve stops short of the optimum; a restart
    # that lowers the cost by less than one residual variance is stationary (a play operator's
    # kink: the Gauss–Newton promise is not kept), one that keeps gaining is not converged
    import tribojax._model._history_fit as hf

    real = hf.least_squares_fit
    calls = []

    def short(fn, theta, records, **kw):
        fit = real(fn, theta, records, **kw)
        n, dof = fit.residuals.size, fit.residuals.size - len(fit.names)
        cost = 1000.0 * (1.0 - gain * len(calls) / dof)  # each pass gains `gain` variances
        r = np.sqrt(cost / n) * np.where(np.arange(n) % 2, 1.0, -1.0)  # not a constant
        calls.append(1)
        return dataclasses.replace(
            fit,
            residuals=r,
            result=tj.RESULTS.short_of_optimum,
            converged=False,
            message="short",
        )

    monkeypatch.setattr(hf, "least_squares_fit", short)
    h = tj.fit_history(_numpy_jenkins(), "jenkins", throw=False)
    assert h.fit.converged is converged
    assert len(calls) == (2 if converged else 3)
    if converged:
        assert h.fit.message.startswith("stationary: no descent step (a restart from the stop")
