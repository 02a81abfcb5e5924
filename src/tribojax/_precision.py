"""float64 switch.

tribojax works in float64 throughout: slips of a nanometre against stiffnesses of 1e8 N/m lose
all their digits in float32. Importing `tribojax` therefore turns on `jax_enable_x64` (the one
side effect of the import, documented in the README, with the compilation cache of
`tribojax._cache`). If a user turns it off again, every model
entry point refuses to run instead of silently computing in float32.
"""

import jax

from ._cache import enable_cache

# x64 was switched on by `import tribojax` (tribojax/__init__.py); not again here, so that a user
# who switched it off after that import is refused by `ensure_x64`, not silently overruled
CACHE_DIR = enable_cache(jax.config)  # the persistent compilation cache (`tribojax._cache`)


def ensure_x64() -> None:
    """Raise `RuntimeError` if JAX has been switched back to 32-bit floats."""
    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "tribojax needs float64 but jax_enable_x64 is off (it was switched off after "
            "`import tribojax`). Run `jax.config.update('jax_enable_x64', True)` and try again."
        )
