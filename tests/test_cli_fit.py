"""`tribojax fit FILE.csv`: slip runs and loops, JSON + plot, exit codes, nothing overwritten."""

import json

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._main import main

TRUTH = {"F_s": 0.4868, "K_tau": 1.4878e7, "C_tau": 771.05}
MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22


@pytest.fixture(scope="module")
def slip_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("slip")
    # the same record shape as tests/test_fit_user.py, so one compiled fit serves both
    run = tj.synthetic_slip_run(
        tj.PreSlipLuGre(*TRUTH.values()), n=10001, t_end=1.0, noise=2e-10, seed=5, normal_load=3.69
    )
    path = folder / "run.csv"
    tj.write_slip_run(run, path, comment="synthetic, Table 3 at 0.6 kPa, seed 5")
    return path


@pytest.fixture
def loop_file(tmp_path):
    loop = tj.synthetic_loop(
        tj.Mindlin(MU, N, KD), 3 * MU * N / KD, OMEGA, noise=0.004, seed=4, normal_load=N
    )
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path)
    return path


def test_fit_a_slip_run(slip_file, capsys):
    out = slip_file.parent / "out"
    before = slip_file.read_bytes()
    # every sample (the default reduces 10,001 to 2,500: `DECIMATION_MAX_SAMPLES`); α = 1 is
    # the default, stated here as a user may
    args = ["--alpha", "1", "--decimate", "off"]
    assert main(["fit", str(slip_file), "--out", str(out), *args]) == 0
    text = capsys.readouterr().out
    assert "K_tau" in text and "wrote" in text
    assert "LM:" not in text + capsys.readouterr().err  # no progress display in a pipe
    res = json.loads((out / "fit.json").read_text())
    assert res["kind"] == "slip_run" and res["fitted"] == ["F_s", "K_tau", "C_tau"]
    assert res["converged"] and res["fixed"] == {"alpha": 1.0} and res["n_data"] == 10001
    assert res["source"] == str(slip_file) and res["sigma_source"] == "sidecar noise_std_m"
    for name, true in TRUTH.items():
        assert abs(res["parameters"][name] - true) < 2 * res["std_errors"][name], name
    # rms residual ≈ the noise (2e-10 m) within 20 %
    assert res["rms_residual"] == pytest.approx(2e-10, rel=0.2) and res["residual_unit"] == "m"
    assert np.allclose(np.diag(res["correlation"]), 1.0)
    assert (out / "fit.png").stat().st_size > 1000
    assert slip_file.read_bytes() == before
    # fit.json is a model file: `tribojax predict` on the same record gives the fit's own numbers
    pred_out = slip_file.parent / "pred"
    assert main(["predict", str(out / "fit.json"), str(slip_file), "--out", str(pred_out)]) == 0
    pred = json.loads((pred_out / "prediction.json").read_text())
    assert pred["model"]["kind"] == "slip" and pred["model"]["options"] == {"alpha": 1.0}
    assert pred["nrmse"] == pytest.approx(res["nrmse"], rel=1e-6)
    assert pred["rms_error"] == pytest.approx(res["rms_residual"], rel=1e-6)
    assert (pred_out / "prediction.csv").read_text().startswith("time_s,measured_m,predicted_m\n")
    # earlier output is not overwritten
    stamp = (out / "fit.json").read_bytes()
    assert main(["fit", str(slip_file), "--out", str(out)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert (out / "fit.json").read_bytes() == stamp


def test_fit_a_loop_and_force(loop_file, capsys):
    out = loop_file.parent / "out"
    assert main(["fit", str(loop_file), "--out", str(out), "--element", "mindlin"]) == 0
    res = json.loads((out / "fit.json").read_text())
    assert res["kind"] == "loop" and res["fitted"] == ["mu_N", "K_d"] and res["converged"]
    assert res["sigma_source"] == "sidecar noise_std_N" and res["frequency_Hz"] == pytest.approx(
        22.0
    )
    for name, true in (("mu_N", MU * N), ("K_d", KD)):
        assert abs(res["parameters"][name] - true) < 2 * res["std_errors"][name], name
    assert res["mu"] == pytest.approx(MU, rel=0.01)
    assert res["rms_residual"] == pytest.approx(0.004, rel=0.15)
    assert main(["fit", str(loop_file), "--out", str(out)]) == 2
    assert main(["fit", str(loop_file), "--out", str(out), "--force", "--element", "mindlin"]) == 0
    # a step budget too small: the fit says so and exits 1, fit.json records converged false
    out2 = loop_file.parent / "out2"
    assert main(["fit", str(loop_file), "--out", str(out2), "--max-steps", "1"]) == 1
    assert "did not converge" in capsys.readouterr().err
    assert json.loads((out2 / "fit.json").read_text())["converged"] is False


def test_fit_refuses_bad_input(tmp_path, loop_file, capsys):
    # outputs that would replace the input's sidecar (stem "fit" in the output folder)
    src = tmp_path / "fit.csv"
    src.write_bytes(loop_file.read_bytes())
    (tmp_path / "fit.json").write_bytes(loop_file.with_suffix(".json").read_bytes())
    before = (tmp_path / "fit.json").read_bytes()
    assert main(["fit", str(src), "--out", str(tmp_path)]) == 2
    assert "is an input file" in capsys.readouterr().err
    assert (tmp_path / "fit.json").read_bytes() == before
    # NaN in the data: file and line named
    bad = tmp_path / "nan.csv"
    bad.write_text("time_s,stage_accel_m_s2,slip_m\n0,0,0\n0.1,nan,1e-9\n0.2,1,2e-9\n")
    (tmp_path / "nan.json").write_text('{"mass_kg": 0.321}')
    assert main(["fit", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert f"{bad}, line 3: column 'stage_accel_m_s2' is nan" in capsys.readouterr().err
    # fewer data than parameters
    few = tmp_path / "few.csv"
    few.write_text("time_s,stage_accel_m_s2,slip_m\n0,0,0\n0.1,1,1e-9\n0.2,1,2e-9\n")
    (tmp_path / "few.json").write_text('{"mass_kg": 0.321}')
    assert main(["fit", str(few), "--out", str(tmp_path / "o")]) == 2
    assert "3 slip samples are too few to fit 3 parameters" in capsys.readouterr().err
    assert main(["fit", str(few), "--out", str(tmp_path / "o"), "--alpha", "x"]) == 2
    assert "--alpha must be 'free' or a number" in capsys.readouterr().err
    # an unknown header and a missing file
    odd = tmp_path / "odd.csv"
    odd.write_text("a,b\n1,2\n")
    assert main(["fit", str(odd), "--out", str(tmp_path / "o")]) == 2
    assert "neither a slip run" in capsys.readouterr().err
    assert main(["fit", str(tmp_path / "missing.csv"), "--out", str(tmp_path / "o")]) == 2
    assert not (tmp_path / "o").exists()
