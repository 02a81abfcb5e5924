"""Readers of the measured rig data (issue 15): units, round trips, format detection, bad files."""

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

import tribojax as tj

REPO = Path(__file__).resolve().parents[1]
REAL = REPO / "data" / "real"
SHARED = REPO.parent / "shared" / "data" / "real"
needs_shared = pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/data/real is absent")

EPOS_HEAD = "Date:;2020-07-08 21:24:28\nRecorded samples:;4\nSampling period:;51.200\n"
EPOS_COLS = ";Velocity actual value averaged;Torque actual value averaged\nms;rpm;%\n"


def _brfd(tmp_path, rows, name="1Hz30lbtension1amplitude.json", **extra):
    path = tmp_path / name
    obj = {
        "data": rows,
        "dt": 1 / 1024,
        "displacement units": "in",
        "friction force units": "kip",
        **extra,
    }
    path.write_text(json.dumps(obj).replace("], [", "],\n["))
    return path


def test_brfd_units_and_kind(tmp_path):
    t = np.arange(3000) / 1024
    u_in = 0.5 * np.sin(2 * np.pi * t)
    rows = [[a, b, 2.0 * b, 0.0, 1.0, 1.0] for a, b in zip(t, u_in)]
    loop = tj.read_brfd(_brfd(tmp_path, rows))
    np.testing.assert_allclose(loop.u, u_in * 0.0254, rtol=1e-15)
    np.testing.assert_allclose(loop.f, 2.0 * u_in * 4448.2216152605, rtol=1e-15)
    assert loop.periodic and loop.frequency == 1.0 and loop.normal_load is None
    hist = tj.read_brfd(_brfd(tmp_path, rows[:40], name="earthquake_X.json"))
    assert not hist.periodic and hist.frequency is None
    assert tj.detect_format(tmp_path / "earthquake_X.json") == "brfd"


@pytest.mark.parametrize(
    "text, match",
    [
        ('{"data": [[0, 0, 0, 0, 0, 0],\n[0.001, 0, 0', r"line 2: not valid JSON.*truncated"),
        (
            '{"data": [[0, 0, 0, 0, 0, 0],\n[0.001, 0, 0, 0, 0],\n[0.002, 0, 0, 0, 0, 0]]}',
            r"line 2: data row 1 is .*expected 6 finite numbers",
        ),
        (
            '{"data": [[0, 0, 0, 0, 0, 0],\n[0.001, 0, 0, 0, 0, 0],\n[0.001, 0, 0, 0, 0, 0]]}',
            r"line 3: time 0.001 s of data row 2 does not increase",
        ),
        ('{"data": [[0, 0, 0, 0, 0, 0]], "displacement units": "mm"}', r"line 1: .*'mm'"),
    ],
)
def test_brfd_bad_files_name_file_and_line(tmp_path, text, match):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(tj.DataFileError, match=r"bad.json, " + match):
        tj.read_brfd(path)


def _epos(folder, name, rows, announced=None):
    folder.mkdir(exist_ok=True)
    path = folder / name
    body = "\n".join(f"{i * 51.2:.3f};{v};{q}" for i, (v, q) in enumerate(rows))
    head = EPOS_HEAD.replace(";4", f";{len(rows) if announced is None else announced}")
    path.write_text(head + EPOS_COLS + body + "\n")
    return path


def test_epos_folder_refuses_what_is_not_one_steady_point(tmp_path):
    # issue 33: a start-stop export dropped into a steady folder was taken as a point (the fit
    # collapsed), an export cut short was accepted silently, a Windows copy counted twice
    folder = tmp_path / "0.1kg"
    _epos(folder, "10.csv", [(-10, -30.0), (-10, -32.0), (-11, -31.0)])
    _epos(folder, "n10.csv", [(10, 35.0), (10, 36.0), (9, 37.0)])
    assert len(tj.read_record(folder)) == 2
    stray = _epos(folder, "start_stop.csv", [(0, 1.0), (50, 30.0), (-50, -30.0), (0, 1.0)])
    with pytest.raises(tj.DataFileError, match=r"start_stop.csv: not a steady point"):
        tj.read_record(folder)
    stray.unlink()
    cut = _epos(folder, "20.csv", [(-20, -40.0), (-20, -41.0)], announced=500)
    with pytest.raises(
        tj.DataFileError,
        match=r"20.csv, line \d+: 2 samples, but the header "
        "announces 500",
    ):
        tj.read_record(folder)
    cut.unlink()
    copy = folder / "10 (1).csv"
    copy.write_bytes((folder / "10.csv").read_bytes())
    with pytest.raises(tj.DataFileError, match=r"10.csv: the same samples as 10 \(1\).csv"):
        tj.read_record(folder)


@needs_shared
def test_the_rig_steady_folders_pass_the_steady_point_check():
    for drive in ("driveNo1", "driveNo2"):
        curve = tj.read_record(SHARED / "screwdrive" / drive / "steady_state" / "0.096kg")
        assert len(curve) == 32 if drive == "driveNo1" else len(curve) == 30


def test_epos_folder_is_one_curve_in_si(tmp_path):
    folder = tmp_path / "0.1kg"
    _epos(folder, "10.csv", [(-10, -30.0), (-10, -32.0), (-11, -31.0)])  # sign from the data
    _epos(folder, "n10.csv", [(10, 35.0), (10, 36.0), (9, 37.0)])
    curve = tj.read_record(folder)
    assert isinstance(curve, tj.FrictionCurve) and tj.detect_format(folder) == "epos_steady"
    w = 2 * np.pi / 60
    np.testing.assert_allclose(curve.velocity, [-31 / 3 * w, 29 / 3 * w])
    np.testing.assert_allclose(curve.friction, [-31e-2 * 9.84e-3, 36e-2 * 9.84e-3])
    np.testing.assert_allclose(curve.friction_scatter, [1e-2 * 9.84e-3] * 2)
    assert curve.units == {"velocity_unit": "rad/s", "friction_unit": "N m"}
    # round trip through the CSV + sidecar, and no overwrite
    tj.write_friction_curve(curve, tmp_path / "c.csv", provenance={"licence": "MIT"})
    back = tj.read_record(tmp_path / "c.csv")
    np.testing.assert_allclose(back.friction, curve.friction, rtol=1e-11)
    assert back.units == curve.units
    with pytest.raises(FileExistsError):
        tj.write_friction_curve(curve, tmp_path / "c.csv")


@pytest.mark.parametrize(
    "body, match",
    [
        (EPOS_COLS + "0.000;1;2.0\n51.200;1;2", None),  # a short last line is still 3 numbers
        (EPOS_COLS + "0.000;1;2.0\n51.200;1\n", r"line 7: '51.200;1' is not three numbers"),
        (EPOS_COLS + "0.000;1;2.0\n0.000;1;2.5\n", r"line 7: time does not increase"),
        (
            ";a;b\nms;rad;%\n0;1;2\n",
            r"line 6: a sample before the units line ms;rpm;%; line 5 "
            r"should be it but reads 'ms;rad;%'",
        ),
        (";a;b\nms;rpm\n", r"line 5: no units line ms;rpm;%"),
    ],
)
def test_epos_bad_files_name_file_and_line(tmp_path, body, match):
    path = tmp_path / "e.csv"
    path.write_text(EPOS_HEAD + body)
    assert tj.detect_format(path) == "epos"
    if match is None:
        assert len(tj.read_record(path).t) == 2
        return
    with pytest.raises(tj.DataFileError, match=r"e.csv, " + match):
        tj.read_record(path)


def test_history_loop_round_trip(tmp_path):
    t = np.linspace(0.0, 1.0, 50)
    loop = tj.HysteresisLoop(t, 1e-3 * t**2, 5.0 * t, periodic=False)  # no whole cycle
    tj.write_loop(loop, tmp_path / "h.csv")
    back = tj.read_loop(tmp_path / "h.csv")
    assert not back.periodic and back.frequency is None
    np.testing.assert_array_equal(back.u, loop.u)
    (tmp_path / "h.json").write_text('{"drive": "sine"}')
    with pytest.raises(tj.DataFileError, match=r"h.json, line 1: 'drive' = 'sine' is not one"):
        tj.read_loop(tmp_path / "h.csv")


def test_converted_copies_load_and_match_manifest():
    manifest = json.loads((REAL / "MANIFEST.json").read_text())
    for entry in manifest["files"]:
        path = REAL / entry["file"]
        assert hashlib.sha256(path.read_bytes()).hexdigest() == entry["sha256"], entry["file"]
        rec = tj.read_record(path)
        assert "licence" in entry and entry["original_sha256"]
        if entry["file"].startswith("brfd/"):
            assert "CC BY-SA 4.0" in entry["licence"] and isinstance(rec, tj.HysteresisLoop)
    curve = tj.read_record(REAL / "screwdrive" / "driveNo1_steady_0.096kg.csv")
    # both directions, friction with the sign of the velocity, about 25-40 % of 9.84 mN m
    assert np.all(np.sign(curve.friction) == np.sign(curve.velocity))
    assert np.all((np.abs(curve.friction) > 2e-3) & (np.abs(curve.friction) < 4.5e-3))


@needs_shared
def test_manifest_hashes_are_the_originals():
    manifest = json.loads((REAL / "MANIFEST.json").read_text())
    for entry in manifest["files"]:
        digests = entry["original_sha256"]
        if isinstance(digests, str):
            digests = {"": digests}
        for name, digest in digests.items():
            path = SHARED / entry["original"] / name if name else SHARED / entry["original"]
            assert hashlib.sha256(path.read_bytes()).hexdigest() == digest


@needs_shared
def test_converted_brfd_equals_reader_output():
    name = "2Hz30lbtension0.5amplitude"
    fresh = tj.read_record(SHARED / "brfd" / f"{name}.json")
    copy = tj.read_record(REAL / "brfd" / f"{name}.csv")
    np.testing.assert_allclose(copy.f, fresh.f, rtol=1e-15)
    assert copy.frequency == fresh.frequency == 2.0 and copy.periodic


def test_effective_samples_of_a_correlated_series():
    """The batch-means error of a mean, on AR(1) series made here (seed 11): it matches the
    scatter of the means over 400 independent series, where scatter/√n is 3.9× too small."""
    rng = np.random.default_rng(11)
    rho, n, reps = 0.88, 500, 400
    e = rng.normal(size=(reps, n))
    x = np.empty_like(e)
    x[:, 0] = e[:, 0] / np.sqrt(1 - rho**2)
    for k in range(1, n):
        x[:, k] = rho * x[:, k - 1] + e[:, k]
    true_var = np.var(x.mean(axis=1), ddof=1)
    n_eff = np.array([tj.effective_samples(xi) for xi in x])
    est_var = np.mean(x.var(axis=1, ddof=1) / n_eff)
    assert 0.7 < est_var / true_var < 1.15
    naive = np.mean(x.var(axis=1, ddof=1) / n)
    assert true_var / naive > 8  # (1 + rho) / (1 - rho) = 15.7 for the infinite series
    white = np.array([tj.effective_samples(xi) for xi in rng.normal(size=(50, n))])
    assert np.all(white <= n) and np.median(white) > 0.6 * n
    assert tj.effective_samples(np.arange(10.0)) == 10  # too short for batches: the count


def test_epos_resaved_by_a_spreadsheet_is_read_and_edits_are_flagged(tmp_path):
    # trailing empty fields on every line (the units line too), quotes, a note in a spare
    # column, a torque typed with two decimals in a one-decimal column, a time off the grid
    body = [
        "0.000;10;31.0",
        "51.200;10;30.5",
        "102.400;11;31.2",
        "153.600;10;30.9",
        "204.800;10;31.1;checked by hand",
        "256.000;10;30.75",
        "307.100;10;31.0",
        "358.400;10;-31",
    ]
    text = EPOS_HEAD.replace(";4", ";8") + EPOS_COLS + "\n".join(body) + "\n"
    clean = tmp_path / "clean.csv"
    clean.write_text(
        EPOS_HEAD.replace(";4", ";8")
        + EPOS_COLS
        + "\n".join(
            ";".join(line.split(";")[:3]).replace("307.100", "307.200").replace("30.75", "30.7")
            for line in body
        )
        + "\n"
    )
    resaved = tmp_path / "resaved.csv"
    resaved.write_text(
        "\n".join(
            ";".join(f'"{f}"' if f.endswith(":") else f for f in line.split(";")) + ";;,,"
            for line in text.splitlines()
        )
        + "\n"
    )
    assert tj.detect_format(resaved) == "epos"
    with pytest.warns(tj.DataFileWarning) as caught:
        got = tj.read_record(resaved)
    message = str(caught[0].message)
    assert "resaved.csv: 3 line(s) look edited" in message
    assert "line 10: extra field 'checked by hand' ignored" in message
    assert "line 11: % value '30.75' has 2 decimals, the column 1" in message
    assert "line 12: time 307.100 ms is off the 51.2 ms sampling grid" in message
    assert "line 13" not in message  # '-31' is -31.0 with its trailing zeros dropped
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the clean export reads without a warning
        ref = tj.read_record(clean)
    keep = np.arange(8) != 5
    np.testing.assert_allclose(got.friction[keep], ref.friction[keep], rtol=0)
    assert got.friction[5] == pytest.approx(0.3075 * 9.84e-3, rel=1e-12)
    np.testing.assert_allclose(got.velocity, ref.velocity, rtol=0)
    assert got.t[6] == pytest.approx(0.3071) and ref.t[6] == pytest.approx(0.3072)


@needs_shared
def test_scored_windows_reproduce_the_authors_lugre_figures():
    # fitting/real_data.py scores the earthquake predictions on the dataset authors' windows;
    # their stored LuGre predictions give their published NRMSE there (brfd_reference/README.md)
    from fitting import real_data as rd

    quakes = {n: tj.read_brfd(SHARED / "brfd" / f"{n}.json") for n in rd.SCORING_WINDOWS}
    got = rd._authors_lugre(SHARED, quakes)
    assert got == {
        "earthquake_ImperialValleyDBE_30lb": pytest.approx(0.440, abs=5e-4),
        "earthquake_KocaeliDBE_30lb": pytest.approx(0.794, abs=5e-4),
    }
    name = "earthquake_KocaeliDBE_30lb"
    rec = quakes[name]
    f = rec.f[:: rd.DECIMATE]
    assert rd._window_nrmse(rec, f, name) == 0.0
    a, b = rd.SCORING_WINDOWS[name]
    mean = np.full_like(f, rec.f[a:b:2].mean())
    assert rd._window_nrmse(rec, mean, name) == pytest.approx(1.0, rel=1e-12)
