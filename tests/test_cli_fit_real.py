"""`tribojax fit` on measured records (issue 15): format detection, --model, --format, fit.json."""

import contextlib
import json
from pathlib import Path

import pytest

from tribojax._cli import main

REAL = Path(__file__).resolve().parents[1] / "data" / "real"


def test_fit_brfd_history_with_model(tmp_path, capsys):
    out = tmp_path / "o"
    src = REAL / "brfd" / "2Hz30lbtension0.5amplitude.csv"
    assert main(["fit", str(src), "--out", str(out), "--model", "jenkins"]) == 0
    res = json.loads((out / "fit.json").read_text())
    assert res["model"] == "jenkins" and res["route"] == "history"
    assert res["fitted"] == ["mu_N", "K_d", "f0"] and 0.1 < res["nrmse"] < 0.6
    assert res["n_data"] == 3585 and res["converged"]


@pytest.mark.slow
def test_fit_epos_folder_as_one_curve(tmp_path, capsys):
    folder = tmp_path / "0.1kg"
    folder.mkdir()
    head = "Date:;x\n;Velocity actual value averaged;Torque actual value averaged\nms;rpm;%\n"
    for rpm in (2, 5, 10, 20, 40, 80, 120, 160):
        for sign in (1, -1):
            mag = 25 + 8 * 2.718 ** (-((rpm / 10) ** 2)) + 0.05 * rpm + 3 * sign
            rows = [
                f"{i * 51.2:.1f};{sign * rpm};{sign * mag + 0.5 * (-1) ** i:.2f}" for i in range(40)
            ]
            name = f"{'n' if sign < 0 else ''}{rpm}.csv"
            (folder / name).write_text(head + "\n".join(rows) + "\n")
    out = tmp_path / "o"
    # no options: the curve's record model (Coulomb + viscous), as discover's baseline
    assert main(["fit", str(folder), "--out", str(tmp_path / "r")]) == 0
    rec = json.loads((tmp_path / "r" / "fit.json").read_text())
    assert rec["fitted"] == ["F_c", "sigma2"] and rec["fitted_model"]["kind"] == "curve"
    assert main(["fit", str(folder), "--out", str(out), "--model", "lugre"]) == 0
    res = json.loads((out / "fit.json").read_text())
    assert res["kind"] == "friction_curve" and res["model"] == "lugre"
    assert res["units"] == {"velocity_unit": "rad/s", "friction_unit": "N m"}
    # the asymmetry: +3 % of 9.84 mN m in both directions
    assert res["parameters"]["T0"] == pytest.approx(0.03 * 9.84e-3, rel=0.02)
    assert set(res["per_direction"]) == {"positive", "negative"} and "nrmse" in res
    # an explicit --max-steps is the budget (no floor overrides it): 2 LM steps do not converge
    assert (
        main(
            [
                "fit",
                str(folder),
                "--out",
                str(tmp_path / "s"),
                "--max-steps",
                "2",
                "--model",
                "lugre",
            ]
        )
        == 1
    )
    assert json.loads((tmp_path / "s" / "fit.json").read_text())["converged"] is False
    # a model that does not apply to a curve, and a wrong --format, are bad input (2)
    assert main(["fit", str(folder), "--out", str(tmp_path / "p"), "--model", "jenkins"]) == 2
    assert "does not apply to a friction curve" in capsys.readouterr().err
    assert (
        main(["fit", str(folder / "n2.csv"), "--out", str(tmp_path / "q"), "--format", "brfd"]) == 2
    )
    assert "n2.csv, line 1: not valid JSON" in capsys.readouterr().err


def test_discover_refuses_a_friction_transient_cleanly(tmp_path, capsys):
    src = REAL / "screwdrive" / "driveNo1_start_stop_50.csv"
    assert main(["discover", str(src), "--out", str(tmp_path / "d")]) == 2
    assert "no baseline for a FrictionTransient" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()


def test_fit_json_is_the_library_report(tmp_path):
    """fit.json is `FitReport.as_dict()` (issue 67): the same fit in Python gives the command's
    dictionary, numbers and keys."""
    import tribojax as tj

    src = REAL / "screwdrive" / "driveNo2_steady_0.096kg.csv"  # a measured curve (bundled)
    assert main(["fit", str(src), "--out", str(tmp_path / "o")]) == 0
    cli = json.loads((tmp_path / "o" / "fit.json").read_text())
    curve = tj.read_record(src)
    fit = tj.fit_record(tj.discovery.curve_baseline(curve))
    label = "Coulomb + viscous friction (the curve's record model)"
    lib = tj.FitReport.of_record_model(fit, curve, label, units=curve.units).as_dict()
    assert set(lib) <= set(cli) and set(cli) - set(lib) == {"wall_time_s"}
    for key in ("parameters", "std_errors", "sigma", "rms_residual", "nrmse", "n_data"):
        assert lib[key] == pytest.approx(cli[key], rel=1e-12), key
    assert lib["fitted_model"] == cli["fitted_model"] and lib["sigma_source"] == cli["sigma_source"]


def test_best_considers_the_band_brake_on_a_band_brakes_records():
    # issue 69: `--model best` compares every model that applies to the record
    import dataclasses

    import tribojax as tj
    from tribojax._cli._fit_real import best_candidates

    plain = tj.read_record(REAL / "brfd" / "2Hz30lbtension0.5amplitude.csv")  # no tension
    loop = dataclasses.replace(plain, band_tension=133.4)
    assert best_candidates([loop]) == ("jenkins", "mindlin", "lugre", "bouc_wen", "band_brake")
    assert best_candidates([plain]) == ("jenkins", "mindlin", "lugre", "bouc_wen")
    assert best_candidates([loop, plain]) == ("jenkins", "mindlin", "lugre", "bouc_wen")


@pytest.mark.slow
def test_best_on_the_damper_chooses_by_bic_and_prints_the_candidates(tmp_path, capsys):
    out = tmp_path / "o"
    src = REAL / "brfd" / "2Hz30lbtension0.5amplitude.csv"
    args = ["--model", "best", "--decimate", "2", "--band-tension", "30lb"]
    assert main(["fit", str(src), "--out", str(out), *args]) == 0
    res = json.loads((out / "fit.json").read_text())
    cands = res["candidates"]
    assert set(cands) == {"jenkins", "mindlin", "lugre", "bouc_wen", "band_brake"}
    assert res["model"] == min(cands, key=lambda k: cands[k]["bic"])
    said = capsys.readouterr().out
    table = [line.split() for line in said.splitlines() if line.startswith("    ")]
    assert sorted(row[-5] for row in table) == sorted(cands)  # model NRMSE x BIC y
    assert [row[1] for row in table if row[0] == "*"] == [res["model"]]


@pytest.mark.slow
def test_n_starts_fits_bouc_wen_from_each_start_as_the_library(tmp_path):
    # issue 70: the study's thorough Bouc–Wen fit (three starts of n) through the command
    import numpy as np

    import tribojax as tj
    from tribojax._limits import MAX_STEPS

    src = REAL / "brfd" / "2Hz30lbtension0.5amplitude.csv"
    starts = [str(v) for v in tj.BOUC_WEN_STARTS]
    args = ["--model", "bouc_wen", "--decimate", "4", "--n-starts", *starts]
    main(["fit", str(src), "--out", str(tmp_path / "o"), *args])
    cli = json.loads((tmp_path / "o" / "fit.json").read_text())
    assert cli["n_starts"] == list(tj.BOUC_WEN_STARTS)
    loop = tj.read_record(src)
    kw = dict(decimate=4, max_steps=MAX_STEPS, throw=False)
    lib = tj.fit_history(loop, "bouc_wen", n_starts=tj.BOUC_WEN_STARTS, **kw)
    for name, value in zip(lib.fit.names, lib.fit.values):
        assert cli["parameters"][name] == pytest.approx(float(value), rel=1e-8), name
    one = tj.fit_history(loop, "bouc_wen", **kw)  # the default: one start, n = 2
    rss = [float(np.sum(np.square(h.fit.residuals))) for h in (lib, one)]
    assert rss[0] <= rss[1] * (1 + 1e-12)  # the best of three starts is never worse


@pytest.mark.parametrize(
    "args, said",
    [
        (["--model", "jenkins", "--n-starts", "2"], "--n-starts applies to a history fit"),
        (["--model", "bouc_wen", "--n-starts", "0"], "--n-starts = '0' is outside"),
        (["--model", "bouc_wen", "--n-starts", "nan"], "--n-starts = 'nan' is outside"),
    ],
)
def test_n_starts_refused_where_it_does_not_apply(tmp_path, capsys, args, said):
    src = REAL / "brfd" / "2Hz30lbtension0.5amplitude.csv"
    with pytest.raises(SystemExit) if "outside" in said else contextlib.nullcontext():
        status = main(["fit", str(src), "--out", str(tmp_path / "o"), *args])
        assert status == 2
    assert said in capsys.readouterr().err
    assert not (tmp_path / "o" / "fit.json").exists()
