"""A fitted model as a value (issue 29, the save/load of "baseline + the effects discovery added";
issue 30's `predict`): saved by `fit` and `discover`, loaded, and evaluated on records it did not
fit.

The held-out records come from generators that share nothing with the model code: the clearance
+ Masing generator of tests/test_discovery_backlash.py (SciPy brentq, closed-form branches) and
the NumPy Coulomb/Lorentzian curves of tests/test_discovery_curve.py. Reproducing a fitted model
on its own record is self-consistency only and is labelled so.
"""

import json

import numpy as np
import pytest

import tribojax as tj
from test_discovery_backlash import BACKBONES, F_HZ, F_S, GAPS, NOISE, clearance_masing_force
from test_discovery_backlash import record as backlash_record
from test_discovery_curve import _curve_record
from tribojax._cli._main import main
from tribojax.discovery import curve_baseline, discover, discover_curve, loop_baseline


def _loop(amplitude, seed, gap=GAPS[1], cycles=2.25, noise=NOISE, drive=None):
    """A loop from the independent clearance + Jenkins generator at another amplitude (m)."""
    t = np.arange(int(cycles * 200) + 1) / 200 / F_HZ
    u = amplitude * np.sin(2 * np.pi * F_HZ * t) if drive is None else drive(t)
    f = clearance_masing_force(u, BACKBONES["jenkins"], gap)
    f = f + noise * np.random.default_rng(seed).standard_normal(t.size)
    return tj.HysteresisLoop(t, u, f, frequency=F_HZ, noise_std=noise, source=f"<held out {seed}>")


@pytest.fixture(scope="module")
def backlash_report():
    return discover(loop_baseline(backlash_record("jenkins", GAPS[1], seed=11)), max_effects=2)


@pytest.fixture(scope="module")
def backlash_model():
    """The model the 2 mm discovery finds (`backlash_report`, checked in the second tier: μN
    499.9 N, K_d 2.0e6 N/m, full-depth clearance of 1.13 mm), written as the generator's values:
    the start of the refits below, without the discovery's cost."""
    effect = tj.SavedEffect("backlash", {"depth": 1.0}, {"gap_m": GAPS[1]})
    return tj.FittedModel(
        "loop",
        {"mu_N": F_S, "K_d": 2e6},
        {"mu_N": "N", "K_d": "N/m"},
        {"element": "jenkins"},
        (effect,),
    )


@pytest.mark.slow
def test_discovered_model_predicts_a_loop_at_another_amplitude(backlash_report, tmp_path):
    rep = backlash_report
    assert rep.effects == ("backlash",)
    model = tj.fitted_model(rep)
    saved = model.as_dict()
    assert saved["kind"] == "loop" and saved["effects"][0]["name"] == "backlash"
    assert saved["effects"][0]["nuisance"]["gap_m"] == pytest.approx(GAPS[1], rel=0.05)
    # JSON round trip (the discovery.json entry) gives the same model
    path = tmp_path / "discovery.json"
    path.write_text(json.dumps(rep.as_dict()))
    back = tj.load_model(path)
    assert back == model
    # self-consistency: on its own record the rebuilt model is the discovery's final model
    own = tj.predict(back, backlash_record("jenkins", GAPS[1], seed=11))
    np.testing.assert_allclose(own.predicted, rep.final_y, rtol=0, atol=1e-9 * F_S)
    # held out: 1.5 mm and 3 mm amplitude (fitted at 2 mm), new noise; nothing refitted
    alone = tj.FittedModel("loop", rep.baseline_fit["parameters"], {}, model.options)
    for amplitude, seed in ((1.5e-3, 101), (3.0e-3, 102)):
        held = _loop(amplitude, seed)
        with_effect, without = tj.predict(back, held), tj.predict(alone, held)
        assert with_effect.rms_error < 1.25 * NOISE, amplitude  # the noise alone: 5 N
        assert without.rms_error > 10 * NOISE, amplitude
        assert with_effect.nrmse == pytest.approx(
            with_effect.rms_error / np.std(with_effect.measured), rel=1e-12
        )


def test_history_model_predicts_a_history_it_did_not_fit():
    """Jenkins + offset fitted through one sine (independent generator, no gap) predicts a
    chirp (2 → 5 Hz) of decaying amplitude from rest (every reversal travels more than the
    2F_s/K that the generator's Masing branches need)."""
    fitted = tj.fit_history(_loop(2e-3, 7, gap=0.0), "jenkins")
    model = tj.fitted_model(fitted, "<sine>")
    assert model.kind == "history" and model.options == {"element": "jenkins", "decimate": 1}
    assert model.units["K_d"] == "N/m"

    def chirp(t):
        return 2.5e-3 * np.exp(-0.5 * t) * np.sin(2 * np.pi * (2.0 * t + 0.75 * t**2))

    held = _loop(None, 8, gap=0.0, cycles=4.0, drive=chirp)
    pred = tj.predict(tj.FittedModel.from_dict(model.as_dict()), held)
    assert pred.x_name == "time_s" and pred.unit == "N" and pred.x.size == held.t.size
    assert pred.rms_error < 1.25 * NOISE
    # the same numbers as predict_history (the one history model)
    force, nrmse = tj.predict_history(fitted, held)
    np.testing.assert_allclose(pred.predicted, force, rtol=0, atol=1e-9 * F_S)
    assert pred.nrmse == pytest.approx(nrmse, rel=1e-12)


def test_curve_model_with_two_fitted_nuisances_rebuilds_exactly():
    """Stribeck (v_s and β fitted through their shifts) + asymmetry: the saved model rebuilt on
    its own curve is the discovery's final model (self-consistency), and on a curve with other
    velocities and noise it predicts to the noise."""
    rep = discover_curve(_curve_record("stribeck+asymmetry"))
    assert set(rep.effects) == {"stribeck", "asymmetry"}
    model = tj.FittedModel.from_dict(json.loads(json.dumps(rep.as_dict()["fitted_model"])))
    curve = _curve_record("stribeck+asymmetry")
    w = np.asarray(curve_baseline(curve).weight)
    own = tj.predict(model, curve)
    np.testing.assert_allclose(own.predicted, rep.final_y / w, rtol=0, atol=1e-10)
    held = _curve_record("stribeck+asymmetry", seed=7, n_side=12)
    pred = tj.predict(model, held)
    err = np.asarray(held.friction_error)[np.argsort(held.velocity)]
    z = (pred.predicted - pred.measured) / err
    assert pred.x_name == "velocity_rad/s" and np.sqrt(np.mean(z**2)) < 1.6


def test_saved_model_errors_name_the_field(tmp_path):
    good = tj.FittedModel(
        "loop", {"mu_N": 500.0, "K_d": 2e6}, {"mu_N": "N", "K_d": "N/m"}, {"element": "jenkins"}
    )
    d = good.as_dict()
    for change, field in (
        ({"format": "tribojax.fitted_model/0"}, "'format'"),
        ({"kind": "table"}, "'kind'"),
        ({"parameters": {"mu_N": float("nan")}}, "'parameters'"),
        ({"effects": [{"strengths": {}}]}, r"'effects\[0\]'"),
    ):
        with pytest.raises(ValueError, match=field):
            tj.FittedModel.from_dict({**d, **change})
    history = {
        **d,
        "kind": "history",
        "options": {"element": "jenkins"},
        "parameters": {"mu_N": 500.0, "f0": 0.0},
    }
    (tmp_path / "h.json").write_text(json.dumps({"fitted_model": history}))
    with pytest.raises(ValueError, match=r"h.json: fitted_model: field 'parameters' lacks \['K_d'"):
        tj.load_model(tmp_path / "h.json")
    bare = tmp_path / "fit.json"
    bare.write_text(json.dumps({"parameters": {"mu_N": 1.0}}))
    with pytest.raises(ValueError, match="fit.json: no field 'fitted_model'"):
        tj.load_model(bare)
    with pytest.raises(ValueError, match="predicts loop records"):
        tj.predict(good, _curve_record("clean"))
    with pytest.raises(ValueError, match=r"lacks \['K_d'\]"):
        tj.predict(tj.FittedModel("loop", {"mu_N": 1.0}, {}), _loop(2e-3, 1))
    unknown = tj.FittedModel("loop", good.parameters, {}, {}, (tj.SavedEffect("wobble", {}),))
    with pytest.raises(ValueError, match="'wobble' is not a loop effect"):
        tj.predict(unknown, _loop(2e-3, 1))


def test_cli_fit_then_predict(tmp_path, capsys):
    """`tribojax fit loop.csv` then `tribojax predict DIR/fit.json other.csv`: prediction.json
    ("nrmse", "model", "record"), prediction.csv (time_s,measured_N,predicted_N), exit codes."""
    fitted, held = tmp_path / "fitted.csv", tmp_path / "held.csv"
    tj.write_loop(_loop(2e-3, 3, gap=0.0), fitted)
    tj.write_loop(_loop(1.2e-3, 4, gap=0.0), held)
    assert main(["fit", str(fitted), "--out", str(tmp_path / "fit")]) == 0
    model_file = tmp_path / "fit" / "fit.json"
    assert json.loads(model_file.read_text())["fitted_model"]["kind"] == "loop"
    out = tmp_path / "pred"
    assert main(["predict", str(model_file), str(held), "--out", str(out)]) == 0
    res = json.loads((out / "prediction.json").read_text())
    assert {"nrmse", "model", "record"} <= set(res) and res["record"] == str(held)
    header, *rows = (out / "prediction.csv").read_text().splitlines()
    assert header == "time_s,measured_N,predicted_N" and len(rows) == res["n_data"]
    table = np.loadtxt(out / "prediction.csv", delimiter=",", skiprows=1)
    err = table[:, 2] - table[:, 1]
    assert res["nrmse"] == pytest.approx(np.sqrt(np.mean(err**2)) / np.std(table[:, 1]))
    assert np.sqrt(np.mean(err**2)) < 1.25 * NOISE  # Jenkins, no gap: the noise at 1.2 mm
    capsys.readouterr()
    stamp = (out / "prediction.json").read_bytes()
    assert main(["predict", str(model_file), str(held), "--out", str(out)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert (out / "prediction.json").read_bytes() == stamp
    old = tmp_path / "old.json"
    saved = json.loads(model_file.read_text())
    saved["fitted_model"]["format"] = "tribojax.fitted_model/0"
    old.write_text(json.dumps(saved))
    assert main(["predict", str(old), str(held), "--out", str(tmp_path / "p2")]) == 2
    err = capsys.readouterr().err
    assert "old.json: fitted_model: field 'format'" in err
    assert not (tmp_path / "p2").exists()


@pytest.mark.slow
@pytest.mark.parametrize(("gap", "amplitude"), [(0.9e-3, 2.5e-3), (0.37e-3, 1.5e-3)])
def test_refit_of_a_discovered_model_finds_another_gap(backlash_report, gap, amplitude):
    """The discovered model (clearance 1.13 mm at 2 mm) refitted, effects included, on loops of
    another clearance and amplitude from the independent generator finds their gap."""
    fit = tj.refit(tj.fitted_model(backlash_report), _loop(amplitude, 21, gap=gap))
    assert fit.converged, fit.message
    saved = tj.fitted_model(fit)
    assert saved.effects[0].name == "backlash"
    assert saved.effects[0].nuisance["gap_m"] == pytest.approx(gap, rel=0.02)
    assert saved.parameters["mu_N"] == pytest.approx(F_S, rel=0.01)
    assert np.sqrt(np.mean((fit.residuals * fit.scale) ** 2)) < 1.1 * NOISE


def test_cli_fit_from_a_discovery_json(backlash_model, tmp_path, capsys):
    disc = tmp_path / "discovery.json"
    disc.write_text(json.dumps({"fitted_model": backlash_model.as_dict()}))
    held = tmp_path / "held.csv"
    tj.write_loop(_loop(2.5e-3, 22, gap=0.9e-3), held)
    out = tmp_path / "fit"
    assert main(["fit", str(held), "--from", str(disc), "--out", str(out)]) == 0
    res = json.loads((out / "fit.json").read_text())
    assert res["fitted_model"]["effects"][0]["nuisance"]["gap_m"] == pytest.approx(0.9e-3, rel=0.02)
    assert res["start_model"]["effects"][0]["nuisance"]["gap_m"] == pytest.approx(GAPS[1], rel=0.05)
    assert res["rms_residual"] < 1.1 * NOISE and "backlash" in res["model"]
    # the refitted model predicts: its fit.json is a model file
    assert main(["predict", str(out / "fit.json"), str(held), "--out", str(tmp_path / "p")]) == 0
    pred = json.loads((tmp_path / "p" / "prediction.json").read_text())
    assert pred["rms_error"] == pytest.approx(res["rms_residual"], rel=1e-6)
    capsys.readouterr()
    assert (
        main(
            [
                "fit",
                str(held),
                "--from",
                str(disc),
                "--start",
                "mu_N=400",
                "--out",
                str(tmp_path / "f2"),
            ]
        )
        == 2
    )
    assert "--start and --alpha do not apply with --from" in capsys.readouterr().err


def test_steady_law_fit_is_the_curve_model_with_two_effects(tmp_path):
    """`fit_steady_curve` (both directions) saved as the curve model + `stribeck` + `asymmetry`:
    the same law term by term, so the saved model reproduces the fitted curve (to round-off)."""
    curve = _curve_record("stribeck+asymmetry")
    fit = tj.fit_steady_curve(curve)
    model = tj.fitted_model(fit, "<curve>")
    assert [e.name for e in model.effects] == ["stribeck", "asymmetry"]
    law = np.asarray(curve.friction) + np.asarray(fit.residuals) * np.asarray(curve.friction_error)
    order = np.argsort(curve.velocity)
    pred = tj.predict(tj.FittedModel.from_dict(model.as_dict()), curve)
    np.testing.assert_allclose(pred.predicted, law[order], rtol=1e-12, atol=1e-12)
    # and the CLI saves it: fit.json of a curve is a model file
    path = tmp_path / "curve.csv"
    tj.write_friction_curve(curve, path)
    assert main(["fit", str(path), "--out", str(tmp_path / "f"), "--model", "lugre"]) == 0
    saved = tj.load_model(tmp_path / "f" / "fit.json")
    assert saved.kind == "curve" and saved.parameters["F_c"] == pytest.approx(
        model.parameters["F_c"], rel=1e-9
    )


def test_discovery_continues_from_a_saved_model(backlash_model, tmp_path):
    """`discover(..., start=model)`: the clearance found on one loop is refitted on another
    (another gap and amplitude) and the search goes on from there; "before" stays the
    baseline alone."""
    held = _loop(2.5e-3, 23, gap=0.9e-3)
    rep = discover(loop_baseline(held), start=backlash_model)
    assert rep.effects[0] == "backlash" and rep.verdict == "explained"
    assert rep.strengths["backlash"]["nuisance"]["gap_m"] == pytest.approx(0.9e-3, rel=0.02)
    assert rep.settings["start_model"]["effects"] == ["backlash"]
    assert rep.baseline_fit["effects"] == [] and rep.excess_rmse_after < 0.5 * NOISE
    assert rep.excess_rmse_before > 10 * NOISE
    # the CLI: --from a discovery.json; a model of another kind is refused by name
    disc, path = tmp_path / "discovery.json", tmp_path / "held.csv"
    disc.write_text(json.dumps({"fitted_model": backlash_model.as_dict()}))
    tj.write_loop(held, path)
    assert main(["discover", str(path), "--from", str(disc), "--out", str(tmp_path / "d")]) == 0
    out = json.loads((tmp_path / "d" / "discovery.json").read_text())
    assert out["effects"][0] == "backlash"
    assert out["settings"]["start_model"]["refit"] == "converged"
    curve = tmp_path / "curve.csv"
    tj.write_friction_curve(_curve_record("clean"), curve)
    assert main(["discover", str(curve), "--from", str(disc), "--out", str(tmp_path / "d2")]) == 2
