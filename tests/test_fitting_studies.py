"""The fitting/ studies run (short form) and show what they claim."""

import json

import pytest
from fitting import wang2022_table3


def test_table3_study_degeneracy(tmp_path):
    assert wang2022_table3.main(["--short", "--out", str(tmp_path)]) == 0
    rows = json.loads((tmp_path / "table3_calibration_study.json").read_text())["rows"]
    assert all(all(r["converged"]) for r in rows)
    # G and M are degenerate: the M = 4 optimum sits on G(1)·4^(1/(2D-4)) with the same misfit
    assert rows[1]["G_m"] == pytest.approx(rows[1]["G_predicted_from_M1_m"], rel=1e-4)
    assert rows[1]["rms_rel_residual"] == pytest.approx(rows[0]["rms_rel_residual"], rel=1e-6)
    assert rows[1]["mu_t"] == pytest.approx(rows[0]["mu_t"], rel=1e-4)
    assert max(rows[0]["start_spread_over_std_error"]) < 0.01


def test_wang2022_slip_study_short_form(tmp_path):
    from fitting import wang2022_slip

    assert wang2022_slip.main(["--short", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "wang2022_slip_fit.json").read_text())
    agree = result["agreement"]
    assert agree["n_converged"] == 3
    assert agree["max_spread_over_std_error"] < 0.5  # three starts, one optimum
    # refuses to overwrite its own earlier output
    assert wang2022_slip.main(["--short", "--out", str(tmp_path)]) == 2
