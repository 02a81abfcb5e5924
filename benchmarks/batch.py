"""`tribojax batch` against the shell loop of single commands (issue 70), end to end, each
command a fresh process (what a user runs).

    python benchmarks/batch.py [--out DIR] [--records N] [--command fit|discover] [--quick]

Records: the first N slip runs and loops of the discovery study (`benchmarks/discovery_study.py`:
SciPy- and NumPy-made records, written as a user's files). Measured in one run on this machine:

- `serial`: `tribojax fit RECORD --out D` (or `discover`) for each record in turn (a process,
  start-up and compilation per record; the compilation cache warm, as a user's second day);
- `batch_1`, `batch_2`: `tribojax batch fit RECORDS --out D --workers 1|2` (a local cluster,
  start-up and compilation once per worker process);
- `rerun`: the same batch again (every record complete: nothing runs);
- `killed`: a scheduler and two workers started with the `dask` command, one worker killed
  (SIGKILL) while both run a record, plus a corrupt record: the rows, and whether every good
  record's parameters equal the single command's to the last bit; then the rerun's time.

Writes DIR/batch.json (default benchmarks/; under the command's key, the other kept) and prints
it. Records per hour =
records / wall time of the whole command(s).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import platform
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from benchmarks import discovery_study as st  # noqa: E402

TRIBOJAX = [sys.executable, "-m", "tribojax"]


def _run(cmd, **kw) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=False, capture_output=True, text=True, **kw)
    return time.perf_counter() - t0


def _params(folder: Path) -> dict:
    """A record's answer: fit.json's parameters, or discovery.json's verdict, effects, excess."""
    if (folder / "fit.json").exists():
        return json.loads((folder / "fit.json").read_text())["parameters"]
    d = json.loads((folder / "discovery.json").read_text())
    return {k: d[k] for k in ("verdict", "effects", "excess_rmse_before", "excess_rmse_after")}


def _rows(out: Path) -> list[dict]:
    with open(out / "batch.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def records(n: int, folder: Path) -> list[Path]:
    """n study records, slip runs and loops alternating (3 slip runs to a loop)."""
    specs = st.all_specs()
    slips = [s for s in specs if getattr(s, "kind", "slip") == "slip"]
    loops = [s for s in specs if getattr(s, "kind", "slip") == "loop"]
    chosen = [loops[i // 4] if i % 4 == 3 else slips[i - i // 4] for i in range(n)]
    folder.mkdir(parents=True, exist_ok=True)
    return [st.write_record(s, folder) for s in chosen]


def killed_worker_run(files, corrupt: Path, work: Path, serial: dict) -> dict:
    """Batch on a `dask`-command cluster (scheduler + two workers, loopback), one worker killed
    while both run a record; the rows checked against the single command's parameters."""
    sched = work / "scheduler.json"
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    loopback = ["--host", "127.0.0.1", "--no-dashboard", "--scheduler-file", str(sched)]
    scheduler = [sys.executable, "-m", "distributed.cli.dask_scheduler", *loopback]
    procs = [subprocess.Popen(scheduler, **quiet)]
    try:
        while not sched.exists():
            time.sleep(0.2)
        worker = [sys.executable, "-m", "distributed.cli.dask_worker", *loopback]
        worker += ["--nthreads", "1", "--no-nanny"]
        procs += [subprocess.Popen(worker, **quiet) for _ in range(2)]
        out = work / "killed"
        cmd = [*TRIBOJAX, "batch", "fit", *map(str, files), str(corrupt), "--out", str(out)]
        cmd += ["--scheduler-file", str(sched)]
        t0 = time.perf_counter()
        batch = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        while len(list((out / ".batch" / "tmp").glob("*"))) < 2 and batch.poll() is None:
            time.sleep(0.05)
        procs[1].send_signal(signal.SIGKILL)
        batch.communicate()
        wall = time.perf_counter() - t0
        rows = _rows(out)
        same = [
            _params(out / Path(r["record"]).stem) == serial[r["record"]]
            for r in rows
            if r["status"] == "ok"
        ]
        again = _run(cmd)
        reused = all(r["reused"] == "True" for r in _rows(out))
    finally:  # the workers first (without their scheduler they wait to reconnect), then it
        for p in procs[::-1]:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
    bad = next(r for r in rows if r["record"] == str(corrupt))
    return {
        "exit_status": batch.returncode,
        "wall_s": wall,
        "ok": sum(r["status"] == "ok" for r in rows),
        "error": sum(r["status"] == "error" for r in rows),
        "corrupt_row_message": bad["message"],
        "good_records_same_parameters_as_single_command": all(same) and len(same) == len(files),
        "rerun_s": again,
        "rerun_ran_nothing": reused,
    }


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(HERE))
    ap.add_argument("--records", type=int, default=24)
    ap.add_argument("--quick", action="store_true", help="4 records (a smoke run)")
    ap.add_argument(
        "--command",
        choices=("fit", "discover"),
        default="fit",
        help="the command timed (discover: no killed-worker run); results go under its key",
    )
    args = ap.parse_args(argv)
    n = 4 if args.quick else args.records
    command = args.command
    work = Path(args.out) / "batch_work"
    shutil.rmtree(work, ignore_errors=True)
    files = records(n, work / "records")
    corrupt = work / "records" / "corrupt.csv"
    text = files[0].read_text().splitlines()
    corrupt.write_text("\n".join(text[:40] + [text[40].replace(",", ",x", 1)] + text[41:]) + "\n")
    shutil.copy(files[0].with_suffix(".json"), corrupt.with_suffix(".json"))

    _run([*TRIBOJAX, command, str(files[0]), "--out", str(work / "warm")])  # the cache warm
    t0 = time.perf_counter()
    for f in files:
        _run([*TRIBOJAX, command, str(f), "--out", str(work / "serial" / f.stem), "--quiet"])
    timings = {"serial": time.perf_counter() - t0}
    serial = {str(f): _params(work / "serial" / f.stem) for f in files}
    same = {}
    for w in (1, 2):
        out = work / f"batch_{w}"
        cmd = [*TRIBOJAX, "batch", command, *map(str, files), "--out", str(out)]
        cmd += ["--workers", str(w)]
        timings[f"batch_{w}"] = _run(cmd)
        same[f"batch_{w}"] = all(_params(out / f.stem) == serial[str(f)] for f in files)
        if w == 2:
            timings["rerun"] = _run(cmd)
    result = {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores",
        "records": n,
        "command": command,
        "wall_s": timings,
        "records_per_hour": {k: 3600 * n / v for k, v in timings.items() if k != "rerun"},
        "speedup_over_serial": {k: timings["serial"] / timings[k] for k in ("batch_1", "batch_2")},
        "same_parameters_as_single_command": same,
    }
    if command == "fit":
        result["killed"] = killed_worker_run(files, corrupt, work, serial)
    target = Path(args.out, "batch.json")
    stored = json.loads(target.read_text()) if target.exists() else {}
    target.write_text(json.dumps(stored | {command: result}, indent=1) + "\n")
    print(json.dumps(result, indent=1))
    shutil.rmtree(work, ignore_errors=True)
    return result


if __name__ == "__main__":
    main()
