"""Independent fits side by side: a fit is one compiled solve whose ODE steps run on one core,
and JAX releases the GIL while it runs, so independent fits (starts, held-out folds, refits,
seeds; docs/architecture.md) can use the other cores. Results are the same numbers as one after
another (each call is pure)."""

from __future__ import annotations

import contextlib
import dataclasses
import os
from concurrent.futures import ThreadPoolExecutor


def _workers(text) -> int:
    """Threads for independent fits: `TRIBOJAX_FIT_WORKERS` (a whole number ≥ 1, read when
    tribojax is imported), else the CPU count, at most 4."""
    if text is None or text == "":
        return min(4, os.cpu_count() or 1)
    if not (text.strip().isascii() and text.strip().isdigit()) or int(text) < 1:
        raise ValueError(
            f"TRIBOJAX_FIT_WORKERS = {text!r} is outside the allowed range: a whole "
            "number >= 1 (1 runs one fit at a time)"
        )
    return int(text)


FIT_WORKERS = _workers(os.environ.get("TRIBOJAX_FIT_WORKERS"))
_POOL: list = []


def in_parallel(calls, wait=True):
    """Run the zero-argument `calls` on `FIT_WORKERS` threads; their results in order (or the
    futures, `wait=False`). Calls must not themselves call `in_parallel`."""
    if FIT_WORKERS <= 1 or len(calls) <= 1 and wait:
        futures = [_Lazy(c) for c in calls]  # run when read
    else:
        if not _POOL:
            _POOL.append(ThreadPoolExecutor(FIT_WORKERS, thread_name_prefix="tribojax-fit"))
        futures = [_POOL[0].submit(c) for c in calls]
    return [f.result() for f in futures] if wait else futures


@contextlib.contextmanager
def speculatively(calls):
    """Run the zero-argument calls (each may use `in_parallel`) `FIT_WORKERS` at a time ahead of
    need; yields their futures, to be read in order. On exit (a loop that stops at the first
    good result) the ones not started are cancelled and the running ones are waited for, so
    that no work outlives the call."""
    if len(calls) <= 1 or FIT_WORKERS <= 1:
        yield [_Lazy(c) for c in calls]
        return
    ex = ThreadPoolExecutor(FIT_WORKERS, thread_name_prefix="tribojax-start")
    try:
        yield [ex.submit(c) for c in calls]
    finally:
        ex.shutdown(wait=True, cancel_futures=True)


def in_background(call):
    """Start the zero-argument `call` (which may use `in_parallel`) on a thread of its own and
    return its future; with one worker it runs when read instead."""
    if FIT_WORKERS <= 1:
        return _Lazy(call)
    ex = ThreadPoolExecutor(1, thread_name_prefix="tribojax-background")
    try:
        return ex.submit(call)
    finally:
        ex.shutdown(wait=False)


@dataclasses.dataclass
class _Lazy:
    """A call run when its result is first read (once)."""

    call: object
    done: bool = False
    value: object = None

    def result(self):
        if not self.done:
            self.value, self.done, self.call = self.call(), True, None
        return self.value
