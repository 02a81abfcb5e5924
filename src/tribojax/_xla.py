"""The one-kernel XLA option, by explicit choice (docs/performance.md, "One kernel per solve").

XLA:CPU compiles a `while` loop into one kernel only below a size limit (1 kB). Raised, a whole
adaptive slip solve (Rodas4 with its unrolled LU) runs as one kernel, several times faster for
small systems. XLA reads the option once, when JAX's CPU backend starts, for every program of the
process: so it is the application's choice (`use_one_kernel`; the `tribojax` command makes it for
itself), never made by importing or calling tribojax. Numbers do not depend on it beyond rounding:
Rodas4's factorisation is its own field (`Rodas4.lu`), not read from the environment.
"""

from __future__ import annotations

import os
import sys

XLA_HOIST_OPTION = "xla_cpu_small_while_loop_byte_threshold"
HOIST_FLAG = f"--xla_backend_extra_options={XLA_HOIST_OPTION}=1000000000"


def backend_started() -> bool:
    """Whether this process's JAX has started a backend (XLA options are read then)."""
    bridge = getattr(getattr(sys.modules.get("jax"), "_src", None), "xla_bridge", None)
    # no public query in jax 0.10: read (never changed) through its private module
    return bool(bridge is not None and bridge.backends_are_initialized())


def one_kernel_enabled() -> bool:
    """Whether this process's XLA_FLAGS raise the while-loop kernel size limit."""
    return XLA_HOIST_OPTION in os.environ.get("XLA_FLAGS", "")


def use_one_kernel() -> bool:
    """Ask XLA:CPU to compile whole while loops into one kernel (raises its loop-size limit in
    `XLA_FLAGS`, which applies to every program of the process, the application's own too).

    Call it before JAX's first computation. Returns True if the option is in effect (set now or
    before), False if the process's XLA_FLAGS already hold other backend extra options (which
    one flag cannot merge); raises RuntimeError if a JAX backend has already started.
    """
    if one_kernel_enabled():
        return True
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_backend_extra_options" in flags:
        return False
    if backend_started():
        raise RuntimeError(
            "use_one_kernel: JAX's backend has started and read XLA_FLAGS already; "
            "call it before the first JAX computation"
        )
    os.environ["XLA_FLAGS"] = f"{flags} {HOIST_FLAG}".strip()
    return True
