"""wang2022 Table 3: the issue's acceptance (calibrated F_s, K_tau within 10 % / 15 %)."""

import json

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._main import main
from tribojax._reproduce._table3 import max_rel_error


@pytest.fixture(scope="module")
def fit():
    return tj.calibrate_table3()


@pytest.fixture(scope="module")
def result(fit):
    return tj.reproduce_table3(fit)


def test_calibration_converges_and_is_identifiable(fit):
    assert fit.converged, fit.message
    assert fit.names == ("G_m", "mu_t", "sigma_s_Pa")
    assert np.all(np.isfinite(fit.std_errors)) and np.all(fit.std_errors > 0)
    assert fit.singular_values[-1] > 1e-3 * fit.singular_values[0]
    corr = fit.correlation
    np.testing.assert_allclose(np.diag(corr), 1.0, rtol=1e-12)
    np.testing.assert_allclose(corr, corr.T, rtol=1e-12)
    # docs/reproduction.md: G ≈ 7e-8 m at M ≈ 2, mu_t ≈ 0.14, sigma_s ≈ 1.9 GPa
    G2 = tj.equivalent_G(fit.values[0], 1.0, 2.8821, 2.0)
    assert 3e-8 < G2 < 1.5e-7
    assert fit.values[1] == pytest.approx(0.14, rel=0.1)
    assert fit.values[2] == pytest.approx(1.9e9, rel=0.1)


def test_acceptance_calibrated_within_tolerance(result):
    rows = result["table3"]
    # issue #2 acceptance: 10 % at 0.6-10 kPa, 15 % at 20 kPa, for F_s and K_tau
    for key in ("Fs_N", "Ktau_N_per_m"):
        assert max_rel_error(rows, key, (0.6, 10.0)) < 0.10, key
        assert max_rel_error(rows, key, (20.0, 20.0)) < 0.15, key


def test_published_inputs_are_far_off(result):
    # docs/reproduction.md: with Table 1's G, K_tau comes out ~5e3-6e3 too large, F_s 2-3.5x
    for r in result["table3"]:
        ratio = r["published_inputs"]["Ktau_N_per_m"] / r["paper"]["Ktau_N_per_m"]
        assert 1e3 < ratio < 1e5
        assert r["published_inputs"]["Fs_N"] > 1.2 * r["paper"]["Fs_N"]
        assert r["published_load_share"]["plastic"] > 0.9


def test_damping_trend_differs_from_the_paper(result):
    # Eq 24's damping falls with load; Table 3's is non-monotonic. Reported, not tuned.
    c = [r["calibrated"]["Ctau_Ns_per_m"] for r in result["table3"]]
    assert np.all(np.diff(c) < 0)
    paper = [r["paper"]["Ctau_Ns_per_m"] for r in result["table3"]]
    assert not (np.all(np.diff(paper) < 0) or np.all(np.diff(paper) > 0))


@pytest.mark.parametrize("start", [(3e-7, 0.3, 3e9), (1e-9, 0.12, 5e8)])
def test_distinct_starts_reach_the_same_optimum(fit, start):
    other = tj.calibrate_table3(start)
    assert other.converged
    np.testing.assert_allclose(other.values, fit.values, rtol=1e-4)
    assert np.all(np.abs(other.values - fit.values) < 0.01 * fit.std_errors)


@pytest.mark.slow
def test_cli_writes_json_and_figure(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["reproduce", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "calibrated: G_m" in text and "wrote" in text
    data = json.loads((out / "reproduction.json").read_text())
    assert len(data["table3"]) == 6
    for row in data["table3"]:
        assert set(row) >= {"vacuum_kPa", "load_N", "paper", "published_inputs", "calibrated"}
        for k in ("paper", "published_inputs", "calibrated"):
            assert set(row[k]) == {"Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m", "zmax_nm"}
    cal = data["table3_calibration"]
    assert set(cal) >= {"parameters", "std_errors", "correlation", "converged"}
    assert cal["converged"] is True
    assert (out / "table3.png").stat().st_size > 10_000
    # wu2015 (issue #4): the key the issue specifies, and its figure
    assert set(data["wu2015"]) == {"eq7_rms", "cbar_peak"}
    assert data["wu2015"]["cbar_peak"]["mindlin"]["Abar"] == pytest.approx(2.4, abs=1e-9)
    assert (out / "wu2015.png").stat().st_size > 10_000
    # issue 3: Tables 4-7 (slip). Acceptance: fitted alpha within 5 % of the paper's theory in
    # Tables 4 and 6, alpha = 1 within 15 % (docs/reproduction.md: ~2 % and ~13 % expected).
    rows = data["tables4to7"]
    assert len(rows) == 24 and {r["table"] for r in rows} == {4, 5, 6, 7}
    keys = {"table", "vacuum_kPa", "paper_theory_nm", "paper_measured_nm", "model_alpha1_nm"}
    assert all(set(r) >= keys | {"model_fitted_alpha_nm"} for r in rows)
    t46 = [r for r in rows if r["table"] in (4, 6)]
    assert max(abs(r["model_fitted_alpha_nm"] / r["paper_theory_nm"] - 1) for r in t46) < 0.05
    assert max(abs(r["model_alpha1_nm"] / r["paper_theory_nm"] - 1) for r in t46) < 0.15
    assert 1.1 < data["alpha_fit"]["alpha"] < 1.4 and data["alpha_fit"]["std_error"] > 0
    assert (out / "figure10.png").stat().st_size > 10_000
    # issue 5: the full-chain fit to the measured Tables 4-7 (keys of the issue), and its
    # acceptance: no worse than the paper's own theory on the same 24 cells
    fm = data["fit_measured"]
    keys = {"parameters", "std_errors", "correlation", "rms_relative_residual", "converged"}
    assert set(fm) >= keys | {"paper_theory_rms_relative_residual"}
    assert fm["converged"] is True and len(fm["cells"]) == 24
    assert set(fm["std_errors"]) == set(fm["free_parameters"]) == {"D", "G_m", "mu_t"}
    assert fm["rms_relative_residual"] < fm["paper_theory_rms_relative_residual"]
    assert fm["symmetric_model_bound_rms_relative_residual"] <= fm["rms_relative_residual"]
    # issue 19: the robust fit flags Table 5 at 20 kPa (the paper's fibre bending) and, on the
    # cells it keeps, beats the paper's own theory (0.215 on the 23 other cells)
    assert {"loss", "flagged_cells", "rms_relative_residual_unflagged", "robust"} <= set(fm)
    assert fm["loss"]["kind"] in ("student_t", "gaussian") and fm["robust"]["converged"] is True
    flagged = {
        (c["table"], c["vacuum_kPa"]): c["standardized_residual"] for c in fm["flagged_cells"]
    }
    # ln|measured/model| far below the others (measured −0.47 nm, the model ~ −2.6 nm)
    assert flagged[(5, 20.0)] < -5
    keep = [r for r in rows if (r["table"], r["vacuum_kPa"]) not in flagged]
    paper = np.sqrt(
        np.mean([(r["paper_theory_nm"] / r["paper_measured_nm"] - 1) ** 2 for r in keep])
    )
    assert fm["paper_theory_rms_relative_residual_unflagged"] == pytest.approx(paper, rel=1e-9)
    if set(flagged) == {(5, 20.0)}:
        assert paper == pytest.approx(0.2145, abs=5e-4)  # the tables' error columns, 23 cells
    assert (
        fm["rms_relative_residual_unflagged"] < fm["paper_theory_rms_relative_residual_unflagged"]
    )
    assert fm["rms_relative_residual_unflagged"] < fm["plain_rms_relative_residual_unflagged"]
    assert (out / "fit_measured.png").stat().st_size > 10_000
    # issue 31: the reproduction's own programs hold no host callback, so their traces are stored
    from tribojax._export import export_dir
    from tribojax._reproduce import _tables4to7, _wu2015

    if export_dir() is not None:
        for fn in (
            _tables4to7._table3_phase_slips,
            _tables4to7._figure10,
            _wu2015._curves,
            _wu2015._newton_peak,
        ):
            assert fn.programs and None not in fn.programs.values(), fn.__name__


def test_reproduce_reports_a_fit_that_does_not_converge(monkeypatch, capsys):
    # issue 5 point 6: a non-converged full-chain fit gives a clear message and False (the CLI
    # then exits 1); the fit itself is replaced by a stand-in so that this test is cheap
    from tribojax._cli import _reproduce as _cli
    from tribojax._fit._result import FitResult
    from tribojax._reproduce import _chain_fit as _fit_chain

    def stand_in(start=None, **kw):
        fit = FitResult(
            names=("D",),
            values=np.ones(1),
            std_errors=np.ones(1),
            covariance=np.eye(1),
            correlation=np.eye(1),
            theta=np.zeros(1),
            residuals=np.zeros(24),
            singular_values=np.ones(1),
            converged=False,
            steps=60,
            message="The maximum number of steps was reached",
        )
        return _fit_chain.ChainFit(
            fit=fit,
            parameters=dict(_fit_chain.DEFAULTS),
            free=("D",),
            model_nm=_fit_chain.measured_slips(),
            target_nm=_fit_chain.measured_slips(),
            scaled_singular_values=np.ones(1),
            scaled_right_vectors=np.eye(1),
            wall_s=0.0,
            evaluations=0,
            start=dict(_fit_chain.DEFAULTS),
        )

    monkeypatch.setattr(_fit_chain, "fit_measured_slips", stand_in)
    result = {}
    assert _cli._reproduce_fit_measured(result) is False
    assert "did not converge: The maximum number of steps" in capsys.readouterr().err
    assert result["fit_measured"]["converged"] is False
