"""Helpers shared by the subcommands: the one error path, output reservation, JSON output.

The error line and the exit statuses: docs/cli.md, "Errors". `run_command` turns any exception
into that line (`--debug` shows the traceback instead); a subcommand may also
`raise CommandError(...)` or `return error(...)`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import shutil
import signal
import sys
import threading
import time
from pathlib import Path

import equinox as eqx

from .._checks import runtime_message
from .._decimate import decimate_record
from .._io._files import sidecar_path, write_json_atomic
from .._limits import INTERRUPTED
from .._plot import figure, save_figure
from ._lock import LockHeld, lock_stamp, take_lock

__all__ = [
    "BAD_INPUT",
    "FAILED",
    "INTERRUPTED",
    "CommandError",
    "Progress",
    "claim_outputs",
    "decimate_factor",
    "error",
    "plot_model_and_residual",
    "progress",
    "reduce_record",
    "refused_outputs",
    "run_command",
    "warn",
    "with_band_tension",
    "write_json_atomic",
]

BAD_INPUT = 2  # malformed input, a parameter out of range or a refused output
FAILED = 1  # the computation failed (did not converge, the model could not be evaluated)

_PROG = ["tribojax"]  # "tribojax <cmd>" of the running subcommand, for messages


class CommandError(Exception):
    """A problem the command reports as one line and an exit status (default 2, bad input)."""

    def __init__(self, message: str, status: int = BAD_INPUT):
        super().__init__(message)
        self.status = status


def error(message: str, status: int = BAD_INPUT) -> int:
    """Print `tribojax <cmd>: error: message` to stderr; return `status` (2)."""
    print(f"{_PROG[0]}: error: {message}", file=sys.stderr)
    return status


def warn(message: str) -> None:
    """Print `tribojax <cmd>: warning: message` to stderr."""
    print(f"{_PROG[0]}: warning: {message}", file=sys.stderr)


def describe(exc: BaseException) -> tuple[int, str]:
    """(exit status, one-line message) for an exception raised by a subcommand."""
    if isinstance(exc, CommandError):
        return exc.status, str(exc)
    if isinstance(exc, OSError) and exc.filename is not None:
        return BAD_INPUT, f"{exc.filename}: {exc.strerror or exc}"
    if isinstance(exc, ValueError):  # DataFileError and every range check
        return BAD_INPUT, str(exc)
    if isinstance(exc, eqx.EquinoxRuntimeError):
        msg = runtime_message(exc)
        return (BAD_INPUT if "allowed range" in msg else FAILED), msg
    return FAILED, f"the computation failed: {type(exc).__name__}: {exc} (--debug shows where)"


class Terminated(KeyboardInterrupt):
    """SIGTERM (`kill`, `timeout`, Slurm, systemd) raised as an interrupt, so that it unwinds
    like Ctrl-C: claimed outputs and lock files are removed on the way out."""


def _on_sigterm(signum, frame):
    raise Terminated


def run_command(name: str, func, args, *, debug: bool = False) -> int:
    """Run a subcommand `func(args)` through the one error path; its exit status (130 after
    Ctrl-C or SIGTERM, with every claimed output and lock removed)."""
    _PROG[0] = f"tribojax {name}"
    main = threading.current_thread() is threading.main_thread()
    before = signal.signal(signal.SIGTERM, _on_sigterm) if main else None
    try:
        return int(func(args))
    except KeyboardInterrupt as exc:
        if debug:
            raise
        how = "SIGTERM" if isinstance(exc, Terminated) else "Ctrl-C"
        print(f"{_PROG[0]}: interrupted ({how})", file=sys.stderr)
        return INTERRUPTED
    except Exception as exc:
        if debug:
            raise
        status, message = describe(exc)
        return error(message, status=status)
    finally:
        if main:
            signal.signal(signal.SIGTERM, before)


def refused_outputs(src, targets, *, force: bool, inputs=()) -> str | None:
    """Why the output files `targets` may not be written, or None if they may: an output is
    never an input (the record `src`, its sidecar, a file of `inputs` such as a `--from` model),
    and no existing target is replaced unless `force` (which replaces only `targets`)."""
    given = [(Path(p), Path(p)) for p in inputs if p is not None]
    if src is not None:
        given += [(Path(src), Path(src)), (sidecar_path(src), Path(src))]
    resolved = {p.resolve(): named for p, named in given}
    for target in targets:
        named = resolved.get(Path(target).resolve())
        if named is not None:
            return (
                f"{target} is an input file: writing it would overwrite the input {named}; "
                "choose another --out"
            )
    first = Path(targets[0])
    if first.is_dir():
        return f"{first} is a folder; choose another output name"
    if not force:
        for target in map(Path, targets):
            if target.exists():
                return f"{target} exists; refusing to overwrite it (use --force or another --out)"
    return None


@contextlib.contextmanager
def claim_outputs(src, targets, *, force: bool, inputs=()):
    """Reserve the output files `targets` before a long computation; remove them on failure.

    Checks (before any work) `refused_outputs` and that the folder can be created and written. A
    lock file beside the first target keeps a second run with the same output from starting
    (CommandError naming it); it is removed on exit. If the block raises, targets it created are
    removed (and the folder, if it was made here and is left empty), so a failed run leaves no
    partial output. Write the first target with `exclusive=not force`.
    """
    targets = [Path(t) for t in targets]
    why = refused_outputs(src, targets, force=force, inputs=inputs)
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
        fd, note = take_lock(lock, targets[0])
    except LockHeld as err:
        raise CommandError(str(err)) from None
    except OSError as err:
        raise CommandError(f"cannot write into the folder {folder}: {err.strerror}") from None
    if note:
        warn(note)
    try:
        os.write(fd, lock_stamp().encode())
    except OSError as err:  # a full disk: no lock left behind
        lock.unlink(missing_ok=True)
        if created and not any(folder.iterdir()):
            folder.rmdir()
        raise CommandError(f"cannot write the lock file {lock}: {err.strerror}") from None
    finally:
        os.close(fd)
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


class Progress:
    """A one-line progress display on stderr for a long subcommand.

    Shown only when the stream is a terminal and not `quiet`; otherwise every method does
    nothing, so CI logs, pipes and files stay clean. `step(note)` counts a step (a bar when
    `total` is known), `note(text)` shows a solver's latest message in place (a callback for
    `progress=` arguments); a ticker redraws the elapsed time while a compiled computation runs.
    While shown, the command's own stdout lines are printed above the display.
    """

    TICK_S = 0.5

    def __init__(self, label: str, total: int | None = None, *, quiet: bool = False, stream=None):
        self.stream = sys.stderr if stream is None else stream
        isatty = getattr(self.stream, "isatty", None)
        self.enabled = not quiet and bool(isatty and isatty())
        self.label, self.total = label, total
        self.count, self.text = 0, ""
        self._t0 = time.perf_counter()
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._thread = None
        self._stdout = None
        self._shown = False  # the display line is on screen
        self._midline = False  # stdout has written part of a line: do not draw over it

    def line(self) -> str:
        """The display's current text (without control characters)."""
        elapsed = f"{time.perf_counter() - self._t0:5.1f} s"
        if self.total:
            done = min(self.count, self.total)
            bar = "#" * (20 * done // self.total) + "-" * (20 - 20 * done // self.total)
            head = f"{self.label} [{bar}] {done}/{self.total} {elapsed}"
        else:
            spin = "|/-\\"[int(2 * (time.perf_counter() - self._t0)) % 4]
            head = f"{self.label} {spin} {elapsed}"
        width = shutil.get_terminal_size((100, 20)).columns - 1
        return f"{head}  {self.text}"[:width].rstrip()

    def _draw(self) -> None:
        if self.enabled:
            with self._lock:
                if not self._midline:
                    self.stream.write("\r\x1b[K" + self.line())
                    self.stream.flush()
                    self._shown = True

    def _clear(self) -> None:
        if self.enabled:
            with self._lock:
                if self._shown:
                    self.stream.write("\r\x1b[K")
                    self.stream.flush()
                    self._shown = False

    def step(self, note: str | None = None) -> None:
        """One more step done (and the text shown beside the bar, if given)."""
        self.count += 1
        if note is not None:
            self.text = note
        self._draw()

    def note(self, text: str) -> None:
        """Show `text` (a solver's progress line) beside the bar."""
        self.text = " ".join(str(text).split())
        self._draw()

    def _tick(self) -> None:
        while not self._stop.wait(self.TICK_S):
            self._draw()

    def __enter__(self):
        if self.enabled:
            self._draw()
            self._thread = threading.Thread(target=self._tick, daemon=True)
            self._thread.start()
            self._stdout = sys.stdout
            sys.stdout = _AboveProgress(self, self._stdout)
        return self

    def __exit__(self, *exc):
        if self.enabled:
            self._stop.set()
            self._thread.join()
            sys.stdout = self._stdout
            self._clear()
        return False


class _AboveProgress:
    """stdout while a Progress is shown: a write clears the display line first, and the display
    is drawn again once the line is complete."""

    def __init__(self, progress: Progress, out):
        self._progress, self._out = progress, out

    def write(self, text: str) -> int:
        with self._progress._lock:
            self._progress._clear()
            n = self._out.write(text)
            self._out.flush()
            if text:
                self._progress._midline = not text.endswith("\n")
            self._progress._draw()
        return n

    def __getattr__(self, name):
        return getattr(self._out, name)


def progress(args, label: str, total: int | None = None) -> Progress:
    """The progress display of a subcommand: off with `--quiet` (`args.quiet`) or when stderr is
    not a terminal."""
    return Progress(label, total, quiet=bool(getattr(args, "quiet", False)))


def with_band_tension(record, value, path):
    """`record` with the `--band-tension` value (N) set; CommandError unless it is a loop or
    history (None: unchanged)."""
    if value is None:
        return record
    if record.kind != "loop":
        raise CommandError(
            f"--band-tension is for loops and histories; {path} is {record.description}"
        )
    return dataclasses.replace(record, band_tension=value)


def decimate_factor(args) -> int | None:
    """`--decimate auto|off|N` as None (auto), 1 (off) or N; CommandError otherwise."""
    text = str(args.decimate).strip().lower()
    if text in ("auto", "off"):
        return None if text == "auto" else 1
    try:
        factor = int(text)
    except ValueError:
        raise CommandError(
            f"--decimate = {args.decimate!r}: expected auto, off or an integer >= 1"
        ) from None
    if factor < 1:
        raise CommandError(f"--decimate = {factor} is outside the allowed range [1, inf)")
    return factor


def reduce_record(record, args, *, whole_cycles: bool = False):
    """(the record reduced as `--decimate` asks, the `Decimation`): `tribojax.decimate_record`.

    A reduction is announced on stdout in one line."""
    factor = decimate_factor(args)
    if args.max_samples < 4:
        raise CommandError(
            f"--max-samples = {args.max_samples} is outside the allowed range [4, inf)"
        )
    record, how = decimate_record(
        record, factor, max_samples=args.max_samples, whole_cycles=whole_cycles
    )
    if how.cycles_kept is not None:
        print(
            f"{record.source}: kept the first {how.cycles_kept} whole cycles "
            f"({how.samples_used} of {how.samples_in_record} samples)"
        )
    if how.factor > 1:
        print(
            f"{record.source}: {how.samples_used} samples reduced to {how.samples} (blocks "
            f"of {how.factor}, {how.method}; noise sd {how.noise_std_original:.3g} -> "
            f"{how.noise_std:.3g})"
        )
    return record, how


def plot_model_and_residual(
    path,
    c: dict,
    title: str,
    resid_axes: tuple[str, str],
    *,
    labels=("data", "model"),
    title_size=None,
) -> bool:
    """The figure of `fit` and `predict`: data and model (`c`'s "x", "data", "model", "xlabel",
    "ylabel") over the residual ("resid_x", "resid"). False when matplotlib is missing."""
    fig = figure("figure", figsize=(7, 6), constrained_layout=True)
    if fig is None:
        return False
    ax, ar = fig.subplots(2, 1, gridspec_kw=dict(height_ratios=[3, 1.3]))
    ax.plot(c["x"], c["data"], "k.", ms=2, label=labels[0])
    ax.plot(c["x"], c["model"], "C3-", lw=1, label=labels[1])
    ax.set(xlabel=c["xlabel"], ylabel=c["ylabel"])
    ax.set_title(title, **({"fontsize": title_size} if title_size else {}))  # default: rcParams
    ax.legend()
    ar.plot(c["resid_x"], c["resid"], "C0.", ms=2)
    ar.axhline(0, color="k", lw=0.5)
    ar.set(xlabel=resid_axes[0], ylabel=resid_axes[1])
    save_figure(fig, path)
    return True
