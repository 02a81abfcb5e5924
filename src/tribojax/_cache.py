"""JAX's persistent compilation cache and tribojax's stored traces, by explicit choice.

Importing or calling tribojax configures no cache. An application opts in with
`use_compilation_cache(folder)`; the `tribojax` command does so for its own process
(`TRIBOJAX_CACHE_DIR`, `TRIBOJAX_CACHE=off`). Everything stored goes inside the chosen folder:
`folder/jax` (JAX's compiled programs, unless the process already chose a JAX cache folder) and
`folder/export` (tribojax's traced programs, `tribojax._export`). docs/performance.md (The
compilation cache) has the reasons and why a program with a host callback is never cached.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

OFF = ("off", "0", "no", "false")
READ_ERROR = "Error reading persistent compilation cache entry"
"""The start of JAX's warning for a cache entry it cannot read (it compiles the program again
but never rewrites the entry: the warning comes back on every run until the entry goes)."""
_FOLDER: list[Path] = []  # the folder chosen by `use_compilation_cache` in this process


def default_cache_dir() -> Path | None:
    """The folder the `tribojax` command caches in: `TRIBOJAX_CACHE_DIR`, else the platform's
    user cache folder (`~/.cache/tribojax` on Linux); None when `TRIBOJAX_CACHE` is off."""
    if os.environ.get("TRIBOJAX_CACHE", "").strip().lower() in OFF:
        return None
    chosen = os.environ.get("TRIBOJAX_CACHE_DIR", "").strip()
    if chosen:
        return Path(chosen).expanduser()
    home = Path.home()
    if sys.platform == "darwin":
        return home / "Library" / "Caches" / "tribojax"
    if os.name == "nt":
        return Path(os.environ.get("LOCALAPPDATA", home / "AppData" / "Local")) / "tribojax"
    return Path(os.environ.get("XDG_CACHE_HOME", "") or home / ".cache") / "tribojax"


def use_compilation_cache(folder=None) -> Path | None:
    """Keep compiled programs and tribojax's traces on disk, so that a new process skips their
    tracing and compilation. An explicit choice of the application (a script, a notebook, the
    `tribojax` command); tribojax never makes it by itself.

    Args:
        folder: where to store them (default `default_cache_dir()`). JAX's programs go to
            `folder/jax` unless this process already set `jax_compilation_cache_dir`, and then
            JAX's minimum compile time for caching is set to 0 s unless
            `JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS` is set; traces go to `folder/export`.

    Returns:
        The folder in use, or None when no folder is given and `TRIBOJAX_CACHE` is off, or the
        folder cannot be created or written (the cache then stays off).
    """
    import jax

    folder = default_cache_dir() if folder is None else Path(folder).expanduser()
    if folder is None:
        return None
    try:
        (folder / "jax").mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(folder, os.W_OK):
        return None
    if not (jax.config.jax_compilation_cache_dir or os.environ.get("JAX_COMPILATION_CACHE_DIR")):
        jax.config.update("jax_compilation_cache_dir", str(folder / "jax"))
        if "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS" not in os.environ:
            jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    _FOLDER[:] = [folder]
    return folder


def export_dir() -> Path | None:
    """The folder of stored traces (`use_compilation_cache`), or None when none was chosen."""
    return _FOLDER[0] / "export" if _FOLDER else None


def repair_compilation_cache(folder=None) -> list[Path]:
    """Remove the entries of JAX's compilation cache in `folder` (default: the folder this
    process uses, `jax_compilation_cache_dir`) that cannot be read back: a truncated or
    corrupted file fails its compression's checksum. JAX warns on every read of such an entry
    and never replaces it; once removed, the program is stored again the next time it is
    compiled. Returns the entries removed. The `tribojax` command calls it after a run in
    which JAX reported an unreadable entry."""
    import jax

    try:
        from jax._src.compilation_cache import decompress_executable  # (private: may move)
    except ImportError:
        return []
    folder = folder if folder is not None else jax.config.jax_compilation_cache_dir
    if not folder or not Path(folder).is_dir():
        return []
    removed = []
    for entry in sorted(Path(folder).glob("*-cache")):
        try:
            ok = len(decompress_executable(entry.read_bytes())) > 8
        except OSError:
            continue  # unreadable for another reason (permissions): not ours to delete
        except Exception:  # noqa: BLE001  (zstd and zlib raise their own errors)
            ok = False
        if not ok:
            entry.unlink(missing_ok=True)
            entry.with_name(entry.name[: -len("-cache")] + "-atime").unlink(missing_ok=True)
            removed.append(entry)
    return removed
