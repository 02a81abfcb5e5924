"""JAX's persistent compilation cache, on by default for tribojax's programs.

Set when tribojax is first used, unless the user chose a JAX cache (`jax_compilation_cache_dir`
or `JAX_COMPILATION_CACHE_DIR`). `TRIBOJAX_CACHE=off` (or 0/no/false) leaves JAX's settings
alone; `TRIBOJAX_CACHE_DIR` chooses the folder (`cache_dir`). Every program is kept
(`MIN_COMPILE_S`). docs/performance.md (The compilation cache) has the folders, the reasons and
why a program with a host callback is never cached (`tribojax._checks.failures_as_nan`); traced
programs are kept beside it (`tribojax._export`).
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
