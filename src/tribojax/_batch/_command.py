"""`tribojax batch fit|discover|predict RECORDS... --out DIR`: the single command on every record,
over a Dask cluster (a local one by default). docs/cli.md, "Many records".

Exit codes: 0 every record ok (run now or complete from an earlier run); 1 a record failed (its
row says why); 2 a usage error (nothing run) or the output folder held by another batch.
"""

from __future__ import annotations

from pathlib import Path

from .._cli._common import CommandError, progress
from .._cli._lock import LockHeld, lock_stamp, take_lock
from ._records import BatchUsageError
from ._run import run_batch, strip_batch_keys


def _held(out: Path):
    out.mkdir(parents=True, exist_ok=True)
    lock = out / ".batch.lock"
    try:
        fd, _ = take_lock(lock, out / "batch.json")
    except LockHeld as err:
        raise CommandError(str(err)) from None
    with open(fd, "w") as fh:
        fh.write(lock_stamp())
    return lock


def run_batch_command(args) -> int:
    """Run `tribojax batch` with parsed `args`; the exit status (module docstring)."""
    command, out = args.batch_command, Path(args.out)
    options = strip_batch_keys(vars(args))
    if out.exists() and not out.is_dir():
        raise CommandError(f"--out {out} is a file, not an output folder")
    lock = _held(out)
    try:
        cluster = {k: getattr(args, k) for k in ("workers", "scheduler", "scheduler_file")}
        cluster["quiet"] = True
        with progress(args, f"batch {command}") as shown:
            rows = run_batch(
                command,
                options,
                args.records,
                out,
                cluster=cluster,
                force=args.force,
                progress=shown,
            )
    except BatchUsageError as err:
        raise CommandError(str(err)) from None
    finally:
        lock.unlink(missing_ok=True)
    failed = [r for r in rows if r["status"] != "ok"]
    reused = sum(bool(r.get("reused")) for r in rows)
    n = f"{len(rows)} record" + "s" * (len(rows) != 1)
    print(
        f"{n}: {len(rows) - len(failed)} ok, {len(failed)} failed ({reused} not run again: "
        f"complete from an earlier run); wrote {out / 'batch.csv'} and {out / 'batch.json'}"
    )
    for r in failed:
        said = r["message"] if r["record"] in r["message"] else f"{r['record']}: {r['message']}"
        print(f"  {said}")
    return 1 if failed else 0
