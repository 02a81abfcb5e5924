"""A saved model file is checked like a `--start`: each value within its parameter's range, its
units those of the model on the record (issue 72, row 5); and a file the user wrote is never
removed by a command (row 16)."""

import dataclasses
import json

import numpy as np
import pytest

import tribojax as tj
from tribojax._cli._main import main

MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """A loop record and the fit.json of its Jenkins loop model."""
    folder = tmp_path_factory.mktemp("model-files")
    loop = tj.synthetic_loop(
        tj.Jenkins(MU, N, KD), 3 * MU * N / KD, OMEGA, noise=0.004, seed=4, normal_load=N
    )
    path = folder / "loop.csv"
    tj.write_loop(dataclasses.replace(loop, noise_std=None), path)
    assert main(["fit", str(path), "--out", str(folder / "fit"), "--element", "jenkins"]) == 0
    return path, json.loads((folder / "fit" / "fit.json").read_text())


def _edited(tmp_path, fit, **change):
    d = json.loads(json.dumps(fit))
    for key, value in change.items():
        field, name = key.split("__")
        d["fitted_model"][field][name] = value
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(d))
    return path


@pytest.mark.parametrize(
    "name, value, shown",
    [
        ("K_d", 0.0, "'parameters.K_d' = 0 N/m is outside the allowed range (0, 1e+20]"),
        ("K_d", 1e308, "'parameters.K_d' = 1e+308 N/m is outside the allowed range (0, 1e+20]"),
        ("mu_N", -1.0, "'parameters.mu_N' = -1 N is outside the allowed range (0, 1e+20]"),
    ],
)
def test_a_model_value_outside_its_range_is_exit_2_naming_it(
    saved, tmp_path, capsys, name, value, shown
):
    record, fit = saved
    model = _edited(tmp_path, fit, **{f"parameters__{name}": value})
    out = tmp_path / "p"
    assert main(["predict", str(model), str(record), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and shown in err and str(model) in err
    assert not out.exists()
    with pytest.raises(ValueError, match=r"outside the allowed range"):
        tj.predict(tj.load_model(model), tj.read_loop(record))


def test_a_model_in_other_units_is_refused(saved, tmp_path, capsys):
    record, fit = saved
    model = _edited(tmp_path, fit, units__K_d="N/mm")
    assert main(["predict", str(model), str(record), "--out", str(tmp_path / "p")]) == 2
    assert "field 'units.K_d' is 'N/mm'; the loop model on this record has K_d in 'N/m'" in (
        capsys.readouterr().err
    )


def test_the_saved_model_predicts_unchanged(saved, tmp_path):
    # the checks pass the file as written: the refit-free prediction of the fitted record
    record, fit = saved
    model = _edited(tmp_path, fit)
    pred = tj.predict(tj.load_model(model), tj.read_loop(record))
    assert 0 < pred.nrmse < 0.05


def test_a_history_model_is_checked_alike(tmp_path):
    model = tj.FittedModel(
        "history",
        {"mu_N": 0.9, "K_d": -1e6, "f0": 0.0},
        {"mu_N": "N", "K_d": "N/m", "f0": "N"},
        {"element": "jenkins"},
    )
    path = tmp_path / "m.json"
    path.write_text(json.dumps(model.as_dict()))
    with pytest.raises(ValueError, match=r"'parameters.K_d' = -1e\+06 N/m is outside the allowed"):
        tj.load_model(path)


def test_a_full_disk_names_the_file(saved, tmp_path, capsys, monkeypatch):
    import errno

    from tribojax._io import _files

    class Full:  # the file system has no space left: the OS error carries no file name
        def __init__(self, fd, *a, **k):
            _files.os.close(fd)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def write(self, text):
            raise OSError(errno.ENOSPC, "No space left on device")

    record, fit = saved
    monkeypatch.setattr(_files.os, "fdopen", Full)
    out = tmp_path / "p"
    model = _edited(tmp_path, fit)
    assert main(["predict", str(model), str(record), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{out / 'prediction.json'}: No space left on device" in err and "OSError" not in err
    assert not out.exists() or not any(out.iterdir())


def test_a_full_disk_at_the_lock_leaves_no_lock(saved, tmp_path, capsys, monkeypatch):
    import errno

    from tribojax._cli import _common

    def full(fd, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    record, fit = saved
    monkeypatch.setattr(_common.os, "write", full)
    out = tmp_path / "p"
    assert main(["predict", str(_edited(tmp_path, fit)), str(record), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"cannot write the lock file {out / '.prediction.json.lock'}: No space left" in err
    assert not out.exists()


# --- 4: a model saves the range it was fitted on; predict says when a record lies beyond it ----


def test_a_loop_far_beyond_the_fitted_amplitude_is_flagged(saved, tmp_path, capsys):
    record, fit = saved
    fitted = fit["fitted_model"]["fitted_range"]
    amp = fitted["amplitude"]["max"]
    assert fitted["amplitude"]["unit"] == "m" and amp == fitted["amplitude"]["min"]
    assert 0.9 * MU * N / KD * 3 < 2 * amp < 1.1 * 2 * MU * N / KD * 3  # the drive's ±3 A0
    assert fitted["normal_load"] == {"min": N, "max": N, "unit": "N"}
    big = tmp_path / "big.csv"  # the same contact driven 8x further: ~8x amplitude and velocity
    loop = tj.synthetic_loop(
        tj.Jenkins(MU, N, KD), 24 * MU * N / KD, OMEGA, noise=0.004, seed=5, normal_load=N
    )
    tj.write_loop(loop, big)
    model = _edited(tmp_path, fit)
    out = tmp_path / "p"
    assert main(["predict", str(model), str(big), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "extrapolation: the record's amplitude" in err and "lies outside the fitted range" in err
    far = json.loads((out / "prediction.json").read_text())["extrapolation"]
    assert {d["quantity"] for d in far} == {"amplitude", "velocity"}
    d = {d["quantity"]: d for d in far}["amplitude"]
    assert d["record_max"] / d["fitted_max"] == pytest.approx(8.0, rel=0.02)
    # the fitted record itself: nothing beyond, and the Python API says the same by a warning
    with pytest.warns(UserWarning) as said:
        tj.predict(tj.load_model(model), tj.read_loop(big))
    assert sorted(str(w.message).split("'s ")[1].split(" (")[0] for w in said) == [
        "amplitude",
        "velocity",
    ]
    assert tj.predict(tj.load_model(model), tj.read_loop(record)).extrapolation == []


def test_a_curve_model_at_twenty_times_the_speed_is_flagged():
    v = np.array([-200.0, -120.0, -60.0, -20.0, 20.0, 60.0, 120.0, 200.0])
    f = np.sign(v) * (0.01 + 2e-5 * np.abs(v))
    units = {"velocity_unit": "rpm", "friction_unit": "N m"}
    ones = np.ones_like(v)
    curve = tj.FrictionCurve(v, f, 1e-4 * ones, 0 * ones, 10 * ones, units=units)
    fast = tj.FrictionCurve(20 * v, f, 1e-4 * ones, 0 * ones, 10 * ones, units=units)
    model = tj.FittedModel(
        "curve",
        {"F_c": 0.01, "sigma2": 2e-5},
        {"F_c": "N m", "sigma2": "N m per rpm"},
        fitted_range={"velocity": {"min": 20.0, "max": 200.0, "unit": "rpm"}},
    )
    assert tj.predict(model, curve).extrapolation == []
    with pytest.warns(UserWarning, match=r"velocity \(400 to 4e\+03 rpm\)"):
        far = tj.predict(model, fast).extrapolation
    assert [d["quantity"] for d in far] == ["velocity"]
    # a range in other units is not compared; a model without a range says nothing is known
    other = dataclasses.replace(
        model, fitted_range={"velocity": {"min": 20.0, "max": 200.0, "unit": "rad/s"}}
    )
    assert tj.predict(other, fast).extrapolation == []
    assert tj.predict(dataclasses.replace(model, fitted_range={}), fast).extrapolation is None


def test_a_joint_fit_spans_its_records():
    from tribojax._io._record import extent_of

    loops = [
        tj.synthetic_loop(
            tj.Jenkins(MU, N, KD), a * MU * N / KD, OMEGA, noise=0.004, seed=4, normal_load=n
        )
        for a, n in ((3, N), (6, 2 * N))
    ]
    span = extent_of(loops)
    amps = [0.5 * np.ptp(lp.u) for lp in loops]
    assert span["amplitude"] == {"min": min(amps), "max": max(amps), "unit": "m"}
    assert span["normal_load"] == {"min": N, "max": 2 * N, "unit": "N"}


def test_a_model_not_finite_on_the_record_writes_nothing(saved, tmp_path, capsys):
    # a value inside its range whose prediction is not finite (μN = 5e-324: K_d·u/μN overflows)
    record, fit = saved
    model = _edited(tmp_path, fit, parameters__mu_N=5e-324)
    out = tmp_path / "p"
    assert main(["predict", str(model), str(record), "--out", str(out)]) == 1
    assert "not finite on this record (no file written)" in capsys.readouterr().err
    assert not out.exists()


def test_a_key_given_twice_is_refused_naming_it(saved, tmp_path, capsys):
    # which of two values is meant cannot be told: JSON parsers keep the last one silently
    record, fit = saved
    text = json.dumps(fit).replace('"K_d": ', '"K_d": 1.0, "K_d": ', 1)
    model = tmp_path / "twice.json"
    model.write_text(text)
    assert main(["predict", str(model), str(record), "--out", str(tmp_path / "p")]) == 2
    assert "the key 'K_d' appears twice" in capsys.readouterr().err
    assert (
        main(["fit", str(record), "--start", "mu_N=1", "mu_N=2", "--out", str(tmp_path / "f")]) == 2
    )
    assert "mu_N is given twice" in capsys.readouterr().err
