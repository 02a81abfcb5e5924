"""Shared timing helper of the benchmark scripts (warm wall time, median of repeats)."""

import statistics
import time

import jax


def median_time(fn, repeats, *, block=True):
    """Median wall time (s) of `fn()` over `repeats` calls, after one untimed (compiling) call.

    With `block`, each call ends in `jax.block_until_ready` so asynchronous dispatch is timed too.
    """
    out = fn()
    if block:
        jax.block_until_ready(out)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        if block:
            jax.block_until_ready(out)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)
