"""`tribojax batch` and `tribojax.batch` (issue 70): the single command on many records over a
Dask cluster, on the loopback address only.

What is checked: every good record's outputs are the single command's (the same files, the
same numbers to the last bit); a corrupt record is a row naming its file and line while the
others go on; exit 0/1/2; a rerun runs nothing that is complete; `--force` runs again; stems made
unique; the Python entry with a user's client and the command's options by name; and (slow) a
worker killed mid-run on a cluster started with the `dask` command.
"""

import csv
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import jax
import pytest

import tribojax as tj

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
LOOP = ROOT / "data" / "real" / "brfd" / "2Hz30lbtension0.5amplitude.csv"


def _copy_loop(folder: Path, stem: str = "loop") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(LOOP, folder / f"{stem}.csv")
    shutil.copy(LOOP.with_suffix(".json"), folder / f"{stem}.json")
    return folder / f"{stem}.csv"


def _corrupt(folder: Path) -> Path:
    bad = folder / "bad.csv"
    bad.write_text("time_s,displacement_m,force_N\n0,0.001,2\n0.1,oops,3\n")
    shutil.copy(LOOP.with_suffix(".json"), bad.with_suffix(".json"))
    return bad


def _tribojax(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "tribojax", *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


def _table(out: Path) -> dict:
    with open(out / "batch.csv", newline="") as fh:
        return {
            Path(r["record"]).parent.name + "/" + Path(r["record"]).name: r
            for r in csv.DictReader(fh)
        }


@pytest.fixture(scope="module")
def single(tmp_path_factory):
    """The single command's fit.json of the bundled loop."""
    where = tmp_path_factory.mktemp("single")
    done = _tribojax("fit", LOOP, "--out", where / "fit", "--quiet", cwd=where)
    assert done.returncode == 0, done.stderr
    return json.loads((where / "fit" / "fit.json").read_text())


def test_the_command_on_a_folder_and_its_rerun(tmp_path, single):
    records = tmp_path / "records"
    _copy_loop(records / "rig_a")
    _copy_loop(records / "rig_b")  # the same stem in another folder
    _corrupt(records)
    out = tmp_path / "out"
    run = _tribojax("batch", "fit", records, "--out", out, "--workers", "2", cwd=tmp_path)
    assert run.returncode == 1, run.stderr  # one record failed
    rows = _table(out)
    assert sorted(rows) == ["records/bad.csv", "rig_a/loop.csv", "rig_b/loop.csv"]
    bad = rows["records/bad.csv"]
    assert bad["status"] == "error" and "bad.csv, line 3" in bad["message"], bad
    assert bad["message"] in run.stdout
    for name in ("rig_a", "rig_b"):
        row = rows[f"{name}/loop.csv"]
        assert row["status"] == "ok" and row["reused"] == "False", row
        folder = out / f"{name}__loop"
        assert sorted(p.name for p in folder.iterdir()) == ["fit.json", "fit.png"]
        fit = json.loads((folder / "fit.json").read_text())
        assert fit["parameters"] == single["parameters"]  # to the last bit
        assert fit["std_errors"] == single["std_errors"] and fit["nrmse"] == single["nrmse"]
        assert float(row["mu_N"]) == single["parameters"]["mu_N"]
        assert float(row["nrmse"]) == single["nrmse"]
    assert not (out / ".batch" / "tmp").exists()
    summary = json.loads((out / "batch.json").read_text())
    assert (summary["records"], summary["ok"], summary["error"]) == (3, 2, 1)

    stamp = (out / "rig_a__loop" / "fit.json").stat().st_mtime_ns
    t0 = time.perf_counter()
    again = _tribojax("batch", "fit", records, "--out", out, cwd=tmp_path)
    assert again.returncode == 1 and "3 not run again" in again.stdout, again.stdout
    assert time.perf_counter() - t0 < 20
    assert {r["reused"] for r in _table(out).values()} == {"True"}
    assert (out / "rig_a__loop" / "fit.json").stat().st_mtime_ns == stamp

    _corrupt(records).unlink()  # the bad record gone: the others still complete
    (records / "bad.json").unlink()
    forced = _tribojax(
        "batch", "fit", records / "rig_a", "--out", out, "--force", "--workers", "1", cwd=tmp_path
    )
    assert forced.returncode == 0, forced.stderr
    row = _table(out)["rig_a/loop.csv"]
    assert row["reused"] == "False" and float(row["mu_N"]) == single["parameters"]["mu_N"]


@pytest.mark.parametrize(
    "argv, said",
    [
        (["fit", "missing.csv", "--out", "o"], "missing.csv: no such file or folder"),
        (["fit", "*.nothing", "--out", "o"], "the pattern matches no file"),
        (["fit", "x.csv", "--out", "o", "--workers", "0"], "--workers = '0' is outside"),
        (["predict", "x.csv", "--out", "o"], "--model"),
        (["fit", "x.csv"], "--out"),
    ],
)
def test_usage_errors_run_nothing(tmp_path, argv, said):
    done = _tribojax("batch", *argv, cwd=tmp_path)
    assert done.returncode == 2 and said in done.stderr, done.stderr
    assert not (tmp_path / "o" / "batch.csv").exists()


def test_the_python_entry_on_a_users_client(tmp_path, single, monkeypatch):
    rec = _copy_loop(tmp_path / "records", "sine")
    environ, x64 = dict(os.environ), jax.config.jax_enable_x64
    with pytest.raises(ValueError, match="nothing.csv: no such file"):
        tj.batch([tmp_path / "nothing.csv"], "fit", out=tmp_path / "o")
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, host="127.0.0.1", dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        environ = dict(os.environ)  # as the user's own cluster left it (Dask's nanny sets some)
        rows = tj.batch(
            [str(tmp_path / "records" / "*.csv")],
            "fit",
            out=tmp_path / "o",
            client=client,
            max_steps=200,
        )
        assert client.status == "running"  # the user's client is left open
        model = tmp_path / "o" / "sine" / "fit.json"  # relative to the caller: made absolute
        monkeypatch.chdir(tmp_path)
        (pred,) = tj.batch(
            [rec], "predict", out="p", client=client, model=model.relative_to(tmp_path)
        )
    assert pred["status"] == "ok", pred
    # the workers made the command's settings in their processes, not in this one
    assert dict(os.environ) == environ and jax.config.jax_enable_x64 == x64
    # the record predicted by the model fitted to it: the fit's own NRMSE
    assert pred["figures"]["nrmse"] == pytest.approx(single["nrmse"], rel=1e-9)
    assert (tmp_path / "p" / "sine" / "prediction.json").is_file()
    (row,) = rows
    assert row["record"] == str(rec) and row["status"] == "ok" and not row["reused"]
    assert row["figures"]["mu_N"] == single["parameters"]["mu_N"]
    saved = json.loads((tmp_path / "o" / "sine" / "fit.json").read_text())
    assert saved["parameters"] == single["parameters"]
    with pytest.raises(ValueError, match="fit has no option 'alhpa'"):
        tj.batch([rec], "fit", out=tmp_path / "o", alhpa="free")
    with pytest.raises(ValueError, match=r"values \['b'\] belong to no option"):
        tj.batch([rec], "fit", out=tmp_path / "o", alpha=["a", "b"])
    with pytest.raises(ValueError, match="command = 'fits' is not one of"):
        tj.batch([rec], "fits", out=tmp_path / "o")


def test_records_and_their_names(tmp_path):
    from tribojax._batch._records import expand_records, unique_stems

    epos = tmp_path / "curve" / "0.1kg"
    epos.mkdir(parents=True)
    for speed in (10, 20):
        (epos / f"{speed}.csv").write_text("Recorded samples:;2\nms;rpm;%\n0;1;2\n1;1;2\n")
    a = _copy_loop(tmp_path / "a", "x")
    b = _copy_loop(tmp_path / "b", "x")
    (tmp_path / "a" / "fit.json").write_text("{}")  # a command's output: not a record
    found = expand_records([tmp_path])
    assert found == [a, b, epos]  # sidecars and outputs left out, the EPOS folder one record
    assert unique_stems(found) == ["a__x", "b__x", "0.1kg"]
    assert expand_records([tmp_path], out=tmp_path / "a") == [b, epos]
    assert expand_records([a, str(tmp_path / "*" / "x.csv")]) == [a, b]


@pytest.mark.slow
def test_a_worker_killed_mid_run(tmp_path, single):
    """A scheduler and two workers started with the `dask` command; one worker is killed while
    both run a record (benchmarks/batch.py's scenario): every good record still gets the single
    command's answer, the corrupt one is a row naming its file and line, the rerun runs
    nothing."""
    from benchmarks.batch import killed_worker_run

    files = [_copy_loop(tmp_path / "records", f"loop{i}") for i in range(4)]
    corrupt = _corrupt(tmp_path / "records")
    serial = {str(f): single["parameters"] for f in files}
    got = killed_worker_run(files, corrupt, tmp_path, serial)
    assert (got["exit_status"], got["ok"], got["error"]) == (1, 4, 1), got
    assert got["good_records_same_parameters_as_single_command"], got
    assert "bad.csv, line 3" in got["corrupt_row_message"]
    assert got["rerun_ran_nothing"] and got["rerun_s"] < 20


def test_the_python_entry_leaves_the_callers_process_alone(tmp_path):
    """`tj.batch` on its own local cluster: Dask's nannies set OMP_NUM_THREADS and others in the
    process that spawns them; the caller's environment and JAX settings are as before."""
    rec = _copy_loop(tmp_path, "sine")
    code = (
        "import os, sys, jax, tribojax as tj\n"
        "before, flags = dict(os.environ), jax.config.jax_enable_x64\n"
        f"(row,) = tj.batch([{str(rec)!r}], 'fit', out={str(tmp_path / 'o')!r}, workers=1)\n"
        "assert row['status'] == 'ok', row\n"
        "keys = set(before) | set(os.environ)\n"
        "changed = {k for k in keys if before.get(k) != os.environ.get(k)}\n"
        "print(sorted(changed), jax.config.jax_enable_x64 == flags)\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "OMP_NUM_THREADS")}
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "[] True"


def test_without_dask_the_command_says_what_to_install(tmp_path, monkeypatch, capsys):
    # the core install does not bring Dask: `batch` says which extra does (exit 2)
    from tribojax._cli import main

    rec = _copy_loop(tmp_path, "sine")
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed → ImportError
    assert main(["batch", "fit", str(rec), "--out", str(tmp_path / "o")]) == 2
    assert "pip install 'tribojax[distributed]'" in capsys.readouterr().err
    assert not (tmp_path / "o" / "sine").exists()
