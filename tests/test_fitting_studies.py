"""The fitting/ studies run (short form) and show what they claim."""

import json
import os

import pytest
from fitting import wang2022_table3

pytestmark = pytest.mark.slow  # the second tier (tests/conftest.py)


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


def test_wu2015_loops_study_short_form(tmp_path):
    from fitting import wu2015_loops

    assert wu2015_loops.main(["--short", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "wu2015_loops.json").read_text())
    rows = res["rows"]
    assert len(rows) == 4 and all(r["converged"] for r in rows)
    for r in rows:
        # within 3 se where the loop slips; Jenkins at Ā = 1 does not slip: μN is only bounded
        # below (no finite se) while its stick slope still gives K_d
        if r["A_bar_true"] > 1 or r["element"] == "mindlin":
            assert abs(r["z_mu_N"]) < 3 and abs(r["z_K_d"]) < 3
        else:
            assert not (r["mu_N_se"] < 1e-3 * r["mu_N"])  # NaN or huge
            assert r["K_d"] == pytest.approx(r["K_d_true"], rel=1e-3)
    # gross slip (Ā = 3): the steady loop's K̄ is within 0.03 of Eq 7 for both elements
    for r in rows:
        if r["A_bar_true"] == 3.0:
            assert abs(r["K_bar"] - r["K_bar_eq7"]) < 0.03
    assert (tmp_path / "wu2015_loops.csv").read_text().count("\n") == 5


@pytest.mark.slow
@pytest.mark.skipif(
    os.environ.get("TRIBOJAX_FULL") != "1",
    reason="several robust full-chain fits (minutes); short CI form: the robust fit in the "
    "reproduce CLI test and tests/test_fit_robust.py",
)
def test_wang2022_robust_study_short_form(tmp_path):
    from fitting import wang2022_robust

    assert wang2022_robust.main(["--short", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "wang2022_robust.json").read_text())
    ll = {(r["loss"]["noise"], r["loss"]["nu"]): r["log_likelihood"] for r in res["noise_models"]}
    # heavy tails win over Gaussian errors for both shapes (the one 20 kPa cell, the 0.6 kPa ones)
    assert ll[("relative", 4.0)] > ll[("relative", None)] + 5
    assert ll[("absolute", 4.0)] > ll[("absolute", None)]
    assert wang2022_robust.main(["--short", "--out", str(tmp_path)]) == 2  # no overwrite
