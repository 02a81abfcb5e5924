"""Input validation that works both at the Python boundary and inside `jax.jit`.

Concrete values are checked with NumPy and rejected with a `ValueError` naming the parameter,
the offending value and the allowed range. Traced values (inside jit/vmap/grad) are checked with
`equinox.error_if`, whose return value must be used for the check to survive tracing.
"""

import contextlib

import equinox as eqx
import equinox._errors as _eqx_errors
import jax
import jax.numpy as jnp
import numpy as np

from ._precision import ensure_x64

# How a traced check fails: "default" follows EQX_ON_ERROR (a host callback that raises);
# "nan" makes the checked value NaN instead. The fit engine traces its programs with "nan" so
# that they hold no host callback (JAX's persistent cache skips such programs, jax 0.10) and a
# parameter the optimiser steps out of range is a rejected step, not an exception.
_ON_ERROR = "default"


# What `failures_as_nan` swaps in equinox 0.13's error module: the mode its checks read when they
# are traced, and its jitted check (whose trace cache could hand back a check traced earlier in
# "raise" mode) for the plain function.
_EQX_SWAP = (("EQX_ON_ERROR", "nan"),
             ("branched_error_if_impl_jit", getattr(_eqx_errors, "branched_error_if_impl", None)))


@contextlib.contextmanager
def failures_as_nan():
    """Within this block, checks traced under jit return NaN on failure instead of raising: the
    library's own (`on_error="nan"`, a distinct trace) and those inside diffrax and lineax
    (through equinox's error module, `_EQX_SWAP`; with another equinox that lacks those names
    nothing is swapped and the programs just are not cached). For programs whose caller turns a
    non-finite result into a `RESULTS` value."""
    global _ON_ERROR
    swap = [(k, v) for k, v in _EQX_SWAP if v is not None and hasattr(_eqx_errors, k)]
    before = _ON_ERROR, {k: getattr(_eqx_errors, k) for k, _ in swap}
    _ON_ERROR = "nan"
    for k, v in swap:
        setattr(_eqx_errors, k, v)
    try:
        yield
    finally:
        _ON_ERROR = before[0]
        for k, v in before[1].items():
            setattr(_eqx_errors, k, v)


def _is_concrete(*xs) -> bool:
    return not any(isinstance(x, jax.core.Tracer) for x in xs)


def as_f64(x, name: str):
    """Convert to a float64 JAX array (refusing bool/complex/str inputs)."""
    ensure_x64()
    if isinstance(x, str):
        raise ValueError(f"{name} must be a number, got the string {x!r}")
    if not isinstance(x, jax.core.Tracer):
        arr = np.asarray(x)
        if arr.dtype.kind not in "fiu":
            raise ValueError(f"{name} must be real-valued, got dtype {arr.dtype}")
    return jnp.asarray(x, dtype=jnp.float64)


def _interval(lo, hi, lo_open, hi_open) -> str:
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    lo_s = "-inf" if lo is None else f"{lo:g}"
    hi_s = "inf" if hi is None else f"{hi:g}"
    return f"{left}{lo_s}, {hi_s}{right}"


def check_range(x, name: str, lo=None, hi=None, *, lo_open=True, hi_open=True, unit=""):
    """Return `x` as float64, raising if any element lies outside the interval.

    `lo`/`hi` of None mean unbounded. NaN is always rejected.
    """
    x = as_f64(x, name)
    rng = _interval(lo, hi, lo_open, hi_open)
    unit_s = f" {unit}" if unit else ""
    bad = jnp.isnan(x)
    if lo is not None:
        bad = bad | ((x <= lo) if lo_open else (x < lo))
    if hi is not None:
        bad = bad | ((x >= hi) if hi_open else (x > hi))
    if _is_concrete(x, bad):  # under a jit trace, ops on a constant x give a traced `bad`
        bad_np = np.asarray(bad)
        if bad_np.any():
            value = np.asarray(x)[bad_np].ravel()[0]
            raise ValueError(f"{name} = {value:g}{unit_s} is outside the allowed range {rng}")
        return x
    message = f"{name} is outside the allowed range {rng}{unit_s} (or NaN)"
    return eqx.error_if(x, bad, message, on_error=_ON_ERROR)


def fail_if(x, bad, message: str):
    """Attach a check: raise `ValueError(message)` now if `bad` is concretely true, else `error_if`.

    Returns `x` (use the return value so the check is kept under jit).
    """
    if _is_concrete(x, bad):
        if np.asarray(bad).any():
            raise ValueError(message)
        return x
    return eqx.error_if(x, bad, message, on_error=_ON_ERROR)


def runtime_message(exc: BaseException) -> str:
    """The check's own message from an `equinox.error_if` failure raised inside jit (the text
    after the last "EquinoxRuntimeError:", without the trace and debugging hints), or the first
    line of any other exception."""
    text = str(exc)
    key = "EquinoxRuntimeError:"
    if key in text:
        return text[text.rindex(key) + len(key) :].split("\n\n")[0].strip()
    return (text.strip().splitlines() or [type(exc).__name__])[0].strip()
