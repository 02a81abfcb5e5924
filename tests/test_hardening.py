"""Defects a hostile but realistic user found (issue 18), each reproduced through the CLI or API.

Every CLI error is one line `tribojax <cmd>: error: ...` with exit status 2 (bad input) or 1
(failed computation), never a traceback; nothing is left behind by a failed run.
"""

import dataclasses
import json
import os
import re
import stat
from pathlib import Path

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli import _fit as cli_fit
from tribojax._cli._main import main
from tribojax._fit._result import fit_statistics
from tribojax._io._files import write_json_atomic
from tribojax._predict import _fit_methods as fit_methods

MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22
SHARED = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "topography"


def _loop(tmp_path, name="loop.csv", f_scale=1.0, noise_std=None):
    loop = tj.synthetic_loop(
        tj.Jenkins(MU, N, KD), 3 * MU * N / KD, OMEGA, noise=0.004, seed=4, normal_load=N
    )
    loop = dataclasses.replace(loop, f=loop.f * f_scale, noise_std=noise_std)
    path = tmp_path / name
    tj.write_loop(loop, path)
    return path


def _one_error_line(err: str, cmd: str) -> str:
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ": error: " in ln]
    assert len(lines) == 1 and lines[0].startswith(f"tribojax {cmd}: error: "), err
    return lines[0]


# --- 1, 6: concurrent writers and the destination checked before the work ----------------------


def test_a_second_writer_to_the_same_out_refuses(tmp_path, capsys, monkeypatch):
    src, out = _loop(tmp_path), tmp_path / "out"
    real, inner = fit_methods.fit_loop, []

    def racing_fit(*a, **k):  # a second run with the same --out starts while the first fits
        inner.append(main(["fit", str(src), "--out", str(out)]))
        return real(*a, **k)

    monkeypatch.setattr(fit_methods, "fit_loop", racing_fit)
    assert main(["fit", str(src), "--out", str(out)]) == 0
    assert inner == [2]
    err = capsys.readouterr().err
    assert "another tribojax run is writing" in err and str(out / "fit.json") in err
    assert json.loads((out / "fit.json").read_text())["converged"]
    assert sorted(p.name for p in out.iterdir()) == ["fit.json", "fit.png"]  # no lock left


def test_exclusive_write_never_replaces_a_file(tmp_path):
    target = tmp_path / "r.json"
    write_json_atomic(target, {"a": 1}, exclusive=True)
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        write_json_atomic(target, {"a": 2}, exclusive=True)
    assert json.loads(target.read_text()) == {"a": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]  # no temporary file left


def test_bad_destination_is_refused_before_the_fit(tmp_path, capsys, monkeypatch):
    src = _loop(tmp_path)
    monkeypatch.setattr(fit_methods, "fit_loop", lambda *a, **k: pytest.fail("fitted anyway"))
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert main(["fit", str(src), "--out", str(afile)]) == 2
    assert "is a file, not an output folder" in _one_error_line(capsys.readouterr().err, "fit")
    if os.geteuid() != 0:  # root writes anywhere
        ro = tmp_path / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        assert main(["fit", str(src), "--out", str(ro / "o")]) == 2
        assert "cannot" in _one_error_line(capsys.readouterr().err, "fit")


# --- 2, 3: honest uncertainty ---------------------------------------------------------------


def test_stated_noise_contradicted_scales_the_errors(tmp_path, capsys):
    # force noise 0.004 N, but the sidecar claims 4e-13 N (10^10 times too small)
    src = _loop(tmp_path, noise_std=4e-13)
    out = tmp_path / "o"
    assert main(["fit", str(src), "--out", str(out), "--element", "jenkins"]) == 0
    res = json.loads((out / "fit.json").read_text())
    assert res["noise_consistent"] is False and res["reduced_chi2"] > 1e18
    assert "reduced chi2" in capsys.readouterr().err
    assert "scaled" in res["uncertainty_model"]
    # the same errors as a fit that estimates the noise from the residuals (within 1 %; the
    # loop model, as `tribojax fit` fits by default)
    free = tj.fit_loop(tj.read_loop(src), "jenkins", sigma=None, model="history")
    ref = tj.fit_loop(
        dataclasses.replace(tj.read_loop(src), noise_std=None), "jenkins", model="history"
    )
    for k, name in enumerate(ref.names):
        assert res["std_errors"][name] == pytest.approx(ref.std_errors[k], rel=1e-2)
        assert free.std_errors[k] == pytest.approx(ref.std_errors[k], rel=1e-2)
    # a stated noise that is right keeps its own errors and says so
    good = tj.fit_loop(
        dataclasses.replace(tj.read_loop(src), noise_std=0.004), "jenkins", model="history"
    )
    assert good.noise_consistent is True and 0.5 < good.reduced_chi2 < 2


def test_unidentifiable_direction_is_reported():
    # two parameters that enter only through their sum: the direction (1, -1)/√2 is undetermined
    rng = np.random.default_rng(0)
    x = rng.normal(size=50)
    J = np.stack([x, x, np.ones(50)], axis=1)
    r = rng.normal(size=50)
    fit = fit_statistics(
        np.zeros(3),
        r,
        J,
        names=("a", "b", "c"),
        transform=lambda t: t,
        sigma_known=True,
        result=tj.RESULTS.successful,
        steps=3,
    )
    assert fit.converged and not fit.as_dict()["identified"]
    (d,) = fit.unidentifiable
    assert d["relative_singular_value"] < 1e-12
    np.testing.assert_allclose(
        [d["direction"][k] for k in "abc"], [2**-0.5, -(2**-0.5), 0], atol=1e-12
    )
    assert np.isinf(fit.std_errors[:2]).all()
    text = cli_fit.uncertainty_warnings(fit.as_dict())
    assert len(text) == 1 and "+0.707*a -0.707*b" in text[0] and "not identifiable" in text[0]


def test_identified_fit_reports_no_direction(tmp_path):
    fit = tj.fit_loop(tj.read_loop(_loop(tmp_path)), "jenkins", model="steady")
    d = fit.as_dict()
    assert d["identified"] and d["unidentifiable"] == [] and d["noise_consistent"] is None


def test_a_failed_loop_fit_raises_unless_asked_not_to(tmp_path):
    loop = tj.read_loop(_loop(tmp_path))
    fit = tj.fit_loop(loop, "jenkins", max_steps=1, throw=False, model="steady")
    assert not fit.converged and fit.result == tj.RESULTS.nonlinear_max_steps_reached
    with pytest.raises(tj.FitError, match="max_steps = 1") as err:  # the default: it raises
        tj.fit_loop(loop, "jenkins", max_steps=1, model="steady")
    assert np.array_equal(err.value.fit.values, fit.values)


def test_D_near_either_end_is_not_silent():
    def model(D, throw=True):
        return tj.FractalContact(
            tj.FractalSurface(D, 4.36e-8, 1.0),
            tj.wang2022_pair(sigma_s=1.893e9),
            mu_t=0.1416,
            tangential_load=0.321,
            mass=0.321,
            throw=throw,
        )

    with pytest.raises(Exception, match="fully plastic"):  # no tangential stiffness at all
        model(2.001)(3.0)
    with pytest.warns(RuntimeWarning, match="no asperity is elastic"):  # F_s = 0, K_tau > 0
        out = model(2.999)(3.0)
    assert float(out.F_s) == 0.0 and float(out.z_max) == 0.0 and float(out.K_tau) > 0
    assert bool(out.no_static_friction) and not bool(out.all_plastic)
    assert not bool(model(2.999)(30.0).no_static_friction)


def test_contact_cli_warns_when_F_s_is_zero(capsys):
    assert main(["contact", "--D", "2.999", "--G", "4.36e-8", "--load", "3", "30"]) == 0
    err = capsys.readouterr().err
    assert err.count("warning: ") == 1 and "load 3 N: no asperity is elastic" in err


# --- 4: a start from the CLI ----------------------------------------------------------------


def test_fit_start_from_the_command_line(tmp_path, capsys):
    src = _loop(tmp_path)
    out = tmp_path / "o"
    assert (
        main(
            [
                "fit",
                str(src),
                "--out",
                str(out),
                "--element",
                "jenkins",
                "--start",
                "mu_N=0.5",
                "K_d=3e6",
            ]
        )
        == 0
    )
    res = json.loads((out / "fit.json").read_text())
    assert res["parameters"]["K_d"] == pytest.approx(KD, rel=0.05)
    for bad in (["mu_N"], ["mu_N=x"], ["=3"]):
        assert main(["fit", str(src), "--out", str(tmp_path / "p"), "--start", *bad]) == 2
        assert "expected NAME=VALUE" in _one_error_line(capsys.readouterr().err, "fit")
    assert main(["fit", str(src), "--out", str(tmp_path / "p"), "--start", "F_s=1"]) == 2
    assert "unknown key" in _one_error_line(capsys.readouterr().err, "fit")
    assert not (tmp_path / "p").exists()


@pytest.mark.parametrize("start", [["mu_N=882"], ["K_d=1"], ["mu_N=1e300"]])
def test_a_start_the_data_cannot_inform_is_exit_1(tmp_path, capsys, start):
    # issue 33 items 1 and 6: a start above every measured force (the element never slips: zero
    # gradient in mu_N) or a K_d so soft that the element slips at once (no gradient in K_d)
    # used to end as "converged, identified" with mu_N = 882 +- inf, or with exit 2 "mu is
    # outside the allowed range" when the optimiser stepped out; now the stepped-out trial is a
    # rejected step (failures as NaN inside the compiled fit) and the flat end is exit 1
    src = _loop(tmp_path)
    out = tmp_path / "o"
    assert (
        main(
            [
                "fit",
                str(src),
                "--out",
                str(out),
                "--element",
                "mindlin",
                "--quiet",
                "--start",
                *start,
            ]
        )
        == 1
    )
    captured = capsys.readouterr()
    line = _one_error_line(captured.err, "fit")
    assert "do not determine" in line and "--start" in line
    assert "± inf" in captured.out  # the undetermined parameter is not printed as a result
    assert "outside the allowed range" not in line
    res = json.loads((out / "fit.json").read_text())  # the record of what happened stays
    assert res["identified"] is False and res["unidentifiable"]


@pytest.mark.parametrize(
    "option, pattern",
    [
        (["--max-steps", "0"], r"--max-steps = 0 must be at least 1"),
        (["--decimate", "0"], r"--decimate = 0 is outside the allowed range \[1, inf\)"),
        (["--decimate", "x"], r"--decimate = 'x': expected auto, off or an integer"),
        (["--max-samples", "3"], r"--max-samples = 3 is outside the allowed range \[4, inf\)"),
        (["--start", "mu_N=nan"], r"mu_N"),
        (["--start", "K_d=inf"], r"--start 'K_d=inf': the value must be a finite number"),
    ],
)
def test_fit_numeric_options_are_refused_before_the_fit(tmp_path, capsys, option, pattern):
    # issue 33: every numeric option of `fit` out of range is exit 2 with one line, no output
    src = _loop(tmp_path)
    out = tmp_path / "o"
    assert main(["fit", str(src), "--out", str(out), "--quiet", *option]) == 2
    assert re.search(pattern, _one_error_line(capsys.readouterr().err, "fit"))
    assert not out.exists() or not any(out.iterdir())


def test_alpha_is_refused_for_loops(tmp_path, capsys):
    src = _loop(tmp_path)
    assert main(["fit", str(src), "--out", str(tmp_path / "o"), "--alpha", "1"]) == 2
    assert "--alpha is for slip runs" in _one_error_line(capsys.readouterr().err, "fit")
    assert not (tmp_path / "o").exists()


# --- 5: no partial output -------------------------------------------------------------------


def test_hysteresis_with_a_bad_loop_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "in" / "bad.csv"
    bad.parent.mkdir()
    bad.write_text("t_s,u_m,f_N\n0,0,0\n0.1,nan,1\n")
    out = tmp_path / "out"
    assert main(["hysteresis", "--loop", str(bad), "--out", str(out), "--n", "5"]) == 2
    assert "bad.csv, line 3" in _one_error_line(capsys.readouterr().err, "hysteresis")
    assert not out.exists()


def test_contact_json_into_a_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "DIR").mkdir()
    assert main(["contact", "--D", "2.88", "--G", "4.36e-8", "--load", "5", "--json", "DIR"]) == 2
    assert "is a folder" in _one_error_line(capsys.readouterr().err, "contact")
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["DIR"]


def test_json_is_written_world_readable_like_the_figures(tmp_path):
    src = _loop(tmp_path)
    out = tmp_path / "o"
    assert main(["fit", str(src), "--out", str(out)]) == 0
    umask = os.umask(0)
    os.umask(umask)
    for name in ("fit.json", "fit.png"):
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o666 & ~umask, name


# --- 7, 8: messages, not tracebacks ---------------------------------------------------------


def test_contact_errors_are_one_line(tmp_path, capsys):
    for D, G, load, expect in (
        ("2.88", "4.36e-8", "inf", "--load = inf N is outside the allowed range"),
        ("2.88", "4.36e-8", "-1", "outside the allowed range"),
        ("2.88", "-1", "5", "G = -1 m is outside the allowed range"),
        ("3.5", "4.36e-8", "5", "D = 3.5 is outside the allowed range"),
    ):
        argv = ["contact", "--D", D, "--G", G, "--load", load]
        assert main(argv) == 2, argv
        assert expect in _one_error_line(capsys.readouterr().err, "contact")


@pytest.mark.parametrize("cmd", ["fit", "discover", "hysteresis"])
def test_a_loop_with_zero_force(tmp_path, capsys, cmd):
    t = np.linspace(0, 3 / 22, 600, endpoint=False)
    loop = tj.HysteresisLoop(
        t=t, u=1e-6 * np.cos(2 * np.pi * 22 * t), f=0 * t, normal_load=N, frequency=22.0
    )
    src = tmp_path / "zero.csv"
    tj.write_loop(loop, src)
    out = tmp_path / "o"
    argv = [cmd, str(src), "--out", str(out)]
    if cmd == "hysteresis":
        argv = ["hysteresis", "--loop", str(src), "--out", str(out), "--n", "5"]
    assert main(argv) == 2
    line = _one_error_line(capsys.readouterr().err, cmd)
    assert "zero.csv" in line and "force is constant" in line
    assert not out.exists()


def test_ctrl_c_is_one_line_and_130(tmp_path, capsys, monkeypatch):
    src = _loop(tmp_path)

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(fit_methods, "fit_loop", interrupted)
    assert main(["fit", str(src), "--out", str(tmp_path / "o")]) == 130
    err = capsys.readouterr().err
    assert err.strip() == "tribojax fit: interrupted (Ctrl-C)"
    assert not (tmp_path / "o").exists()


def test_debug_shows_the_traceback(tmp_path):
    with pytest.raises(ValueError, match="outside the allowed range"):
        main(["--debug", "contact", "--D", "3.5", "--G", "1e-9", "--load", "5"])
    with pytest.raises(ValueError):
        main(["contact", "--D", "3.5", "--G", "1e-9", "--load", "5", "--debug"])


def test_unexpected_failure_is_exit_1(capsys, monkeypatch):
    from tribojax._cli import _contact

    def broken(*a, **k):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(_contact, "_contact_rows", broken)
    assert main(["contact", "--D", "2.88", "--G", "4.36e-8", "--load", "5"]) == 1
    assert "ZeroDivisionError" in _one_error_line(capsys.readouterr().err, "contact")


# --- unclear messages -----------------------------------------------------------------------


def test_shapes_and_empty_arrays_name_the_parameter():
    pair = tj.wang2022_pair(sigma_s=1.893e9)
    kw = dict(mu_t=0.1416, tangential_load=0.321, mass=0.321)
    model = tj.FractalContact(tj.FractalSurface(2.5, 1e-10, 1.0), pair, **kw)
    for load in (np.ones((2, 3)), np.array([])):
        with pytest.raises(ValueError, match=r"load has shape \("):
            model(load)
    with pytest.raises(ValueError, match=r"D has shape \(2,\)"):
        tj.FractalContact(tj.FractalSurface(np.array([2.3, 2.4]), 1e-10, 1.0), pair, **kw)(10.0)


def test_bom_cp1252_and_header_order(tmp_path, capsys):
    src = _loop(tmp_path)
    text = src.read_text()
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode())
    bom.with_suffix(".json").write_bytes(src.with_suffix(".json").read_bytes())
    np.testing.assert_array_equal(tj.read_loop(bom).f, tj.read_loop(src).f)  # a BOM is accepted
    lines = text.splitlines()
    k = next(i for i, ln in enumerate(lines) if ln and ln[0].isdigit()) + 2
    lines[k - 1] += " \x80"  # a Windows-1252 euro sign on line k
    cp = tmp_path / "cp.csv"
    cp.write_bytes("\n".join(lines).encode("latin-1"))
    with pytest.raises(tj.DataFileError, match=rf"cp.csv, line {k}: byte 0x80 is not UTF-8"):
        tj.read_loop(cp)
    odd = tmp_path / "odd.csv"
    odd.write_text("zeta,alpha,mid\n1,2,3\n")
    assert main(["fit", str(odd), "--out", str(tmp_path / "o")]) == 2
    assert "header ['zeta', 'alpha', 'mid']" in _one_error_line(capsys.readouterr().err, "fit")


def test_discover_on_two_rows_names_the_file(tmp_path, capsys):
    src = tmp_path / "two.csv"
    src.write_text("time_s,stage_accel_m_s2,slip_m\n0,0,0\n0.1,1,1e-9\n")
    (tmp_path / "two.json").write_text('{"mass_kg": 0.321}')
    assert main(["discover", str(src), "--out", str(tmp_path / "o")]) == 2
    assert str(src) in _one_error_line(capsys.readouterr().err, "discover")
    assert not (tmp_path / "o").exists()


# --- real instrument files ------------------------------------------------------------------

REAL = ["xy-4.txt", "dektak-1.csv", "di-1.di", "x3p-2.x3p"]


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/topography is absent")
@pytest.mark.parametrize("name", REAL)
def test_real_topographies_get_an_answer(tmp_path, capsys, name):
    pytest.importorskip("SurfaceTopography")
    out = tmp_path / "c.json"
    code = main(["contact", "--topography", str(SHARED / name), "--load", "5", "--json", str(out)])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    if name == "di-1.di":  # smoother than any fractal over every band: each method's D is named
        assert code == 0 and "structure: D = 1." in err and "smoother" in err
        surface = json.loads(out.read_text())["surface"]
        assert surface["D"] is None and len(surface["findings"]) == 3 and surface["warning"]
        assert all("rms log10 residual" in f for f in surface["findings"])
        assert json.loads(out.read_text())["contact"] == []
        return
    assert code == 0
    surface = json.loads(out.read_text())["surface"]
    assert 2 < surface["D"] < 3 and surface["warning"] and surface["rms_residual"] > 0.15
    assert "warning: " in err and "not a clean power law" in err


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/topography is absent")
def test_contact_band_on_a_real_profile(tmp_path, capsys):
    out = tmp_path / "c.json"
    code = main(
        [
            "contact",
            "--topography",
            str(SHARED / "dektak-1.csv"),
            "--method",
            "rms",
            "--band",
            "1e-5",
            "3e-4",
            "--load",
            "5",
            "--json",
            str(out),
        ]
    )
    assert code == 0 and "by rms, band" in capsys.readouterr().out
    surface = json.loads(out.read_text())["surface"]
    assert 1e-5 <= surface["band"][0] < surface["band"][1] <= 3e-4 and 2 < surface["D"] < 3


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/topography is absent")
@pytest.mark.parametrize("name", ["di-1.di", "x3p-2.x3p"])
def test_truncated_instrument_files_say_so(tmp_path, name):
    pytest.importorskip("SurfaceTopography")
    cut = tmp_path / name
    cut.write_bytes((SHARED / name).read_bytes()[:1_000_000])
    with pytest.raises(tj.DataFileError, match="truncated or damaged") as info:
        tj.read_topography(cut)
    assert "tried" not in str(info.value) and len(str(info.value)) < 400


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/topography is absent")
def test_contact_band_where_the_surface_is_smoother_than_fractal(tmp_path, capsys):
    pytest.importorskip("SurfaceTopography")
    out = tmp_path / "c.json"
    code = main(
        [
            "contact",
            "--topography",
            str(SHARED / "di-1.di"),
            "--band",
            "1e-8",
            "1e-7",
            "--load",
            "5",
            "--json",
            str(out),
        ]
    )
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err and "over the given band" in err
    surface = json.loads(out.read_text())["surface"]
    assert surface["band"] == [1e-8, 1e-7] and surface["findings"][0].startswith("psd: D = 1.")


def test_no_user_file_is_replaced_without_force_and_no_input_even_with_it(tmp_path, capsys):
    # a user's own fit.png in --out (no fit.json there): refused without --force, unchanged
    path, out = _loop(tmp_path), tmp_path / "out"
    out.mkdir()
    (out / "fit.png").write_bytes(b"the user's own figure")
    assert main(["fit", str(path), "--out", str(out), "--element", "jenkins"]) == 2
    assert "fit.png exists; refusing" in _one_error_line(capsys.readouterr().err, "fit")
    assert (out / "fit.png").read_bytes() == b"the user's own figure"
    assert not (out / "fit.json").exists()
    # --force replaces the command's own files; the --from model is an input: never replaced
    assert main(["fit", str(path), "--out", str(out), "--element", "jenkins", "--force"]) == 0
    model = (out / "fit.json").read_bytes()
    for cmd in ("fit", "discover"):
        name = "fit.json" if cmd == "fit" else "discovery.json"
        if cmd == "discover":
            (out / name).write_bytes(model)
        code = main([cmd, str(path), "--from", str(out / name), "--out", str(out), "--force"])
        assert code == 2, cmd
        assert "is an input file" in _one_error_line(capsys.readouterr().err, cmd)
        assert (out / name).read_bytes() == model


@pytest.mark.parametrize("value", ["0", "abc", "²", "-1"])
def test_a_bad_fit_workers_setting_is_one_line_exit_2(tmp_path, value):
    import subprocess
    import sys

    cmd = [
        sys.executable,
        "-m",
        "tribojax._cli._main",
        "contact",
        "--D",
        "2.5",
        "--G",
        "1e-9",
        "--load",
        "5",
    ]
    out = subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "TRIBOJAX_FIT_WORKERS": value},
    )
    assert out.returncode == 2, out.stderr[-2000:]
    line = _one_error_line(out.stderr, "contact")
    assert "TRIBOJAX_FIT_WORKERS" in line and repr(value) in line


def test_a_bad_equinox_error_setting_is_one_line_exit_2(tmp_path):
    # the command reads EQX_ON_ERROR for equinox (its default: nan); a bad value was equinox's
    # import-time traceback
    import subprocess
    import sys

    cmd = [
        sys.executable,
        "-m",
        "tribojax._cli._main",
        "contact",
        "--D",
        "2.5",
        "--G",
        "1e-9",
        "--load",
        "5",
    ]
    out = subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "EQX_ON_ERROR": "maybe"},
    )
    assert out.returncode == 2, out.stderr[-2000:]
    assert "EQX_ON_ERROR = 'maybe'" in _one_error_line(out.stderr, "contact")


def test_deeply_nested_json_is_refused_naming_the_file(tmp_path, capsys):
    # a sidecar and a model file nested 100,000 deep: exit 2 naming the file, no RecursionError
    deep = "[" * 100_000 + "]" * 100_000
    path = _loop(tmp_path)
    side = path.with_suffix(".json")
    original = side.read_text()
    side.write_text(deep)
    assert main(["fit", str(path), "--out", str(tmp_path / "o")]) == 2
    line = _one_error_line(capsys.readouterr().err, "fit")
    assert str(side) in line and "nested too deeply" in line
    side.write_text(original)
    model = tmp_path / "model.json"
    model.write_text(deep)
    assert main(["predict", str(model), str(path), "--out", str(tmp_path / "p")]) == 2
    line = _one_error_line(capsys.readouterr().err, "predict")
    assert str(model) in line and "nested too deeply" in line


def test_a_model_file_with_a_byte_order_mark_is_read_and_utf32_named(tmp_path, capsys):
    path, out = _loop(tmp_path), tmp_path / "out"
    assert main(["fit", str(path), "--out", str(out), "--element", "jenkins"]) == 0
    fit_json = out / "fit.json"
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + fit_json.read_bytes())
    assert tj.load_model(bom).as_dict() == tj.load_model(fit_json).as_dict()
    wide = tmp_path / "wide.json"
    wide.write_bytes(fit_json.read_text().encode("utf-32"))  # with its byte-order mark
    with pytest.raises(tj.DataFileError, match="UTF-32 text"):
        tj.load_model(wide)


def test_a_fit_that_is_not_a_result_saves_no_model_to_predict_with(tmp_path, capsys):
    # a start whose slider never slips (μN far above the peak force): exit 1, "not a result",
    # and fit.json carries no fitted_model, so predict refuses it naming why
    path, out = _loop(tmp_path), tmp_path / "out"
    assert (
        main(["fit", str(path), "--out", str(out), "--element", "jenkins", "--start", "mu_N=50"])
        == 1
    )
    assert "not a result" in _one_error_line(capsys.readouterr().err, "fit")
    saved = json.loads((out / "fit.json").read_text())
    assert saved["fitted_model"] is None and "do not determine" in saved["not_a_result"]
    assert main(["predict", str(out / "fit.json"), str(path), "--out", str(tmp_path / "p")]) == 2
    assert "fitted_model" in _one_error_line(capsys.readouterr().err, "predict")


def test_a_record_given_twice_to_a_joint_fit_is_refused(tmp_path, capsys):
    # the same path, the same file through "..", an identical copy: counted twice, the standard
    # errors would shrink by √2 with no new data
    path = _loop(tmp_path)
    copy = tmp_path / "copy.csv"
    copy.write_bytes(path.read_bytes())
    copy.with_suffix(".json").write_bytes(path.with_suffix(".json").read_bytes())
    (tmp_path / "sub").mkdir()
    dotted = tmp_path / "sub" / ".." / path.name
    for other in (path, dotted, copy):
        out = tmp_path / f"out-{other.name}-{len(str(other))}"
        assert main(["fit", str(path), str(other), "--model", "jenkins", "--out", str(out)]) == 2
        assert "same samples" in _one_error_line(capsys.readouterr().err, "fit")
    loop = tj.read_loop(path)
    with pytest.raises(ValueError, match=r"loops\[1\].*same samples as loops\[0\]"):
        tj.fit_history([loop, tj.read_loop(copy)], "jenkins")


@pytest.mark.parametrize("column", ["displacement_m", "force_N"])
def test_a_record_scaled_to_nothing_is_refused_with_file_line_and_value(tmp_path, capsys, column):
    # displacement or force ×1e-300 (a unit error): exit 2 naming the file, the line and the
    # value, not LAPACK's DLASCL lines, "SVD did not converge" or a ZeroDivisionError
    path, source = tmp_path / "tiny.csv", _loop(tmp_path)
    lines = source.read_text().splitlines()
    header = lines[0].split(",")
    k = header.index(column)
    rows = [ln.split(",") for ln in lines[1:]]
    for r in rows:
        r[k] = repr(float(r[k]) * 1e-300)
    path.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    path.with_suffix(".json").write_bytes(source.with_suffix(".json").read_bytes())
    assert main(["fit", str(path), "--out", str(tmp_path / "o")]) == 2
    line = _one_error_line(capsys.readouterr().err, "fit")
    assert f"{path}, line " in line and "largest value, below the plausible" in line


def test_a_lock_whose_process_id_was_reused_is_taken_over(tmp_path, capsys):
    import socket

    from tribojax._cli._lock import lock_stamp

    path, out = _loop(tmp_path), tmp_path / "out"
    out.mkdir()
    lock = out / ".fit.json.lock"
    # a live process (this one) holding the lock as recorded: held, exit 2
    lock.write_text(lock_stamp())
    assert main(["fit", str(path), "--out", str(out), "--element", "jenkins"]) == 2
    assert "another tribojax run" in _one_error_line(capsys.readouterr().err, "fit")
    # the same process id, recorded with another start time: a dead run whose id was reused
    pid, started, host = lock_stamp().split()
    if started == "-":
        pytest.skip("no process start times here (/proc)")
    lock.write_text(f"{pid} {int(started) + 1} {socket.gethostname()}\n")
    assert main(["fit", str(path), "--out", str(out), "--element", "jenkins"]) == 0
    assert "taking over the lock" in capsys.readouterr().err
    assert not lock.exists() and (out / "fit.json").exists()
