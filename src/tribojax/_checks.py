"""Input validation that works both at the Python boundary and inside `jax.jit`.

Concrete values are checked with NumPy and rejected with a `ValueError` naming the parameter,
the offending value and the allowed range. Traced values (inside jit/vmap/grad) are checked with
`equinox.error_if`, whose return value must be used for the check to survive tracing.
"""

import contextlib
import contextvars
import functools
import os

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ._precision import ensure_x64

# Failures as values (docs/performance.md, "Programs with a host callback"): while set, checks
# traced by tribojax (`fail_if`) give NaN instead of a raising host callback. Read at trace time,
# so every tribojax jit that may trace a check carries it in its cache key (`mode_jit`).
_NAN_MODE = contextvars.ContextVar("tribojax_failures_as_nan", default=False)


@contextlib.contextmanager
def failures_as_nan(on: bool = True):
    """Within this block (this thread or task), tribojax's checks traced under jit return NaN on
    failure instead of raising: for programs whose caller turns a non-finite result into a
    `RESULTS` value or an exception at its boundary. Checks inside diffrax, optimistix and
    lineax follow equinox's own `EQX_ON_ERROR` (the `tribojax` command sets it to `nan` for its
    process; docs/performance.md)."""
    token = _NAN_MODE.set(bool(on))
    try:
        yield
    finally:
        _NAN_MODE.reset(token)


def nan_mode() -> bool:
    """Whether checks traced now give NaN (`failures_as_nan`)."""
    return _NAN_MODE.get()


def _on_error() -> str:
    """How a check traced now reports a failure: NaN under `failures_as_nan`; else it raises with
    its message, whatever `EQX_ON_ERROR` says for other libraries' checks, unless that asks for
    a debugger or no checks ("breakpoint", "off")."""
    if _NAN_MODE.get():
        return "nan"
    return "default" if os.environ.get("EQX_ON_ERROR") in ("breakpoint", "off") else "raise"


def mode_jit(fn):
    """`eqx.filter_jit(fn)` whose cache key holds `nan_mode()`: a trace made with failures as NaN
    is never reused where checks must raise, and the reverse (`failures_as_nan`)."""

    @eqx.filter_jit
    def jitted(nan, *args, **kwargs):
        with failures_as_nan(nan):
            return fn(*args, **kwargs)

    @functools.wraps(fn)
    def call(*args, **kwargs):
        return jitted(_NAN_MODE.get(), *args, **kwargs)

    call.jitted = jitted
    return call


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
    if _is_concrete(x, bad) and np.asarray(bad).any():  # under jit a constant x gives a traced bad
        value = np.asarray(x)[np.asarray(bad)].ravel()[0]
        raise ValueError(f"{name} = {value:g}{unit_s} is outside the allowed range {rng}")
    return fail_if(x, bad, f"{name} is outside the allowed range {rng}{unit_s} (or NaN)")


def fail_if(x, bad, message: str):
    """Attach a check: raise `ValueError(message)` now if `bad` is concretely true, else `error_if`.

    Returns `x` (use the return value so the check is kept under jit).
    """
    if _is_concrete(x, bad):
        if np.asarray(bad).any():
            raise ValueError(message)
        return x
    return eqx.error_if(x, bad, message, on_error=_on_error())


# failure codes of diffrax's, optimistix's and lineax's result enumerations (those that exist)
_FAILURES = (
    "max_steps_reached",
    "singular",
    "breakdown",
    "divergence",
    "dt_min_reached",
    "nonlinear_max_steps_reached",
    "nonlinear_divergence",
    "nonfinite_input",
)


def check_result(x, result, enumeration, what: str):
    """Attach the failure check of a solver's `result` (an item of `enumeration`, e.g.
    `diffrax.RESULTS`) to `x`: raises "`what`: <the enumeration's message>" for a failure code,
    or gives NaN under `failures_as_nan` (`fail_if`). For solvers run with `throw=False`, so that
    how a failure surfaces is tribojax's choice, not `EQX_ON_ERROR`'s."""
    for name in _FAILURES:
        item = getattr(enumeration, name, None)
        if item is not None:
            x = fail_if(x, result == item, f"{what}: {enumeration[item]}")
    return x


def runtime_message(exc: BaseException) -> str:
    """The check's own message from an `equinox.error_if` failure raised inside jit (the text
    after the last "EquinoxRuntimeError:", without the trace and debugging hints), or the first
    line of any other exception."""
    text = str(exc)
    key = "EquinoxRuntimeError:"
    if key in text:
        return text[text.rindex(key) + len(key) :].split("\n\n")[0].strip()
    return (text.strip().splitlines() or [type(exc).__name__])[0].strip()


def finite_or_raise(x, what: str):
    """`x` as a NumPy array, or `RuntimeError` naming `what` if any value is NaN or infinite: the
    boundary check of a program compiled with failures as NaN (`failures_as_nan`, `throw=False`
    inside). A traced `x` is returned unchanged (the caller's own boundary checks it)."""
    if not _is_concrete(x):
        return x
    arr = np.asarray(x)
    if not np.all(np.isfinite(arr)):
        raise RuntimeError(
            f"{what}: the result is not finite (a solver did not finish, or an "
            "input is outside the model's range)"
        )
    return arr


def finite_result(fn, *args, what: str):
    """`fn(*args)` run with failures as NaN (`failures_as_nan`: a program without host callbacks,
    which can be stored and cached) and checked at this boundary: its array outputs as NumPy
    arrays, or `RuntimeError` naming `what` if one is not finite (`finite_or_raise`)."""
    with failures_as_nan():
        out = fn(*args)
    return jax.tree_util.tree_map(lambda x: finite_or_raise(x, what), out)


def cacheable_call(fn, *args, failed=None, raising=None):
    """`fn(*args)` for a caller outside any trace (inside one: `raising(*args)`), compiled so
    that JAX's persistent cache keeps it: with failures as NaN (`failures_as_nan`: no host
    callback). If `failed(out)` (default: a non-finite array in the output), `raising(*args)`
    (default `fn`) runs with the usual raising checks, so the user meets the check's own
    exception and message (or, if nothing raises, gets that run's output): a second compilation
    only where something failed."""
    raising = fn if raising is None else raising
    if any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(args)):
        return raising(*args)  # inside a caller's trace: the checks as they are
    with failures_as_nan():
        out = fn(*args)
    failed = _non_finite if failed is None else failed
    return raising(*args) if failed(out) else out


def _non_finite(out) -> bool:
    return not all(
        bool(np.all(np.isfinite(np.asarray(x))))
        for x in jax.tree_util.tree_leaves(out)
        if np.asarray(x).dtype.kind in "fc"
    )
