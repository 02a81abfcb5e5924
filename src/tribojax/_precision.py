"""The float64 check.

Slips of a nanometre against stiffnesses of 1e8 N/m lose all their digits in float32. `import
tribojax` turns `jax_enable_x64` on unless the user chose otherwise (`JAX_ENABLE_X64` set to a
false value); a process in which it is off is refused by every model entry point (`ensure_x64`)
instead of computing in float32.
"""

import jax


def ensure_x64() -> None:
    """Raise `RuntimeError` if JAX runs with 32-bit floats."""
    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "tribojax needs float64 but jax_enable_x64 is off (JAX_ENABLE_X64=0 in the "
            "environment, or switched off after `import tribojax`). Run "
            "`jax.config.update('jax_enable_x64', True)` (or unset JAX_ENABLE_X64) and try again."
        )
