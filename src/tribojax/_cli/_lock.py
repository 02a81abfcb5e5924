"""The output folder's lock: one tribojax run writes a result at a time.

The lock file holds the writing process's id, its start time (Linux: `/proc/PID/stat`) and the
host. A lock whose process no longer runs, or whose id now belongs to another process (started at
another time: the id was reused), is taken over with a note; one from another host is held. A
bare process id (no start time) is taken over when that process is not a tribojax run, an
empty or unreadable stamp when older than `WRITE_GRACE_S`.
"""

from __future__ import annotations

import os
import socket
import time
from pathlib import Path


def _start_time(pid: int) -> str:
    """The start time of process `pid` in clock ticks since boot ("-" where unknown)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return "-"
    return stat.rsplit(")", 1)[-1].split()[19]  # field 22, counted after the command name


def lock_stamp() -> str:
    """This process's line for a lock file."""
    return f"{os.getpid()} {_start_time(os.getpid())} {socket.gethostname()}\n"


def _stale(lock: Path) -> int | None:
    """The PID of `lock`'s run when that run is over (its process gone, or its id reused by a
    process started at another time), else None (held, unreadable, or another host's)."""
    try:
        pid_s, *rest = lock.read_text().split()
        pid = int(pid_s)
    except OSError:
        return None  # unreadable: treat as held
    except ValueError:  # empty or not a stamp: being written now, or left by a killed writer
        return 0 if _age(lock) > WRITE_GRACE_S else None
    if not rest and not _is_tribojax(pid):  # a bare process id (an older stamp, by hand)
        return pid
    started, host = (rest + ["-", ""])[:2]
    if host and host != socket.gethostname():
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return pid
    except OSError:  # exists (another user's process): held unless its id was reused
        pass
    now = _start_time(pid)
    return pid if started != "-" and now != "-" and now != started else None


WRITE_GRACE_S = 10.0
"""A lock without a stamp older than this (s) was left by a writer killed before it wrote one."""


def _age(lock: Path) -> float:
    try:
        return time.time() - lock.stat().st_mtime
    except OSError:
        return 0.0


def _is_tribojax(pid: int) -> bool:
    """Whether process `pid` may be a tribojax run (its command line names tribojax; True where
    it cannot be read)."""
    try:
        return b"tribojax" in Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return True


class LockHeld(Exception):
    """Another run holds the lock (the message says which and what to do)."""


def take_lock(lock: Path, target: Path) -> tuple[int, str | None]:
    """Create `lock` exclusively: (its file descriptor, a note when a lock whose run is over — a
    run killed with SIGKILL, a crash, its process id since reused — was taken over). LockHeld
    while another run holds it; OSError when the folder cannot be written."""
    note = None
    for attempt in range(2):
        try:
            return os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644), note
        except FileExistsError:
            pid = _stale(lock) if attempt == 0 else None
            if pid is None:
                raise LockHeld(
                    f"another tribojax run is writing {target} (lock file {lock}); wait for it, "
                    "choose another --out, or delete the lock if no run is active"
                ) from None
            who = f"(process {pid})" if pid else "(no process recorded)"
            note = f"taking over the lock {lock}: its run {who} is no longer running"
            lock.unlink(missing_ok=True)
    raise AssertionError("unreachable")
