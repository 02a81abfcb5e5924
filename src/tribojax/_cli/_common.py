"""Helpers shared by the subcommands: the one error path, output reservation, JSON output.

Every subcommand reports a problem as one line, `tribojax <cmd>: error: <message>`, and an exit
status: 2 for bad input (a malformed file, a parameter out of range, a refused output), 1 for a
computation that failed, 130 for Ctrl-C. `run_command` turns any exception into that line
(`--debug` shows the traceback instead); a subcommand may also `raise CommandError(...)` or
`return error(...)`.
"""

from __future__ import annotations

import contextlib
import os
import sys
from pathlib import Path

import equinox as eqx

from .._io._files import sidecar_path, write_json_atomic

__all__ = [
    "BAD_INPUT",
    "FAILED",
    "INTERRUPTED",
    "CommandError",
    "claim_outputs",
    "error",
    "refused_outputs",
    "run_command",
    "warn",
    "write_json_atomic",
]

BAD_INPUT = 2  # malformed input, a parameter out of range or a refused output
FAILED = 1  # the computation failed (did not converge, the model could not be evaluated)
INTERRUPTED = 130  # Ctrl-C (128 + SIGINT)

_PROG = ["tribojax"]  # "tribojax <cmd>" of the running subcommand, for messages


class CommandError(Exception):
    """A problem the command reports as one line and an exit status (default 2, bad input)."""

    def __init__(self, message: str, status: int = BAD_INPUT):
        super().__init__(message)
        self.status = status


def error(message: str, err=None, status: int = BAD_INPUT) -> int:
    """Print `tribojax <cmd>: error: message` to stderr (or `err`); return `status` (2)."""
    print(f"{_PROG[0]}: error: {message}", file=sys.stderr if err is None else err)
    return status


def warn(message: str, err=None) -> None:
    """Print `tribojax <cmd>: warning: message` to stderr (or `err`)."""
    print(f"{_PROG[0]}: warning: {message}", file=sys.stderr if err is None else err)


def _equinox_message(exc) -> str:
    """The check's own message from an `equinox.error_if` failure (without the JIT trace)."""
    text = str(exc)
    key = "EquinoxRuntimeError: "
    if key in text:
        text = text[text.rindex(key) + len(key) :]
    return text.split("\n\n")[0].strip()


def describe(exc: BaseException) -> tuple[int, str]:
    """(exit status, one-line message) for an exception raised by a subcommand."""
    if isinstance(exc, CommandError):
        return exc.status, str(exc)
    if isinstance(exc, OSError) and exc.filename is not None:
        return BAD_INPUT, f"{exc.filename}: {exc.strerror or exc}"
    if isinstance(exc, ValueError):  # DataFileError and every range check
        return BAD_INPUT, str(exc)
    if isinstance(exc, eqx.EquinoxRuntimeError):
        msg = _equinox_message(exc)
        return (BAD_INPUT if "allowed range" in msg else FAILED), msg
    return FAILED, f"the computation failed: {type(exc).__name__}: {exc} (--debug shows where)"


def run_command(name: str, func, args, *, debug: bool = False) -> int:
    """Run a subcommand `func(args)` through the one error path; its exit status."""
    _PROG[0] = f"tribojax {name}"
    try:
        return int(func(args))
    except KeyboardInterrupt:
        if debug:
            raise
        print(f"{_PROG[0]}: interrupted (Ctrl-C)", file=sys.stderr)
        return INTERRUPTED
    except Exception as exc:
        if debug:
            raise
        status, message = describe(exc)
        return error(message, status=status)


def refused_outputs(src, targets, *, force: bool) -> str | None:
    """Why the output files `targets` may not be written, or None if they may.

    An output may never be the input record `src` or its sidecar; the first target (the result
    JSON) is not replaced unless `force`.
    """
    if src is not None:
        inputs = {Path(src).resolve(), sidecar_path(src).resolve()}
        for target in targets:
            if Path(target).resolve() in inputs:
                return (
                    f"{target} is an input file: writing it would overwrite the input {src}; "
                    "choose another --out"
                )
    first = Path(targets[0])
    if first.is_dir():
        return f"{first} is a folder; choose another output name"
    if first.exists() and not force:
        return f"{first} exists; refusing to overwrite it (use --force or another --out)"
    return None


@contextlib.contextmanager
def claim_outputs(src, targets, *, force: bool):
    """Reserve the output files `targets` before a long computation; remove them on failure.

    Checks (before any work): no target is the input `src` or its sidecar, the first target does
    not exist (unless `force`), the folder can be created and written. A lock file beside the
    first target keeps a second run with the same output from starting (CommandError naming it);
    it is removed on exit. If the block raises, targets it created are removed (and the folder,
    if it was made here and is left empty), so a failed run leaves no partial output. Write the
    first target with `exclusive=not force`.
    """
    targets = [Path(t) for t in targets]
    why = refused_outputs(src, targets, force=force)
    if why:
        raise CommandError(why)
    folder = targets[0].parent
    if folder.exists() and not folder.is_dir():
        raise CommandError(f"{folder} is a file, not an output folder; choose another --out")
    created = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise CommandError(f"cannot create the output folder {folder}: {err.strerror}") from None
    lock = folder / f".{targets[0].name}.lock"
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        raise CommandError(
            f"another tribojax run is writing {targets[0]} (lock file {lock}); wait for it, "
            "choose another --out, or delete the lock if no run is active"
        ) from None
    except OSError as err:
        raise CommandError(f"cannot write into the folder {folder}: {err.strerror}") from None
    with os.fdopen(fd, "w") as f:
        f.write(f"{os.getpid()}\n")
    before = {t: t.exists() for t in targets}
    try:
        yield targets
    except BaseException as exc:
        if not isinstance(exc, FileExistsError):  # (that one is another run's file)
            for t, existed in before.items():
                if not existed:
                    t.unlink(missing_ok=True)
        raise
    finally:
        lock.unlink(missing_ok=True)
        if created and not any(folder.iterdir()):
            folder.rmdir()  # a folder made for outputs that were not written
