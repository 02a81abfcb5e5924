"""The `tribojax` command line: the subcommands of `SUBCOMMANDS` (usage and errors:
docs/cli.md)."""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import warnings
from typing import NoReturn

from .._cache import READ_ERROR
from .._limits import INTERRUPTED
from . import _arguments as A

__all__ = ["SUBCOMMANDS", "build_parser", "main"]

# The subcommands: (name, help, add_arguments(parser), "module:function" that runs it, imported
# only when it runs; relative to this package unless it starts with "tribojax."). A new
# subcommand is one line here, its arguments in `_arguments` and one module in this package;
# errors go through `_common.run_command`.
SUBCOMMANDS = [
    (
        "reproduce",
        "reproduce wang2022 Tables 3-7 and wu2015 K̄, C̄",
        A.reproduce_arguments,
        "_reproduce:cmd_reproduce",
    ),
    (
        "contact",
        "contact parameters from a topography file or D, G",
        A.contact_arguments,
        "_contact:run_contact",
    ),
    (
        "hysteresis",
        "K̄, C̄ of a Jenkins or Mindlin element (wu2015)",
        A.hysteresis_arguments,
        "_hysteresis:run_hysteresis",
    ),
    (
        "discover",
        "find the effect a slip run or loop's model is missing",
        A.discover_arguments,
        "_discover:run_discover",
    ),
    (
        "fit",
        "fit a slip run or hysteresis loop CSV (+ sidecar JSON)",
        A.fit_arguments,
        "_fit:run_fit",
    ),
    (
        "predict",
        "a fitted model (fit.json, discovery.json) on another record",
        A.predict_arguments,
        "_predict:run_predict",
    ),
    (
        "frf",
        "forced response of a structure with friction contacts",
        A.frf_arguments,
        "_frf:run_frf",
    ),
    (
        "batch",
        "fit, discover or predict many records on a Dask cluster",
        A.batch_arguments,
        "tribojax._batch._command:run_batch_command",  # the batch layer, above the command line
    ),
]


# Subcommands that show a progress display on a terminal (`--quiet` turns it off).
LONG_RUNNING = ("reproduce", "fit", "discover", "frf")


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("tribojax")
    except PackageNotFoundError:
        return "0.0.0"


def build_parser() -> argparse.ArgumentParser:
    """The `tribojax` argument parser with every subcommand of `SUBCOMMANDS` (no JAX import)."""
    parser = argparse.ArgumentParser(
        prog="tribojax", description="Rough-surface contact and friction models (JAX)."
    )
    parser.add_argument("--version", action="version", version=f"tribojax {_version()}")
    debug = dict(action="store_true", help="show the traceback of an error")
    parser.add_argument("--debug", **debug)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, help_text, add_arguments, target in SUBCOMMANDS:
        cmd = sub.add_parser(name, help=help_text)
        add_arguments(cmd)
        cmd.add_argument("--debug", dest="debug_here", **debug)
        if name in LONG_RUNNING:
            cmd.add_argument(
                "--quiet",
                action="store_true",
                help="no progress display (it is shown only on a terminal)",
            )
        cmd.set_defaults(target=target)
    return parser


def configure_process() -> None:
    """The choices the `tribojax` command makes for its own process (a library user makes them by
    explicit calls): XLA:CPU's one-kernel loops (`tribojax.use_one_kernel`) unless
    `TRIBOJAX_XLA_HOIST=off`, the compilation cache (`tribojax.use_compilation_cache`:
    `TRIBOJAX_CACHE_DIR`, `TRIBOJAX_CACHE=off`), and failures inside diffrax, optimistix and
    lineax as NaN (`EQX_ON_ERROR=nan` unless set: their programs then hold no host callback and
    are cached; tribojax's own checks still raise with their message). docs/cli.md, "Environment".
    """
    if "equinox" not in sys.modules:  # equinox reads it once, on import
        os.environ.setdefault("EQX_ON_ERROR", "nan")
        given = os.environ["EQX_ON_ERROR"]
        if given not in ("raise", "breakpoint", "nan", "off"):  # equinox's traceback otherwise
            raise ValueError(
                f"EQX_ON_ERROR = {given!r}: allowed 'raise', 'breakpoint', 'nan' "
                "(the command's default) or 'off'"
            )
    from .. import _parallel  # noqa: F401  (TRIBOJAX_FIT_WORKERS checked now: exit 2, one line)
    from .._cache import OFF, use_compilation_cache
    from .._xla import use_one_kernel

    hoist = os.environ.get("TRIBOJAX_XLA_HOIST", "on").strip().lower() or "on"
    if hoist not in ("on", "1", "yes", "true", *OFF):
        raise ValueError(f"TRIBOJAX_XLA_HOIST = {hoist!r}: allowed 'on' (the default) or 'off'")
    if hoist not in OFF:
        use_one_kernel()
    use_compilation_cache()


def main(argv=None, *, configure: bool = False) -> int:
    """`tribojax`: the exit status of the subcommand (0 done, 1 failed computation, 2 bad
    input, 130 interrupted); errors are one line `tribojax <cmd>: error: ...`. `configure`: make
    the command's process choices first (`configure_process`; the console script does)."""
    args = build_parser().parse_args(argv)
    debug = args.debug or args.debug_here
    if configure:
        try:
            configure_process()
        except ValueError as err:
            print(f"tribojax {args.command}: error: {err}", file=sys.stderr)
            return 2
    from ._common import run_command

    module, function = args.target.split(":")
    module = module if module.startswith("tribojax.") else f"{__package__}.{module}"
    run = getattr(importlib.import_module(module), function)
    if _CONSOLE[0]:  # the imports are over: from here an interrupt raises (`console`)
        _RAISE[0] = True
        if _INTERRUPTS:
            raise KeyboardInterrupt
    return run_command(args.command, run, args, debug=debug)


_INTERRUPTS: list = []  # Ctrl-C received by the console script's process
_CONSOLE = [False]  # `console` is running `main`
# whether an interrupt raises KeyboardInterrupt where it lands: not during the imports (raised
# inside JAX's C++ module initialisation it aborts the process) nor after the command is over
_RAISE = [False]


def _on_signal(signum, frame):
    _INTERRUPTS.append(signum)
    if _RAISE[0]:
        raise KeyboardInterrupt


def _interrupted(argv) -> int:
    name = " ".join(["tribojax", *[a for a in (argv or sys.argv[1:])[:1] if a[:1] != "-"]])
    print(f"{name}: interrupted (Ctrl-C)", file=sys.stderr)
    return INTERRUPTED


def console(argv=None, *, restore: bool = True) -> int:
    """The console script's run of `main` (the exit status): Ctrl-C (SIGINT) anywhere — during
    the imports (recorded, raised once they are over), the computation, or after the outputs are
    written — is exit 130 with one line.
    An interrupt Python cannot raise where it lands (inside a garbage-collection callback of
    JAX: "Exception ignored in ...") is still remembered and ends the run with 130, its
    traceback not shown. `restore`: put the previous SIGINT handler back (else the handler
    stays, recording only, until the process ends: `entry`)."""
    before = signal.signal(signal.SIGINT, _on_signal)
    hook = sys.unraisablehook

    def quiet(u):  # an interrupt that landed in a callback: said once, below
        if not isinstance(u.exc_value, KeyboardInterrupt):
            hook(u)

    sys.unraisablehook = quiet
    shown, unreadable = warnings.showwarning, []

    def show(message, category, filename, lineno, file=None, line=None):
        if str(message).startswith(READ_ERROR):  # repaired below, said once
            unreadable.append(message)
        else:
            shown(message, category, filename, lineno, file, line)

    warnings.showwarning = show
    _INTERRUPTS.clear()
    _CONSOLE[0], _RAISE[0] = True, False
    try:
        status = main(argv, configure=True)
    except KeyboardInterrupt:  # before the subcommand's own handler (imports, start-up)
        status = None
    finally:
        _CONSOLE[0], _RAISE[0] = False, False
        warnings.showwarning = shown
        if restore:
            signal.signal(signal.SIGINT, before)
            sys.unraisablehook = hook
    if unreadable:
        from .._cache import repair_compilation_cache

        gone = repair_compilation_cache()
        print(
            f"tribojax: {len(unreadable)} compiled programs could not be read from the cache; "
            f"removed {len(gone)} unreadable entries (stored again when next compiled)",
            file=sys.stderr,
        )
    if status is None or (_INTERRUPTS and status != INTERRUPTED):
        status = _interrupted(argv)
    return status


def entry() -> NoReturn:
    """The console script: `console`, then an exit without the interpreter's teardown once the
    command is over (its files are closed and written); why: docs/cli.md, "Exit". An interrupt
    after the command is over still ends the process with 130."""
    status = console(restore=False)
    sys.stdout.flush()
    if _INTERRUPTS and status != INTERRUPTED:
        status = _interrupted(None)
    sys.stderr.flush()
    os._exit(status)


if __name__ == "__main__":
    sys.exit(entry())
