"""User records: slip runs and loops on disk (CSV + sidecar), validation, synthetic runs."""

import json
import re

import numpy as np
import pytest

import tribojax as tj

ELEMENT = tj.PreSlipLuGre(0.4868, 1.4878e7, 750.0)  # Table 3, 0.6 kPa (F_s, K_τ; C_τ rounded)
MU, N, KD, OMEGA = 0.3, 2.94, 1.2e6, 2 * np.pi * 22


@pytest.fixture(scope="module")
def run():
    return tj.synthetic_slip_run(ELEMENT, n=461, noise=2e-10, seed=3, normal_load=17.4)


def test_synthetic_run_and_model_on_its_own_samples(run):
    assert len(run) == 461 and run.t[-1] == 2.3 and run.mass == 0.321
    assert run.noise_std == 2e-10 and run.normal_load == 17.4
    # the sampled trapezoid's drive stops the solver at its 8 corners (plus the end points) only
    np.testing.assert_allclose(
        run.profile().kinks(), [0, 0.1, 0.25, 0.6, 0.75, 1.5, 1.65, 2.0, 2.15, 2.3], atol=1e-12
    )
    sol = tj.simulate_run(ELEMENT, run)
    resid = np.asarray(sol.slip) - run.slip
    # the noise is all that separates the record from the model: sd 2e-10 m within 15 %
    assert np.std(resid) == pytest.approx(2e-10, rel=0.15)
    assert abs(np.mean(resid)) < 4 * 2e-10 / np.sqrt(len(run))
    # slip peaks at tens of nm (Tables 4-7 scale) and is not trivially zero
    assert 5e-9 < np.max(np.abs(run.slip)) < 1e-7
    assert isinstance(run.profile(), tj.MeasuredProfile)
    np.testing.assert_array_equal(np.asarray(run.profile().accelerations), run.accel)


def test_slip_run_round_trip(run, tmp_path):
    path = tmp_path / "run.csv"
    tj.write_slip_run(run, path, comment="synthetic\nseed 3")
    side = json.loads((tmp_path / "run.json").read_text())
    assert side == {"mass_kg": 0.321, "normal_load_N": 17.4, "noise_std_m": 2e-10}
    back = tj.read_slip_run(path)
    for name in ("t", "accel", "slip"):
        np.testing.assert_array_equal(getattr(back, name), getattr(run, name))
    assert (back.mass, back.normal_load, back.noise_std) == (0.321, 17.4, 2e-10)
    assert back.source == str(path)
    assert isinstance(tj.read_record(path), tj.SlipRun)
    # never overwrite: neither the CSV nor the sidecar
    before = path.read_bytes(), (tmp_path / "run.json").read_bytes()
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        tj.write_slip_run(run, path)
    other = tmp_path / "other.csv"
    (tmp_path / "other.json").write_text("{}")
    with pytest.raises(FileExistsError, match="other.json exists"):
        tj.write_slip_run(run, other)
    assert not other.exists()
    assert (path.read_bytes(), (tmp_path / "run.json").read_bytes()) == before
    tj.write_slip_run(run, path, overwrite=True, comment="synthetic\nseed 3")
    assert path.read_bytes() == before[0]
    # optional sidecar keys stay optional
    bare = tj.SlipRun(run.t, run.accel, run.slip, mass=0.5)
    tj.write_slip_run(bare, tmp_path / "bare.csv")
    assert json.loads((tmp_path / "bare.json").read_text()) == {"mass_kg": 0.5}
    back = tj.read_slip_run(tmp_path / "bare.csv")
    assert back.normal_load is None and back.noise_std is None


GOOD_ROWS = ["0,0,0", "0.1,0.5,1e-9", "0.2,1,2e-9", "0.3,1,2.5e-9"]
HEADER = "time_s,stage_accel_m_s2,slip_m"


def _slip_file(tmp_path, rows=GOOD_ROWS, sidecar='{"mass_kg": 0.321}', header=HEADER):
    path = tmp_path / "bad.csv"
    path.write_text("# rig log\n" + header + "\n" + "\n".join(rows) + "\n")
    if sidecar is not None:
        (tmp_path / "bad.json").write_text(sidecar)
    return path


def _rows(i, text):
    rows = list(GOOD_ROWS)
    rows[i] = text
    return rows


@pytest.mark.parametrize(
    "rows, pattern",
    [
        (_rows(1, "0.1,nan,1e-9"), r"line 4: column 'stage_accel_m_s2' is nan"),
        (_rows(2, "0.2,1,abc"), r"line 5: column 'slip_m' holds 'abc', not a number"),
        (_rows(2, "0.2,1"), r"line 5: 2 fields, the header has 3"),
        (_rows(2, "0.1,1,2e-9"), r"line 5: time_s = 0.1 does not increase"),
        (_rows(3, "0.15,1,2e-9"), r"line 6: time_s = 0.15 does not increase"),
        (_rows(0, "-0.1,0,0"), r"line 3: time_s = -0.1 must be >= 0"),
        (["0,0,0"], r"at least 2 data rows, got 1"),
        ([], r"no data rows"),
        (_rows(1, "0.1,inf,1e-9"), r"line 4: column 'stage_accel_m_s2' is inf"),
        # issue 33 item 6: a sample scaled by 1e300 (LAPACK lines and "SVD did not converge"
        # before) is refused with file, line, column and the plausible range
        (_rows(2, "0.2,1,1e300"), r"line 5: slip_m = 1e\+300 m is outside the plausible range"),
        (_rows(1, "0.1,2e5,1e-9"), r"line 4: stage_accel_m_s2 = 200000 m/s² is outside"),
    ],
)
def test_malformed_slip_csv_is_refused_with_file_and_line(tmp_path, rows, pattern):
    path = _slip_file(tmp_path, rows)
    before = path.read_bytes()
    with pytest.raises(tj.DataFileError, match=re.escape(str(path)) + ".*" + pattern):
        tj.read_slip_run(path)
    assert path.read_bytes() == before


@pytest.mark.parametrize(
    "sidecar, pattern",
    [
        (None, r"bad.json: sidecar not found; bad.csv needs .*\"mass_kg\""),
        ('{"mass_kg": 0.321,}', r"bad.json, line 1: not valid JSON"),
        ('{\n "mass_kg": -1\n}', r"bad.json, line 2: 'mass_kg' = -1 kg is outside .*\(0, inf\)"),
        ('{"mass_kg": 0}', r"'mass_kg' = 0 kg is outside"),
        ('{"mass_kg": "0.3"}', r"'mass_kg' must be a number \(kg\), got '0.3'"),
        ('{"mass_kg": true}', r"'mass_kg' must be a number"),
        ('{"mass_kg": null}', r"'mass_kg' must be a number"),
        ('{"normal_load_N": 3}', r"bad.json: 'mass_kg' is required \(kg\)"),
        ('{"mass_kg": 1,\n"mass_Kg": 2}', r"line 2: unknown key 'mass_Kg'; allowed keys"),
        ('{"mass_kg": 1, "normal_load_N": -3}', r"'normal_load_N' = -3 N is outside"),
        ('{"mass_kg": 1, "noise_std_m": NaN}', r"'noise_std_m' = nan m is outside"),
        ("[0.321]", r"line 1: must be a JSON object"),
    ],
)
def test_bad_sidecar_is_refused(tmp_path, sidecar, pattern):
    path = _slip_file(tmp_path, sidecar=sidecar)
    with pytest.raises(tj.DataFileError, match=pattern):
        tj.read_slip_run(path)


def test_sidecar_comment_is_allowed(tmp_path):
    path = _slip_file(tmp_path, sidecar='{"mass_kg": 0.321, "comment": "rig 2, 4 kPa"}')
    assert tj.read_slip_run(path).mass == 0.321


def test_slip_run_validation():
    t = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match=r"slip\[2\] is nan"):
        tj.SlipRun(t, t, np.where(t == 0.5, np.nan, t), mass=1)
    with pytest.raises(ValueError, match="same length"):
        tj.SlipRun(t, t, t[:3], mass=1)
    with pytest.raises(ValueError, match=r"not strictly increasing at sample 3"):
        tj.SlipRun([0, 1, 2, 2, 3], t, t, mass=1)
    with pytest.raises(ValueError, match=r"t\[0\] = -1 s must be >= 0"):
        tj.SlipRun(t - 1, t, t, mass=1)
    with pytest.raises(ValueError, match=r"mass = -1 kg is outside the allowed range \(0, inf\)"):
        tj.SlipRun(t, t, t, mass=-1)
    with pytest.raises(ValueError, match=r"noise_std = 0 m is outside"):
        tj.SlipRun(t, t, t, mass=1, noise_std=0.0)
    with pytest.raises(ValueError, match="at least 2 samples"):
        tj.SlipRun([0.0], [0.0], [0.0], mass=1)
    run = tj.SlipRun(t, t, t, mass=1)
    with pytest.raises(ValueError, match="read-only"):
        run.slip[0] = 1.0  # records are immutable
    with pytest.raises(ValueError, match=r"noise = -1 m is outside"):
        tj.synthetic_slip_run(ELEMENT, noise=-1.0)


def _loop(noise=0.005 * MU * N, seed=7):
    return tj.synthetic_loop(
        tj.Mindlin(MU, N, KD), 3 * MU * N / KD, OMEGA, noise=noise, seed=seed, normal_load=N
    )


def test_loop_file_round_trip_new_and_legacy(tmp_path):
    loop = _loop()
    assert loop.frequency == pytest.approx(22.0, rel=1e-12) and loop.noise_std == 0.005 * MU * N
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path, comment="Mindlin, seed 7")
    assert path.read_text().splitlines()[1] == "time_s,displacement_m,force_N"
    assert json.loads((tmp_path / "loop.json").read_text()) == {
        "normal_load_N": N,
        "frequency_Hz": loop.frequency,
        "noise_std_N": loop.noise_std,
    }
    for back in (tj.read_loop(path), tj.read_record(path)):
        assert isinstance(back, tj.HysteresisLoop)
        np.testing.assert_array_equal(back.f, loop.f)
        assert (back.normal_load, back.frequency, back.noise_std) == (
            N,
            loop.frequency,
            loop.noise_std,
        )
    with pytest.raises(FileExistsError, match="refusing to overwrite"):
        tj.write_loop(loop, path)
    legacy = tmp_path / "legacy.csv"
    tj.write_loop(loop, legacy, legacy=True)
    assert not (tmp_path / "legacy.json").exists()
    back = tj.read_record(legacy)
    assert back.normal_load is None and back.frequency is None
    np.testing.assert_array_equal(back.u, loop.u)
    # fit_loop takes the noise from the record: chi² per point ≈ 1 without passing sigma
    fit = tj.fit_loop(tj.read_loop(path), "mindlin", model="steady")
    assert fit.converged
    assert np.mean(fit.residuals**2) == pytest.approx(1.0, abs=0.15)


def test_implausible_loop_samples_name_file_line_and_column(tmp_path):
    loop = _loop()
    path = tmp_path / "big.csv"
    tj.write_loop(loop, path)
    lines = path.read_text().splitlines()
    t, u, f = lines[5].split(",")
    lines[5] = f"{t},{float(u) * 1e300 or 1e300},{f}"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(
        tj.DataFileError,
        match=r"big.csv, line 6: displacement_m = .* m is "
        r"outside the plausible range \[-1000, 1000\] m",
    ):
        tj.read_record(path)
    with pytest.raises(ValueError, match=r"f\[2\] = 1e\+12 N is outside the plausible range"):
        tj.HysteresisLoop(loop.t[:4], loop.u[:4], np.array([0.0, 1.0, 1e12, 0.0]))


def test_bad_loop_sidecars(tmp_path):
    loop = _loop()
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path)
    side = tmp_path / "loop.json"
    side.unlink()
    with pytest.raises(tj.DataFileError, match=r"loop.json: sidecar not found.*normal_load_N"):
        tj.read_loop(path)
    side.write_text('{"normal_load_N": 2.94}')
    with pytest.raises(tj.DataFileError, match=r"'frequency_Hz' is required \(Hz\)"):
        tj.read_loop(path)
    side.write_text(json.dumps({"normal_load_N": 2.94, "frequency_Hz": 2 * np.pi * 22}))
    with pytest.raises(
        tj.DataFileError, match=r"frequency_Hz = 138.23 disagrees with the record.s 22 Hz"
    ):
        tj.read_loop(path)
    side.write_text('{"normal_load_N": 2.94, "frequency_Hz": 22, "noise_std_N": -1}')
    with pytest.raises(tj.DataFileError, match=r"loop.json, line 1: 'noise_std_N' = -1 N"):
        tj.read_loop(path)
    with pytest.raises(ValueError, match="normal_load = -2 N is outside"):
        tj.HysteresisLoop(loop.t, loop.u, loop.f, normal_load=-2.0)


def test_read_record_refuses_unknown_headers(tmp_path):
    path = tmp_path / "x.csv"
    path.write_text("# c\ntime_s,position_m\n0,1\n")
    with pytest.raises(tj.DataFileError, match=r"x.csv, line 2: header .* is neither a slip run"):
        tj.read_record(path)
    with pytest.raises(tj.DataFileError, match=r"x.csv: cannot be read"):
        tj.read_record(tmp_path / "missing" / "x.csv")


# --- one record family (issue 29): an abstract record, the kinds its final subclasses -----------

RECORD_KINDS = {
    tj.SlipRun: ("slip_run", "a slip run"),
    tj.HysteresisLoop: ("loop", "a hysteresis loop"),
    tj.FrictionCurve: ("friction_curve", "a friction curve"),
    tj.FrictionTransient: ("friction_transient", "a friction transient"),
}


def _subclasses(cls):
    return {s for c in cls.__subclasses__() for s in {c} | _subclasses(c)}


def test_records_are_final_kinds_of_one_abstract_record():
    # every record class is a direct, concrete subclass of AbstractRecord with its declared kind;
    # nothing else subclasses the base, and nothing subclasses a concrete record
    assert _subclasses(tj.AbstractRecord) == set(RECORD_KINDS)
    for cls, (kind, description) in RECORD_KINDS.items():
        assert cls.__bases__ == (tj.AbstractRecord,)
        assert (cls.kind, cls.description) == (kind, description)
        assert cls.__final__ is True  # typing.final, for type checkers
        with pytest.raises(TypeError, match=f"{cls.__name__} is a final record class"):
            type("Sub", (cls,), {})
    assert len({cls.kind for cls in RECORD_KINDS}) == len(RECORD_KINDS)
    with pytest.raises(TypeError, match="abstract"):
        tj.AbstractRecord()


def test_every_record_answers_the_record_interface(run):
    loop = _loop()
    curve = tj.FrictionCurve([-1.0, 1.0], [-0.2, 0.2], [0.01, 0.01], [0.0, 0.0], [10, 10])
    transient = tj.FrictionTransient([0.0, 1.0, 2.0], [0.0, 1.0, 0.0], [0.0, 0.2, 0.0])
    assert [len(r) for r in (run, loop, curve, transient)] == [461, len(loop.t), 2, 3]
    # the drive/response series of the reducible kinds, and a resampled copy of the same kind
    for record, channels, unit in (
        (run, ("t", "accel", "slip"), "m"),
        (loop, ("t", "u", "f"), "N"),
    ):
        assert record.reducible and record.response_unit == unit
        for x, name in zip(record.series(), channels):
            assert x is getattr(record, name)
        t, d, r = (x[::2] for x in record.series())
        half = record.resampled(t, d, r, noise_std=1e-3)
        assert type(half) is type(record) and half.noise_std == 1e-3 and len(half) == len(t)
        assert half.source == record.source
    assert run.resampled(*run.series(), noise_std=None).drive is not None  # the full drive kept
    # whole cycles: the upward mean-crossings of a periodic loop's displacement, every 1/22 s
    assert len(loop.cycle_times()) >= 2 and run.cycle_times() is None
    np.testing.assert_allclose(np.diff(loop.cycle_times()), 2 * np.pi / OMEGA, rtol=1e-3)
    history = tj.HysteresisLoop(loop.t, loop.u, loop.f, periodic=False)
    assert history.cycle_times() is None
    for record in (curve, transient):
        assert not record.reducible
        with pytest.raises(ValueError, match=f"{record.description} is not a drive/response"):
            record.series()
        with pytest.raises(ValueError, match="must be a SlipRun or a HysteresisLoop"):
            tj.decimate_record(record)
