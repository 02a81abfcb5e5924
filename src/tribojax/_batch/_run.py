"""A batch on a Dask cluster: records spread over worker processes, complete ones skipped, the
table (DIR/batch.csv, DIR/batch.json) written at the end. docs/cli.md, "Many records"."""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import logging
import os
import shutil
import time
import uuid
from pathlib import Path

from .._cli._arguments import BATCH_COMMANDS  # (argparse only: no JAX)
from .._io._files import write_json_atomic, write_text_atomic
from ._records import BatchUsageError, expand_records, unique_stems
from ._task import MAIN_OUTPUT, STATE, row_path, run_record

# the arguments of `tribojax batch` that are the batch's own (the rest go to each record's command)
BATCH_KEYS = {
    "records",
    "out",
    "workers",
    "scheduler",
    "scheduler_file",
    "force",
    "quiet",
    "batch_command",
    "command",
    "target",
    "debug",
    "debug_here",
}
FIXED_COLUMNS = ("record", "status")
TAIL_COLUMNS = ("message", "exit_status", "wall_s", "worker", "reused")
GIB = 2**30


def _distributed():
    try:
        import distributed
    except ImportError:
        raise BatchUsageError(
            "batch runs on Dask, which is not installed: pip install 'tribojax[distributed]'"
        ) from None
    return distributed


def default_workers() -> int:
    """Worker processes of the local cluster: one per core, at most one per 2 GiB of memory."""
    from dask.system import CPU_COUNT
    from distributed.system import MEMORY_LIMIT

    return max(1, min(CPU_COUNT, int(MEMORY_LIMIT // (2 * GIB))))


@contextlib.contextmanager
def dask_client(client=None, *, workers=None, scheduler=None, scheduler_file=None, quiet=False):
    """(the client a batch runs on, the fit threads of each worker process or None): `client`
    as given, one connected to an existing scheduler (`scheduler` address or `scheduler_file`),
    or a local cluster of `workers` processes (one task at a time each, the cores shared out
    among them for the threads that run a record's independent fits side by side) on the
    loopback address, closed on exit. `quiet`: the cluster logs errors only (the command's
    choice for its process; else Dask's default)."""
    if client is not None:
        yield client, None
        return
    d = _distributed()
    if scheduler is not None or scheduler_file is not None:
        with d.Client(scheduler, scheduler_file=scheduler_file) as c:
            yield c, None
        return
    n = workers or default_workers()
    before = dict(os.environ)  # Dask's nannies set OMP_NUM_THREADS & co in the spawning process
    try:
        with (
            d.LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address=None,
                **({"silence_logs": logging.ERROR} if quiet else {}),
            ) as cluster,
            d.Client(cluster) as c,
        ):
            _restore(before)  # the workers have them; this process is left as it was
            yield c, max(1, (os.cpu_count() or 1) // n)
    finally:
        _restore(before)


def _restore(environ: dict) -> None:
    for k in set(os.environ) - set(environ):
        del os.environ[k]
    os.environ.update({k: v for k, v in environ.items() if os.environ.get(k) != v})


class _Strict(argparse.ArgumentParser):
    def error(self, message):
        raise BatchUsageError(message)


def command_options(command: str, options: dict) -> dict:
    """A record command's arguments (`tribojax COMMAND`'s parsed options, its defaults filled
    in) from Python keywords named as the options' destinations (`alpha="free"`,
    `max_effects=2`, `start={"F_s": 0.5}`), checked by the command's own parser."""
    if command not in BATCH_COMMANDS:
        raise BatchUsageError(f"command = {command!r} is not one of {list(BATCH_COMMANDS)}")
    parser = _Strict(prog=f"tribojax batch {command}")
    BATCH_COMMANDS[command](parser, batch=True)
    actions = {a.dest: a for a in parser._actions if a.option_strings}
    tokens = []
    for name, value in options.items():
        if name not in actions or name == "help":
            allowed = sorted(k for k in actions if k != "help")
            raise BatchUsageError(f"{command} has no option {name!r}; allowed: {allowed}")
        action = actions[name]
        flag = max(action.option_strings, key=len)
        if action.nargs == 0:
            tokens += [flag] if value else []
        elif value is not None:
            if isinstance(value, dict):
                value = [f"{k}={v}" for k, v in value.items()]
            many = isinstance(value, list | tuple)
            tokens += [flag, *map(str, value)] if many else [flag, str(value)]
    parsed = vars(parser.parse_args([*tokens, "--", "RECORD"]))
    extra = [v for v in parsed["records"] if v != "RECORD"]
    if extra:
        raise BatchUsageError(f"{command}: values {extra} belong to no option (one value each?)")
    return strip_batch_keys(parsed)


def strip_batch_keys(parsed: dict) -> dict:
    return {k: v for k, v in parsed.items() if k not in BATCH_KEYS}


def _stamp(path: Path) -> list:
    """Size and modification time of a file, of a folder's files, and of a CSV's sidecar."""
    files = sorted(path.rglob("*")) if path.is_dir() else [path, path.with_suffix(".json")]
    return [[p.name, p.stat().st_size, p.stat().st_mtime_ns] for p in files if p.is_file()]


def _file_options(command: str) -> tuple[str, ...]:
    """The command's options that name a file (a saved model)."""
    return ("from_model", "model") if command == "predict" else ("from_model",)


def _absolute(command: str, options: dict) -> dict:
    """`options` with the files they name as absolute paths (a worker's folder may differ)."""
    files = {k: str(Path(options[k]).resolve()) for k in _file_options(command) if options.get(k)}
    return options | files


def _request(command, options, path: Path) -> dict:
    """What a record's result depends on: the command, its options, the record's path and the
    stamps of its files and of the files the options name (a model)."""
    named = [Path(options[k]) for k in _file_options(command) if options.get(k)]
    stamps = [_stamp(p) for p in [path, *named]]
    request = {"command": command, "options": options, "record": str(path.resolve())}
    return json.loads(json.dumps(request | {"stamps": stamps}))


def _earlier_row(out: Path, stem: str, command: str, request: dict) -> dict | None:
    """The row of an earlier run of the same request (the same record files and options), if
    it is complete: ok with the command's main JSON in place, or an error of the command itself
    (a bad record fails again the same way; a task the cluster lost is run again)."""
    try:
        row = json.loads(row_path(out, stem).read_text())
    except (OSError, ValueError):
        return None
    if row.get("request") != request:
        return None
    if row.get("status") == "ok":
        return row if (out / stem / MAIN_OUTPUT[command]).is_file() else None
    return row if row.get("exit_status") is not None else None


def _failed_row(path, stem, exc) -> dict:
    what = f"{type(exc).__name__}: {exc}".strip().rstrip(":")
    return {
        "record": path,
        "stem": stem,
        "status": "error",
        "exit_status": None,
        "message": f"the task failed on the cluster: {what}",
        "figures": {},
    }


def run_batch(command, options, records, out, *, cluster=None, force=False, progress=None):
    """Run `tribojax COMMAND` (parsed `options`) on every record; the rows in the order of
    `records` (also written to DIR/batch.csv and DIR/batch.json). A record whose outputs are
    complete from an earlier run with the same request is not run again (`reused`), unless
    `force`; the cluster (`dask_client(**cluster)`) is started only if a record is left to run.
    `progress`: an object with `total` and `step(note)` (the command's display)."""
    out = Path(out).resolve()
    options = _absolute(command, options)
    paths = expand_records(records, out)
    stems = unique_stems(paths)
    rows: dict[int, dict] = {}
    todo = []
    for i, (path, stem) in enumerate(zip(paths, stems)):
        request = _request(command, options, path)
        earlier = None if force else _earlier_row(out, stem, command, request)
        if earlier is not None:
            rows[i] = earlier | {"record": str(path), "reused": True}
        else:
            todo.append((i, request))
    if todo:
        (out / STATE / "tmp").mkdir(parents=True, exist_ok=True)
        with dask_client(**(cluster or {})) as (client, threads):
            futures = {}
            settings = {"caller_pid": os.getpid(), "fit_threads": threads}
            for i, request in todo:
                key = f"tribojax-{command}-{stems[i]}-{uuid.uuid4().hex[:8]}"
                args = (command, options, request, stems[i], str(out), settings)
                futures[client.submit(run_record, *args, key=key, pure=False)] = i
            if progress is not None:
                progress.total = len(futures)
            for fut in _distributed().as_completed(list(futures)):
                i = futures[fut]
                try:
                    row = fut.result()
                except Exception as exc:  # a record that killed its workers (KilledWorker)
                    row = _failed_row(str(paths[i]), stems[i], exc)
                rows[i] = row | {"record": str(paths[i]), "reused": False}
                if progress is not None:
                    progress.step(f"{stems[i]}: {rows[i]['status']}")
    ordered = [rows[i] for i in range(len(paths))]
    write_table(out, command, options, ordered)
    shutil.rmtree(out / STATE / "tmp", ignore_errors=True)  # what killed workers left
    return ordered


def flat_rows(rows) -> tuple[list[str], list[dict]]:
    """The table's columns and rows: record, status, the key figures (in first-seen order),
    message, exit status, wall time, worker, reused."""
    figures: dict[str, None] = {}
    for r in rows:
        figures.update(dict.fromkeys(r.get("figures") or {}))
    columns = [*FIXED_COLUMNS, *figures, *TAIL_COLUMNS]
    flat = [{c: ({**r, **(r.get("figures") or {})}).get(c) for c in columns} for r in rows]
    return columns, flat


def write_table(out: Path, command: str, options: dict, rows) -> None:
    """DIR/batch.csv and DIR/batch.json (atomically)."""
    columns, flat = flat_rows(rows)
    text = io.StringIO()
    writer = csv.DictWriter(text, columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(flat)
    write_text_atomic(out / "batch.csv", text.getvalue())
    counts = {s: sum(r["status"] == s for r in rows) for s in ("ok", "error")}
    summary = {"command": command, "options": options, "records": len(rows), **counts}
    summary["reused"] = sum(bool(r.get("reused")) for r in rows)
    summary["written"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    write_json_atomic(out / "batch.json", summary | {"columns": columns, "rows": flat})


def batch(records, command, *, out, client=None, workers=None, force=False, **options) -> list:
    """Run `tribojax fit|discover|predict` on many records over a Dask cluster.

    Args:
        records: record files, folders (the records in them; a folder of EPOS steady-state
            exports is one record) or globs.
        command: "fit", "discover" or "predict" (predict needs `model="fit.json"`).
        out: the output folder: DIR/<record stem>/ exactly as the single command writes its
            --out folder, DIR/batch.csv and DIR/batch.json (one row per record).
        client: a `dask.distributed.Client` to run on (default: a local cluster of `workers`
            processes, one per core at most one per 2 GiB, started and closed here).
        force: run records again whose outputs are complete from an earlier run.
        **options: the single command's options by their names (`alpha="free"`,
            `max_effects=2`, `model="best"`, `start={"F_s": 0.5}`), checked by its parser.

    Returns:
        The rows, in the order of the records: dicts with "record", "status" ("ok" or "error"),
        the key figures (fit: parameters, "nrmse", "converged"; discover: "verdict", "effect",
        "effects", "excess_before", "excess_after"; predict: "nrmse"), "message", "wall_s",
        "worker", "reused". Each record runs in a worker process with the `tribojax` command's
        process settings there, so its numbers are the single command's; this process is not
        changed. Raises ValueError for a request that names nothing to run.
    """
    opts = command_options(command, options)
    cluster = {"client": client, "workers": workers}
    rows = run_batch(command, opts, records, out, cluster=cluster, force=force)
    return [{k: v for k, v in r.items() if k != "request"} for r in rows]
