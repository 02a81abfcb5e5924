"""JAX's persistent compilation cache, on by default for tribojax's programs.

A command pays tracing and XLA compilation in every new process; the persistent cache keeps the
compiled programs on disk so that the second run of the same fit skips XLA compilation (tracing
is still paid). Set when tribojax is first imported, and only if the user has not chosen a JAX
cache themselves (`jax_compilation_cache_dir` or `JAX_COMPILATION_CACHE_DIR`).
`TRIBOJAX_CACHE=off` (or 0/no/false) leaves JAX's settings alone; `TRIBOJAX_CACHE_DIR` chooses
the folder (default: the platform's user cache folder, `cache_dir`). Programs that compile in
`MIN_COMPILE_S` or more are kept: all of them (docs/performance.md, The compilation cache, has
the folders and says why). Traced programs are kept beside it (`tribojax._export`). A program
holding a host callback (an `equinox.error_if` that raises, `throw=True`) is never cached by
jax 0.10: the fit engine traces its programs without one (`tribojax._checks.failures_as_nan`).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

MIN_COMPILE_S = 0.0
OFF = ("off", "0", "no", "false")


def cache_dir() -> Path | None:
    """The folder tribojax asks JAX to cache compiled programs in, or None when `TRIBOJAX_CACHE`
    turns the cache off."""
    if os.environ.get("TRIBOJAX_CACHE", "").strip().lower() in OFF:
        return None
    chosen = os.environ.get("TRIBOJAX_CACHE_DIR", "").strip()
    if chosen:
        return Path(chosen).expanduser()
    home = Path.home()
    if sys.platform == "darwin":
        base = home / "Library" / "Caches" / "tribojax"
    elif os.name == "nt":
        local = Path(os.environ.get("LOCALAPPDATA", home / "AppData" / "Local"))
        base = local / "tribojax" / "cache"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME", "") or home / ".cache") / "tribojax"
    return base / "jax"


def enable_cache(config) -> Path | None:
    """Point `config` (`jax.config`) at `cache_dir()` unless the user set a JAX cache folder or
    turned ours off; returns the folder in use by tribojax's setting (None if not set here).
    A folder that cannot be created leaves the cache off."""
    if config.jax_compilation_cache_dir or os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return None
    folder = cache_dir()
    if folder is None:
        return None
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(folder, os.W_OK):
        return None
    config.update("jax_compilation_cache_dir", str(folder))
    config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_S)
    return folder
