"""The float64 check, and the compilation cache set up at first use (`tribojax._cache`).

Slips of a nanometre against stiffnesses of 1e8 N/m lose all their digits in float32. `import
tribojax` turns `jax_enable_x64` on; a user who turns it off again is refused by every model
entry point (`ensure_x64`) instead of computing in float32.
"""

import jax

from ._cache import enable_cache

# x64 is not switched on again here: a user who switched it off is refused, not overruled
CACHE_DIR = enable_cache(jax.config)


def ensure_x64() -> None:
    """Raise `RuntimeError` if JAX has been switched back to 32-bit floats."""
    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "tribojax needs float64 but jax_enable_x64 is off (it was switched off after "
            "`import tribojax`). Run `jax.config.update('jax_enable_x64', True)` and try again."
        )
