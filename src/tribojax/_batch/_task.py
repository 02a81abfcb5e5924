"""One record of a batch, run on a worker: the single command in the worker's process, its
outputs moved into place atomically, and its row (status, key figures, wall time, worker).

A worker process runs one record at a time (`_ONE_AT_A_TIME`: a command prints and keeps
per-process state) and keeps its compiled programs warm for the next. The first record a worker
process runs makes the `tribojax` command's process choices there (`configure_process`: XLA
options, compilation cache), so its numbers are the single command's; never in the caller's own
process (an in-process cluster), which tribojax leaves alone.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import json
import os
import shutil
import socket
import threading
import time
import uuid
from pathlib import Path

from .._cli._main import SUBCOMMANDS, configure_process  # (argparse only: no JAX, no equinox)
from .._io._files import write_json_atomic

MAIN_OUTPUT = {"fit": "fit.json", "discover": "discovery.json", "predict": "prediction.json"}
TARGETS = {name: target for name, _, _, target in SUBCOMMANDS if name in MAIN_OUTPUT}
STATE = ".batch"  # DIR/.batch/rows/<stem>.json: each record's row; DIR/.batch/tmp: runs under way

_ONE_AT_A_TIME = threading.Lock()
_CONFIGURED: list[bool] = []


def _configure_once(settings: dict) -> None:
    if _CONFIGURED or os.getpid() == settings["caller_pid"]:
        return
    if settings["fit_threads"]:  # a local cluster's share of the cores (read on import)
        os.environ.setdefault("TRIBOJAX_FIT_WORKERS", str(settings["fit_threads"]))
    with contextlib.suppress(RuntimeError):  # a worker whose JAX had started: as it is
        configure_process()
    _CONFIGURED.append(True)


def _worker_name() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def row_path(out: Path, stem: str) -> Path:
    return Path(out) / STATE / "rows" / f"{stem}.json"


def key_figures(command: str, data: dict) -> dict:
    """The row's figures from the command's main JSON: fit → parameters and NRMSE (plus
    converged); discover → verdict, effect, effects, excess before/after; predict → NRMSE."""
    if command == "fit":
        figures = {"converged": data.get("converged"), "nrmse": data.get("nrmse")}
        return figures | dict(data.get("parameters") or {})
    if command == "discover":
        return {
            "verdict": data.get("verdict"),
            "effect": data.get("effect"),
            "effects": ";".join(data.get("effects") or []),
            "excess_before": data.get("excess_rmse_before"),
            "excess_after": data.get("excess_rmse_after"),
            "converged": data.get("converged"),
        }
    return {"nrmse": data.get("nrmse")}


def _replace_folder(new: Path, final: Path, trash: Path) -> None:
    """Put the folder `new` at `final` by renames (an older `final` removed after)."""
    if final.exists():
        trash.parent.mkdir(parents=True, exist_ok=True)
        os.replace(final, trash)
    os.replace(new, final)
    shutil.rmtree(trash, ignore_errors=True)


def _last_error(text: str) -> str:
    lines = [ln.split(": error: ", 1)[-1] for ln in text.splitlines() if ": error: " in ln]
    return lines[-1] if lines else ""


def run_record(command: str, options: dict, request: dict, stem: str, out: str, settings: dict):
    """Run `tribojax COMMAND` on the record `request["record"]` (an absolute path) with
    `options` (the command's parsed arguments), writing DIR/<stem>/ as the command writes its
    --out folder; the record's row (also kept in DIR/.batch/rows/<stem>.json with the `request`,
    so that a rerun with the same request can skip a complete record). `settings`: the
    caller's process id (never configured) and the fit threads of a local cluster's worker."""
    record = request["record"]
    with _ONE_AT_A_TIME:
        _configure_once(settings)
        from .._cli._common import run_command  # after the settings: it imports equinox

        out = Path(out)
        token = uuid.uuid4().hex[:12]
        tmp = out / STATE / "tmp" / f"{stem}.{token}"
        tmp.parent.mkdir(parents=True, exist_ok=True)
        args = argparse.Namespace(**options)
        args.file = [record] if command in ("fit", "discover") else record
        args.out, args.force, args.quiet = str(tmp), False, True
        module, function = TARGETS[command].split(":")
        run = getattr(importlib.import_module(f"tribojax._cli.{module}"), function)
        said = io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            status = run_command(command, run, args)
        wall = time.perf_counter() - t0
        row = {"record": record, "stem": stem, "status": "ok" if status == 0 else "error"}
        main = tmp / MAIN_OUTPUT[command]
        figures = key_figures(command, json.loads(main.read_text())) if main.exists() else {}
        if tmp.exists() and any(tmp.iterdir()):
            _replace_folder(tmp, out / stem, out / STATE / "trash" / f"{stem}.{token}")
        shutil.rmtree(tmp, ignore_errors=True)
        row |= {
            "exit_status": status,
            "message": "" if status == 0 else _last_error(said.getvalue()),
            "wall_s": wall,
            "worker": _worker_name(),
            "figures": figures,
            "request": request,
        }
        write_json_atomic(row_path(out, stem), row)
        return row
