"""One model per record kind (issue 67): with no options, `tribojax fit` and `discover`'s baseline
are the same fit — same parameters, same noise verdict — and the Python defaults give the
command's parameters. Records from the discovery study's generators (SciPy LSODA on the slip ODE,
NumPy stop operator for loops: code that shares nothing with tribojax's models) and the measured
screw-drive curve (skipped when ../shared is absent)."""

import json
from pathlib import Path

import pytest
from benchmarks import discovery_loop_records as dlr
from benchmarks import discovery_records as dr

import tribojax as tj
from tribojax._cli._main import main

CURVE = Path(__file__).parents[2] / "shared/data/real/screwdrive/driveNo1/steady_state/0.096kg"


def _both(path, tmp_path):
    """fit.json and discovery.json of the two commands with no options."""
    assert main(["fit", str(path), "--out", str(tmp_path / "f")]) == 0
    assert main(["discover", str(path), "--out", str(tmp_path / "d"), "--max-effects", "1"]) == 0
    fit = json.loads((tmp_path / "f" / "fit.json").read_text())
    disc = json.loads((tmp_path / "d" / "discovery.json").read_text())
    return fit, disc


def _same_fit(fit, disc):
    base = disc["baseline_fit"]
    assert sorted(fit["parameters"]) == sorted(base["parameters"])  # the same parameter set
    for name, value in fit["parameters"].items():
        se = max(fit["std_errors"][name], base["std_errors"][name])
        assert abs(value - base["parameters"][name]) < 0.05 * se, name
    assert fit["noise_consistent"] == disc["misfit"]["baseline_consistent"]
    assert fit["sigma"] == pytest.approx(disc["noise_std"], rel=0.05)  # one meaning of sigma


@pytest.mark.slow  # ~20 s: a discovery's ranking of the slip effects
def test_a_slip_run_is_one_fit(tmp_path):
    # 2 kPa, high noise and no stated noise: α held at 1 by both, the noise estimated alike
    spec = dr.RecordSpec("clean", "-", 2.0, "paper", "high", False, 1069)
    path = tmp_path / "run.csv"
    tj.write_slip_run(dr.make_record(spec), path)
    fit, disc = _both(path, tmp_path)
    assert fit["fixed"] == {"alpha": 1.0} and fit["fitted"] == ["F_s", "K_tau", "C_tau"]
    _same_fit(fit, disc)


def test_a_loop_is_one_fit_and_python_fits_it_alike(tmp_path):
    spec = dlr.LoopRecordSpec("clean", "-", "high", False, 2032)
    path = tmp_path / "loop.csv"
    tj.write_loop(dlr.make_loop_record(spec), path)
    fit, disc = _both(path, tmp_path)
    _same_fit(fit, disc)
    py = tj.fit_loop(tj.read_loop(path))  # Python's defaults: the command's parameters
    for name, value in zip(py.names, py.values):
        assert float(value) == pytest.approx(fit["parameters"][name], rel=1e-9), name


@pytest.mark.slow
@pytest.mark.skipif(not CURVE.exists(), reason="../shared/data (measured screw-drive curve) absent")
def test_a_measured_friction_curve_is_one_fit(tmp_path):
    fit, disc = _both(CURVE, tmp_path)
    assert fit["fitted"] == ["F_c", "sigma2"]  # the curve's record model: Coulomb + viscous
    _same_fit(fit, disc)
