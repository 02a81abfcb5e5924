"""The band tension of a band-brake friction damper (issue 30): read from both brfd file-name
patterns or given, and the load knob of the history fits — slip forces proportional to it
(capstan law), so a model fitted at 30 lb predicts a record at 36 lb without a refit.

The records come from a stop operator written here in NumPy (an elastic spring k in series with
a Coulomb slider whose slip force is c·T), which shares no code with tribojax's elements."""

import json
from pathlib import Path

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._main import main

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "real" / "brfd"
LBF = 4.4482216152605  # N
C_SLIP, K = 20.0, 4.0e5  # slip force per unit tension (capstan e^{μφ} − 1), stiffness N/m
F_HZ, FS = 1.0, 200.0


def _stop(u, k, f_slip):
    """Force of a spring k in series with a slider of slip force f_slip, from rest at u[0]."""
    out = np.zeros_like(u)
    for i in range(1, u.size):
        out[i] = np.clip(out[i - 1] + k * (u[i] - u[i - 1]), -f_slip, f_slip)
    return out


def _record(tension_lbf, amplitude, seed, tension_known=True, cycles=2.25):
    t = np.arange(int(cycles * FS / F_HZ) + 1) / FS
    u = amplitude * np.sin(2 * np.pi * F_HZ * t)
    noise = np.random.default_rng(seed).normal(0.0, 2.0, t.size)
    f = _stop(u, K, C_SLIP * tension_lbf * LBF) + 5.0 + noise
    return tj.HysteresisLoop(
        t,
        u,
        f,
        frequency=F_HZ,
        source=f"<{tension_lbf} lb, seed {seed}>",
        band_tension=tension_lbf * LBF if tension_known else None,
    )


def test_tension_from_both_file_name_patterns():
    assert tj.brfd_band_tension("0.5Hz30lbtension1amplitude.json") == pytest.approx(30 * LBF)
    assert tj.brfd_band_tension("a/earthquake_KocaeliDBE_36lb.json") == pytest.approx(36 * LBF)
    assert tj.brfd_band_tension("earthquake_Kocaeli.json") is None
    assert tj.brfd_band_tension("run.json") is None


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/real/brfd is absent")
def test_shared_records_carry_their_tension():
    sine = tj.read_record(SHARED / "1Hz30lbtension1amplitude.json")
    quake = tj.read_brfd(SHARED / "earthquake_KocaeliDBE_30lb.json")
    assert sine.band_tension == quake.band_tension == pytest.approx(133.4466, rel=1e-6)
    given = tj.read_brfd(SHARED / "earthquake_KocaeliDBE_30lb.json", band_tension=160.0)
    assert given.band_tension == 160.0


def test_independent_generator_is_a_stop_operator():
    # the generator itself: force bounded by the slip force, slope k while sticking
    u = 1e-3 * np.sin(np.linspace(0, 4 * np.pi, 801))
    f = _stop(u, K, 100.0)
    assert np.max(np.abs(f)) == pytest.approx(100.0) and f[0] == 0.0
    assert (f[1] - f[0]) / (u[1] - u[0]) == pytest.approx(K)


@pytest.fixture(scope="module")
def fit30():
    records = [_record(30, 15e-3, 1), _record(30, 25e-3, 2)]
    return tj.fit_history(records, "jenkins")


@pytest.mark.slow
def test_fit_at_30_lb_predicts_36_lb_by_the_capstan_law(fit30):
    assert fit30.band_tension == pytest.approx(30 * LBF)
    mu_N, K_d, f0 = fit30.fit.values
    assert mu_N == pytest.approx(C_SLIP * 30 * LBF, rel=0.01)  # slip force at the reference
    assert K_d == pytest.approx(K, rel=0.05) and f0 == pytest.approx(5.0, abs=1.0)
    held = _record(36, 20e-3, 3)
    force, nrmse = tj.predict_history(fit30, held)
    assert nrmse < 0.01  # the noise is 2 N of a ±2.9 kN force
    assert np.max(np.abs(force - 5.0)) == pytest.approx(C_SLIP * 36 * LBF, rel=0.01)
    # the same parameters without the knob predict the 30 lb slip force: 6 times the error
    unscaled = tj.HysteresisLoop(held.t, held.u, held.f, frequency=F_HZ)
    _, nrmse_unscaled = tj.predict_history(
        tj.fit_history([_record(30, 15e-3, 1, False), _record(30, 25e-3, 2, False)], "jenkins"),
        unscaled,
    )
    assert nrmse_unscaled > 6 * nrmse


def test_records_at_two_tensions_share_one_parameter_set():
    fit = tj.fit_history([_record(36, 20e-3, 4), _record(30, 20e-3, 5)], "jenkins")
    assert fit.band_tension == pytest.approx(36 * LBF)  # the first record's: the reference
    assert fit.fit.values[0] == pytest.approx(C_SLIP * 36 * LBF, rel=0.01)
    assert fit.nrmse < 0.01


def test_a_missing_tension_is_refused_naming_the_record_and_field(fit30):
    with pytest.raises(ValueError, match=r"<30 lb, seed 7>: field 'band_tension' is missing"):
        tj.fit_history([_record(30, 4e-3, 1), _record(30, 4e-3, 7, False)], "jenkins")
    with pytest.raises(ValueError, match=r"<36 lb, seed 8>: field 'band_tension' is missing"):
        tj.predict_history(fit30, _record(36, 4e-3, 8, False))


def test_saved_model_keeps_the_reference_and_the_cli_takes_a_tension(fit30, tmp_path):
    model = tj.fitted_model(fit30)
    assert model.options["band_tension_N"] == pytest.approx(30 * LBF)
    back = tj.FittedModel.from_dict(json.loads(json.dumps(model.as_dict())))
    held = _record(36, 20e-3, 3)
    pred = tj.predict(back, held)
    assert pred.nrmse == pytest.approx(tj.predict_history(fit30, held)[1], rel=1e-9)
    # the CLI: a loop CSV without a tension is refused until --band-tension gives it
    (tmp_path / "model.json").write_text(json.dumps(model.as_dict()))
    bare = tj.HysteresisLoop(held.t, held.u, held.f, frequency=F_HZ)
    tj.write_loop(bare, tmp_path / "held.csv")
    args = ["predict", str(tmp_path / "model.json"), str(tmp_path / "held.csv")]
    assert main([*args, "--out", str(tmp_path / "a")]) == 2
    assert not (tmp_path / "a" / "prediction.json").exists()
    assert main([*args, "--out", str(tmp_path / "b"), "--band-tension", "36lb"]) == 0
    out = json.loads((tmp_path / "b" / "prediction.json").read_text())
    assert out["nrmse"] == pytest.approx(pred.nrmse, rel=1e-9)
    assert out["band_tension_N"] == pytest.approx(36 * LBF)
    assert out["model_band_tension_N"] == pytest.approx(30 * LBF)


@pytest.mark.slow
def test_cli_fits_several_records_together(tmp_path):
    for name, rec in (
        ("a", _record(30, 15e-3, 1)),
        ("b", _record(30, 25e-3, 2)),
        ("held", _record(36, 20e-3, 3)),
    ):
        tj.write_loop(rec, tmp_path / f"{name}.csv")
    out = tmp_path / "fit"
    files = [str(tmp_path / "a.csv"), str(tmp_path / "b.csv")]
    assert main(["fit", *files, "--model", "jenkins", "--out", str(out)]) == 0
    fit = json.loads((out / "fit.json").read_text())
    assert [r["source"] for r in fit["records"]] == files and fit["n_data"] == 2 * 451
    assert all(r["nrmse"] < 0.01 for r in fit["records"])
    assert fit["band_tension_N"] == pytest.approx(30 * LBF)
    assert fit["parameters"]["mu_N"] == pytest.approx(C_SLIP * 30 * LBF, rel=0.01)
    args = ["predict", str(out / "fit.json"), str(tmp_path / "held.csv"), "--out"]
    assert main([*args, str(tmp_path / "p")]) == 0
    assert json.loads((tmp_path / "p" / "prediction.json").read_text())["nrmse"] < 0.01
    # what cannot be fitted together is refused before any fit, nothing written
    run = tj.synthetic_slip_run(tj.PreSlipLuGre(F_s=1.1, K_tau=2.0e7, C_tau=150.0), n=101)
    tj.write_slip_run(run, tmp_path / "slip.csv")
    bad = tmp_path / "bad"
    assert main(["fit", files[0], str(tmp_path / "slip.csv"), "--out", str(bad)]) == 2
    assert main(["fit", *files, "--model", "steady", "--out", str(bad)]) == 2
    assert not bad.exists() or not (bad / "fit.json").exists()


def _drag_record(seed):
    """A slack band (0 lb): the stop operator with a fixed drag slip force (the backlash drag
    that remains without tension), not c·T."""
    t = np.arange(int(2.25 * FS / F_HZ) + 1) / FS
    u = 15e-3 * np.sin(2 * np.pi * F_HZ * t)
    f = _stop(u, K, 400.0) + np.random.default_rng(seed).normal(0.0, 2.0, t.size)
    return tj.HysteresisLoop(t, u, f, frequency=F_HZ, source="<0 lb>", band_tension=0.0)


def test_a_slack_band_is_a_record_of_its_own(tmp_path):
    # issue 69: a record at 0 lb (a real setting of the device) is read and fitted; the
    # proportional scaling of a one-tension fit cannot carry slip forces to 0 N: refused by name
    slack = _drag_record(7)
    fit0 = tj.fit_history(slack, "jenkins")
    assert fit0.band_tension == 0.0 and fit0.nrmse < 0.02
    assert fit0.fit.values[0] == pytest.approx(400.0, rel=0.01)  # the drag's slip force
    fit30 = tj.fit_history(_record(30, 15e-3, 1), "jenkins")
    with pytest.raises(ValueError, match="band_tension = 0 N with slip forces"):
        tj.predict_history(fit30, slack)
    with pytest.raises(ValueError, match=r"band_tension = -1 N is outside the allowed range \[0"):
        tj.HysteresisLoop(slack.t, slack.u, slack.f, band_tension=-1.0)
    tj.write_loop(slack, tmp_path / "slack.csv")
    assert tj.read_loop(tmp_path / "slack.csv").band_tension == 0.0
    out = tmp_path / "o"
    args = ["fit", str(tmp_path / "slack.csv"), "--model", "jenkins", "--out", str(out)]
    assert main([*args, "--band-tension", "0lb"]) == 0
    assert json.loads((out / "fit.json").read_text())["band_tension_N"] == 0.0


def _law_record(tension_lbf, seed, drag=400.0, growth=0.0):
    """The stop operator whose slip force is a drag plus a capstan part c·T that grows by
    e^{growth·(T − 30 lb)} (growth per lbf): the device's two tension effects, written here."""
    t = np.arange(int(2.25 * FS / F_HZ) + 1) / FS
    u = 15e-3 * np.sin(2 * np.pi * F_HZ * t)
    slip = drag + C_SLIP * tension_lbf * LBF * np.exp(growth * (tension_lbf - 30.0))
    f = _stop(u, K, slip) + 5.0 + np.random.default_rng(seed).normal(0.0, 2.0, t.size)
    src = f"<{tension_lbf} lb>"
    return tj.HysteresisLoop(t, u, f, frequency=F_HZ, source=src, band_tension=tension_lbf * LBF)


def test_the_tension_law_carries_a_drag_and_a_growing_wrap_to_a_tension_not_fitted():
    # two tensions: the law's residual tension T_res takes the drag that remains at 0 lb, so
    # the 0 and 30 lb records fitted together predict 36 lb; the proportional law cannot
    both = tj.fit_history([_law_record(30, 1), _law_record(0, 2)], "jenkins")
    assert both.fit.names == ("mu_N", "K_d", "f0", "T_res")
    assert both.band_tension == pytest.approx(30 * LBF) and both.nrmse < 0.01
    # slip force 400 + c·T: a residual tension of 400/c at 30 lb's slip force, T_res = 400/c
    assert both.fit.values[3] == pytest.approx(400.0 / C_SLIP, rel=0.05)
    held = _law_record(36, 3)
    assert tj.predict_history(both, held)[1] < 0.01
    only30 = tj.fit_history(_law_record(30, 1), "jenkins")
    assert tj.predict_history(only30, held)[1] > 3 * tj.predict_history(both, held)[1]
    # three tensions and a wrap that grows with the tension: γ (1/N) follows, and the law
    # predicts 33 lb, between the fitted ones, where γ = 0 misses
    g = 0.03  # per lbf
    three = [_law_record(T, s, growth=g) for T, s in ((30, 4), (0, 5), (36, 6))]
    fit3 = tj.fit_history(three, "jenkins")
    assert fit3.fit.names[3:] == ("T_res", "gamma") and fit3.nrmse < 0.01
    assert fit3.fit.values[4] == pytest.approx(g / LBF, rel=0.1)
    mid = _law_record(33, 7, growth=g)
    assert tj.predict_history(fit3, mid)[1] < 0.01
    two = tj.fit_history(three[:2], "jenkins")
    assert tj.predict_history(two, mid)[1] > 3 * tj.predict_history(fit3, mid)[1]
    # the law held (one tension cannot fit it): a record at 33 lb refits f0 alone, at the
    # reference tension of the fit it holds
    held = {n: v for n, v in zip(fit3.names, fit3.values) if n != "f0"}
    one = tj.fit_history(mid, "jenkins", fixed=held, band_tension=fit3.band_tension)
    assert one.names == fit3.names and one.fit.names == ("f0",)
    assert one.band_tension == fit3.band_tension and one.nrmse < 0.01
    with pytest.raises(ValueError, match=r"fixed holds the tension law's \['T_res', 'gamma'\]"):
        bare = tj.HysteresisLoop(mid.t, mid.u, mid.f, frequency=F_HZ)
        tj.fit_history(bare, "jenkins", fixed=held)


def test_the_law_is_saved_and_the_cli_fits_a_slack_band_with_a_tension(tmp_path):
    # `tribojax fit` on records at 0 and 30 lb (refused before the law) writes the law's T_res;
    # `predict` of a 36 lb record from that fit.json gives the Python prediction
    for name, rec in (("a", _law_record(30, 1)), ("b", _law_record(0, 2))):
        tj.write_loop(rec, tmp_path / f"{name}.csv")
    out = tmp_path / "fit"
    files = [str(tmp_path / "a.csv"), str(tmp_path / "b.csv")]
    assert main(["fit", *files, "--model", "jenkins", "--out", str(out)]) == 0
    saved = json.loads((out / "fit.json").read_text())
    assert saved["parameters"]["T_res"] == pytest.approx(400.0 / C_SLIP, rel=0.05)
    assert saved["fitted_model"]["units"]["T_res"] == "N"
    held = _law_record(36, 3)
    tj.write_loop(held, tmp_path / "held.csv")
    assert (
        main(
            [
                "predict",
                str(out / "fit.json"),
                str(tmp_path / "held.csv"),
                "--out",
                str(tmp_path / "p"),
            ]
        )
        == 0
    )
    pred = json.loads((tmp_path / "p" / "prediction.json").read_text())
    both = tj.fit_history([_law_record(30, 1), _law_record(0, 2)], "jenkins")
    assert pred["nrmse"] == pytest.approx(tj.predict_history(both, held)[1], rel=1e-6)
    assert pred["nrmse"] < 0.01
    assert saved["tension_law"] == "residual"
    prop = tmp_path / "prop"
    args = ["fit", *files, "--model", "jenkins", "--tension-law", "proportional"]
    assert main([*args, "--out", str(prop)]) == 2  # 0 N in proportion: refused, named
    assert not (prop / "fit.json").exists()
    with pytest.raises(ValueError, match=r"tension_law = 'growing' needs records at 3"):
        tj.fit_history([_law_record(30, 1), _law_record(0, 2)], "jenkins", tension_law="growing")


def _campaign_record(slip, offset, amplitude, seed, tension_lbf=30):
    """The stop operator of a campaign: its own slip force and offset (the band re-seated), the
    same stiffness (the rig)."""
    t = np.arange(int(2.25 * FS / F_HZ) + 1) / FS
    u = amplitude * np.sin(2 * np.pi * F_HZ * t)
    f = _stop(u, K, slip) + offset + np.random.default_rng(seed).normal(0.0, 2.0, t.size)
    src = f"<campaign, {amplitude * 1e3:g} mm, seed {seed}>"
    return tj.HysteresisLoop(t, u, f, frequency=F_HZ, source=src, band_tension=tension_lbf * LBF)


def test_a_new_campaign_is_calibrated_by_one_test_from_the_cli(tmp_path):
    # campaign A fitted on two records; campaign B (slip force −15 %, another offset) calibrated
    # from A's fit.json by one record with only mu_N and f0 refitted (`--from ... --free`): K_d
    # is held at A's, and B's other record is predicted as well as by a fit of that record
    a = [_campaign_record(3000.0, 5.0, amp, s) for amp, s in ((15e-3, 1), (25e-3, 2))]
    b1, b2 = _campaign_record(2550.0, -40.0, 15e-3, 3), _campaign_record(2550.0, -40.0, 25e-3, 4)
    for name, rec in (("a1", a[0]), ("a2", a[1]), ("b1", b1), ("b2", b2)):
        tj.write_loop(rec, tmp_path / f"{name}.csv")
    fa = tmp_path / "A"
    files = [str(tmp_path / "a1.csv"), str(tmp_path / "a2.csv")]
    assert main(["fit", *files, "--model", "jenkins", "--out", str(fa)]) == 0
    ka = json.loads((fa / "fit.json").read_text())["parameters"]["K_d"]
    fb = tmp_path / "B"
    args = ["fit", str(tmp_path / "b1.csv"), "--from", str(fa / "fit.json")]
    assert main([*args, "--free", "mu_N", "f0", "--out", str(fb)]) == 0
    got = json.loads((fb / "fit.json").read_text())
    assert got["fitted"] == ["mu_N", "f0"] and got["fixed"] == {"K_d": ka}
    assert got["free"] == ["mu_N", "f0"] and got["start_model"]["kind"] == "history"
    assert got["parameters"]["mu_N"] == pytest.approx(2550.0, rel=0.01)
    assert got["parameters"]["f0"] == pytest.approx(-40.0, abs=2.0)
    assert (
        main(
            [
                "predict",
                str(fb / "fit.json"),
                str(tmp_path / "b2.csv"),
                "--out",
                str(tmp_path / "p"),
            ]
        )
        == 0
    )
    pred = json.loads((tmp_path / "p" / "prediction.json").read_text())
    assert pred["nrmse"] < 0.01
    # a name the model does not have, or --free without a history model, is refused by name
    bad = tmp_path / "bad"
    assert main([*args, "--free", "mu", "--out", str(bad)]) == 2
    both = tmp_path / "both"  # a law fitted on 0 and 30 lb cannot be refitted on one record
    law_files = []
    for name, rec in (("l30", _law_record(30, 5)), ("l0", _law_record(0, 6))):
        tj.write_loop(rec, tmp_path / f"{name}.csv")
        law_files.append(str(tmp_path / f"{name}.csv"))
    assert main(["fit", *law_files, "--model", "jenkins", "--out", str(both)]) == 0
    one = ["fit", law_files[0], "--from", str(both / "fit.json"), "--out", str(bad)]
    assert main([*one, "--free", "mu_N", "T_res"]) == 2
    assert main(["fit", str(tmp_path / "b1.csv"), "--free", "mu_N", "--out", str(bad)]) == 2
    assert not (bad / "fit.json").exists()


@pytest.mark.slow
def test_tension_discovery_names_the_components_of_the_law_the_records_demand(tmp_path):
    # a drag at 0 lb and a wrap growing with the tension: `tribojax discover` on the records of
    # three tensions names both components, with the generator's T_res and γ, each predicting
    # the last third of every record better than the law before it; predict takes its model
    g = 0.03  # per lbf
    files = []
    for T, seed in ((30, 4), (0, 5), (36, 6)):
        files.append(str(tmp_path / f"{T}lb.csv"))
        tj.write_loop(_law_record(T, seed, growth=g), files[-1])
    out = tmp_path / "disc"
    assert main(["discover", *files, "--model", "jenkins", "--out", str(out), "--quiet"]) == 0
    d = json.loads((out / "discovery.json").read_text())
    assert d["kind"] == "tension" and d["verdict"] == "explained"
    assert d["effects"] == ["residual_tension", "tension_growth"] and d["tension_law"] == "growing"
    for c in d["candidates"]:
        assert c["accepted"] and c["delta_bic"] < -100
        assert c["heldout"]["nrmse_after"] < 0.5 * c["heldout"]["nrmse_before"]
    (t_res, t_err), (gamma, _) = d["candidates"][1]["parameters"].values()
    assert t_res == pytest.approx(400.0 / C_SLIP, rel=0.05) and t_err < 0.05 * t_res
    assert gamma == pytest.approx(g / LBF, rel=0.1)
    assert all(r["nrmse_final"] < 0.01 < r["nrmse_baseline"] for r in d["records"][1:])
    tj.write_loop(_law_record(33, 7, growth=g), tmp_path / "33lb.csv")
    args = ["predict", str(out / "discovery.json"), str(tmp_path / "33lb.csv"), "--out"]
    assert main([*args, str(tmp_path / "p")]) == 0
    assert json.loads((tmp_path / "p" / "prediction.json").read_text())["nrmse"] < 0.01
    # the capstan law alone (no drag, no growth): nothing named, the residual tension refused
    plain = tj.discovery.discover_tension(
        [_law_record(30, 8, drag=0.0), _law_record(36, 9, drag=0.0)], "jenkins"
    )
    assert plain.effects == () and plain.verdict == "none" and plain.law == "proportional"
    assert [c["name"] for c in plain.candidates] == ["residual_tension"]
    assert plain.candidates[0]["delta_bic"] > -10 and not plain.candidates[0]["accepted"]
    # one tension: refused by name
    with pytest.raises(ValueError, match="two or more band tensions"):
        tj.discovery.discover_tension([_law_record(30, 8), _law_record(30, 9)], "jenkins")


def test_tension_discovery_refuses_what_it_cannot_compare_before_any_fit(tmp_path):
    with pytest.raises(ValueError, match="two or more band tensions; these are all at 133"):
        tj.discovery.discover_tension([_law_record(30, 8), _law_record(30, 9)], "jenkins")
    r = _law_record(36, 9)
    bare = tj.HysteresisLoop(r.t, r.u, r.f, frequency=F_HZ, source="<bare>")
    with pytest.raises(ValueError, match="needs each record's band_tension; <bare> has none"):
        tj.discovery.discover_tension([_law_record(30, 8), bare], "jenkins")
    tj.write_loop(_law_record(30, 8), tmp_path / "a.csv")
    run = tj.synthetic_slip_run(tj.PreSlipLuGre(F_s=1.1, K_tau=2.0e7, C_tau=150.0), n=101)
    tj.write_slip_run(run, tmp_path / "slip.csv")
    out = tmp_path / "d"
    files = [str(tmp_path / "a.csv"), str(tmp_path / "slip.csv")]
    assert main(["discover", *files, "--out", str(out)]) == 2
    assert main(["discover", files[0], "--model", "jenkins", "--out", str(out)]) == 2
    assert not (out / "discovery.json").exists()
