"""Property-based tests (hypothesis) of the record readers and the command line.

Random valid files round-trip exactly; random corruptions of a valid record give a clean error
naming the file (DataFileError from the API; one `tribojax <cmd>: error:` line and exit 2 from the
CLI), never a traceback and never a partial output. Example counts are small to keep the suite
fast; the generators are plain hypothesis strategies, independent of the readers.
"""

import json
import math
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import tribojax as tj  # noqa: E402
from tribojax._cli._main import main  # noqa: E402
from tribojax._io._records import read_record  # noqa: E402
from tribojax._limits import SAMPLE_FLOORS  # noqa: E402
from tribojax._predict import _fit_methods as fit_methods  # noqa: E402
from tribojax._tables import read_table  # noqa: E402

FAST = settings(
    max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
finite = st.floats(
    allow_nan=False, allow_infinity=False, width=64, min_value=-1e300, max_value=1e300
)


@st.composite
def slip_runs(draw):
    n = draw(st.integers(2, 40))
    steps = draw(st.lists(st.floats(1e-9, 1e3), min_size=n, max_size=n))
    t = np.cumsum(steps) - steps[0]  # t[0] = 0, strictly increasing
    if np.any(np.diff(t) <= 0):
        t = np.arange(n) * 1e-3
    # any float64 within the plausible ranges (SAMPLE_LIMITS: beyond them a record is refused)
    accel = np.array(draw(st.lists(st.floats(-1e4, 1e4), min_size=n, max_size=n)))
    slip = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n)))
    for x, name in ((accel, "accel"), (slip, "slip")):  # a record, not a unit error (×1e-300)
        if np.max(np.abs(x)) < SAMPLE_FLOORS[name]:
            x[draw(st.integers(0, n - 1))] = SAMPLE_FLOORS[name]
    mass = draw(st.floats(1e-6, 1e6))
    noise = draw(st.none() | st.floats(1e-15, 1.0))
    return tj.SlipRun(t, accel, slip, mass=mass, noise_std=noise)


@pytest.fixture
def folder():
    path = Path(tempfile.mkdtemp(prefix="tj-prop-"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


@FAST
@given(run=slip_runs())
def test_slip_runs_round_trip_exactly(folder, run):
    path = folder / "run.csv"
    tj.write_slip_run(run, path, overwrite=True, comment="hypothesis")
    back = read_record(path)
    for name in ("t", "accel", "slip"):
        np.testing.assert_array_equal(getattr(back, name), getattr(run, name))
    assert back.mass == run.mass and back.noise_std == run.noise_std


@FAST
@given(
    names=st.lists(
        st.text("abcdefghij_", min_size=1, max_size=8), min_size=1, max_size=5, unique=True
    ),
    rows=st.integers(1, 10),
    data=st.data(),
)
def test_tables_round_trip_in_file_order(folder, names, rows, data):
    values = np.array(
        data.draw(st.lists(finite, min_size=rows * len(names), max_size=rows * len(names)))
    ).reshape(rows, len(names))
    path = folder / "t.csv"
    lines = ["# comment", ",".join(names)] + [",".join(f"{v:.17g}" for v in r) for r in values]
    path.write_text("\n".join(lines) + "\n")
    table = read_table(path)
    assert list(table) == names
    for j, name in enumerate(names):
        np.testing.assert_array_equal(table[name], values[:, j])


# --- corruptions --------------------------------------------------------------------------

_JUNK = ["abc", "nan", "inf", "-inf", "", "1e999", "0x10", "1,5", "\t", "é", '"1"']


@st.composite
def corruptions(draw):
    """(kind, parameters) of one corruption of a valid slip-run CSV and sidecar."""
    kind = draw(
        st.sampled_from(
            ["field", "drop", "extra", "bytes", "truncate", "header", "sidecar", "reverse"]
        )
    )
    return kind, draw(st.integers(0, 10**6)), draw(st.sampled_from(_JUNK))


def _corrupt(csv: Path, kind, k, junk):
    lines = csv.read_text().splitlines()
    data = [i for i, ln in enumerate(lines) if ln and not ln.startswith("#")][1:]
    row = data[k % len(data)]
    fields = lines[row].split(",")
    if kind == "field":
        fields[k % 3] = junk
        lines[row] = ",".join(fields)
    elif kind == "drop":
        lines[row] = ",".join(fields[:-1])
    elif kind == "extra":
        lines[row] = ",".join(fields + ["1"])
    elif kind == "header":
        hdr = data[0] - 1
        lines[hdr] = ["time_s,time_s,slip_m", "time_s,stage_accel,slip_m", "a,b", ""][k % 4]
    elif kind == "reverse":
        lines[data[0]], lines[data[-1]] = lines[data[-1]], lines[data[0]]
    text = "\n".join(lines) + "\n"
    raw = text.encode()
    if kind == "bytes":
        at = len(raw) // 2 + k % (len(raw) // 2)
        raw = raw[:at] + bytes([0x80 + k % 0x40]) + raw[at:]
    if kind == "truncate":
        raw = raw[: k % len(raw)]
    csv.write_bytes(raw)
    if kind == "sidecar":
        side = csv.with_suffix(".json")
        side.write_text(
            [
                '{"mass_kg": -1}',
                '{"mass_kg": 0.3, "x": 1}',
                "{",
                "[]",
                '{"mass": 1}',
                '{"mass_kg": "0.3"}',
                '{"mass_kg": null}',
                "",
            ][k % 8]
        )


def _valid_run(folder):
    t = np.linspace(0.0, 0.1, 12)
    run = tj.SlipRun(t, np.sin(40 * t), 1e-9 * t, mass=0.321, noise_std=1e-10)
    path = folder / "run.csv"
    tj.write_slip_run(run, path, overwrite=True)
    return path


@FAST
@given(c=corruptions())
def test_corrupted_records_give_a_clean_error(folder, c):
    path = _valid_run(folder)
    _corrupt(path, *c)
    try:
        read_record(path)
    except tj.DataFileError as err:
        assert "run.csv" in str(err) or "run.json" in str(err), str(err)
    # (a corruption may leave a valid record: e.g. a junk value in a comment-free position
    # that parses, or a truncation at a line end; then reading succeeds)


@FAST
@given(c=corruptions())
def test_cli_on_corrupted_records_exits_cleanly(folder, c):
    path = _valid_run(folder)
    _corrupt(path, *c)
    out = folder / "out"
    reached = []

    def stop(*a, **k):  # a record that is still valid reaches the fit: stop there
        reached.append(True)
        raise KeyboardInterrupt

    with pytest.MonkeyPatch.context() as mp, _Capture() as cap:
        mp.setattr(fit_methods, "fit_slip_run", stop)
        code = main(["fit", str(path), "--out", str(out)])
    err = cap.err
    assert "Traceback" not in err
    if reached:
        assert code == 130 and err.strip() == "tribojax fit: interrupted (Ctrl-C)"
    else:
        assert code == 2, err
        (line,) = err.strip().splitlines()
        assert line.startswith("tribojax fit: error: ") and (
            "run.csv" in line or "run.json" in line
        )
    assert not out.exists()


class _Capture:
    """Capture stderr inside a hypothesis example (pytest's capsys is per test, not example)."""

    def __enter__(self):
        import contextlib
        import io

        self._buf = io.StringIO()
        self._cm = contextlib.redirect_stderr(self._buf)
        self._cm.__enter__()
        return self

    def __exit__(self, *exc):
        self._cm.__exit__(*exc)
        self.err = self._buf.getvalue()
        return False


@FAST
@given(text=st.text(st.characters(codec="utf-8"), max_size=300) | st.binary(max_size=300))
def test_plain_topography_reader_on_random_files(folder, text):
    path = folder / "surf.txt"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    try:
        topo = tj.read_topography(path, instrument=False, dx=1e-6)
    except (tj.DataFileError, ValueError) as err:
        assert "surf.txt" in str(err), str(err)
    else:
        assert np.all(np.isfinite(np.asarray(topo.heights)))


_number = st.sampled_from(["0", "-1", "nan", "inf", "1e-300", "1e300", "2.5", "3", "2", "x"])


@settings(max_examples=25, deadline=None)
@given(
    D=_number | st.floats(2.0, 3.0).map(repr),
    G=_number | st.floats(1e-12, 1e-6).map(repr),
    load=_number | st.floats(0.1, 100.0).map(repr),
)
def test_cli_contact_never_tracebacks(D, G, load):
    """Exit 0 with finite, non-negative contact numbers in the JSON (warnings only on stderr), or
    1 (a solve did not converge) / 2 (bad input, nothing written) with one line on stderr; never
    a traceback, never a success with a NaN or negative physical quantity."""
    with tempfile.TemporaryDirectory() as tmp, _Capture() as cap:
        out = Path(tmp) / "contact.json"
        try:
            code = main(["contact", "--D", D, "--G", G, "--load", load, "--json", str(out)])
        except SystemExit as exit_:  # argparse refuses a value that is not a float
            code = ("argparse", exit_.code)
        result = json.loads(out.read_text()) if out.exists() else None
    args = (D, G, load, code, cap.err)
    if isinstance(code, tuple):
        assert code[1] == 2 and "invalid float value" in cap.err and result is None, args
        return
    assert "Traceback" not in cap.err, args
    lines = cap.err.strip().splitlines()
    if code == 0:
        assert all(ln.startswith("tribojax contact: warning: ") for ln in lines), args
        assert 2 < result["surface"]["D"] < 3 and 0 < result["surface"]["G"] < math.inf, args
        (row,) = result["contact"]
        assert row["converged"] and row["load_N"] == float(load), (args, row)
        for key in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m", "zmax_m"):
            assert isinstance(row[key], float) and 0.0 <= row[key] < math.inf, (args, row)
        share = row["load_share"]
        assert all(0.0 <= s <= 1.0 for s in share) and math.isclose(sum(share), 1.0), (args, row)
    elif code == 1:  # the load balance failed, or the numbers left their physical range: said,
        # and the JSON says which load
        assert lines and all(ln.startswith("tribojax contact: warning: ") for ln in lines), args
        (row,) = result["contact"]
        assert not (row["converged"] and row["in_range"]), (args, row)
        assert any(
            "did not converge" in ln or "outside the physical range" in ln for ln in lines
        ), args
    else:
        assert code == 2, args
        (line,) = lines
        assert line.startswith("tribojax contact: error: ") and result is None, args


@settings(max_examples=12, deadline=None)
@given(
    mu=_number | st.floats(0.01, 1.0).map(repr),
    N=_number | st.floats(0.1, 100.0).map(repr),
    K_d=_number | st.floats(1e3, 1e9).map(repr),
    omega=_number | st.floats(1.0, 1e3).map(repr),
    abar=st.sampled_from([None, ("0.1", "3"), ("3", "0.1"), ("0", "2"), ("1e-300", "1e300")]),
)
def test_cli_hysteresis_never_tracebacks(mu, N, K_d, omega, abar):
    """issue 33: exit 0 with finite K̄ in [0, 1] and C̄ >= 0 for every amplitude, or exit 1/2 with
    one line and nothing written; never a traceback, never a NaN with exit 0."""
    with tempfile.TemporaryDirectory() as tmp, _Capture() as cap:
        out = Path(tmp) / "h"
        argv = [
            "hysteresis",
            "--element",
            "jenkins",
            "--mu",
            mu,
            "--N",
            N,
            "--K-d",
            K_d,
            "--omega",
            omega,
            "--n",
            "3",
            "--out",
            str(out),
        ]
        argv += ["--abar", *abar] if abar else []
        try:
            code = main(argv)
        except SystemExit as exit_:  # argparse refuses a value that is not a float
            code = ("argparse", exit_.code)
        table = None
        if (out / "hysteresis.csv").exists():  # a comment line, the header, the rows
            rows = [
                ln
                for ln in (out / "hysteresis.csv").read_text().splitlines()
                if not ln.startswith("#")
            ][1:]
            table = np.array([[float(v) for v in ln.split(",")] for ln in rows])
    args = (argv, code, cap.err)
    if isinstance(code, tuple):
        assert code[1] == 2 and "invalid float value" in cap.err and table is None, args
        return
    assert "Traceback" not in cap.err, args
    if code == 0:
        assert table is not None and np.all(np.isfinite(table)), args
        K_bar, C_bar = table[:, 4], table[:, 5]
        assert np.all((K_bar >= -1e-9) & (K_bar <= 1 + 1e-9)) and np.all(C_bar >= -1e-12), args
    else:
        assert code == 2 and table is None, args
        (line,) = cap.err.strip().splitlines()
        assert line.startswith("tribojax hysteresis: error: "), args


def test_cli_contact_huge_load_is_not_a_success(tmp_path, capsys):
    # was a known defect (exit 0 with F_s, C_tau and z_max NaN, null in the JSON): now the row
    # is out of range and the exit status 1
    out = tmp_path / "contact.json"
    code = main(["contact", "--D", "2.88", "--G", "4.36e-8", "--load", "1e300", "--json", str(out)])
    (row,) = json.loads(out.read_text())["contact"]
    assert code == 1 and row["in_range"] is False
    assert "outside the physical range" in capsys.readouterr().err


@pytest.mark.parametrize("text", ["INF", "1.0\nnan\n2.0", "0.1 0.2\n-inf 0.3\n"])
def test_plain_topography_reader_refuses_non_finite_values(tmp_path, text):
    """float() reads "inf"/"nan": the reader names the file and line instead of returning them
    (found by the hypothesis test above: the file "INF" gave heights [inf])."""
    path = tmp_path / "surf.txt"
    path.write_text(text)
    with pytest.raises(tj.DataFileError, match=r"surf\.txt, line \d+: .*not a finite number"):
        tj.read_topography(path, instrument=False, dx=1e-6)
    assert path.read_text() == text  # nothing the user gave is overwritten
