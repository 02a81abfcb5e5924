"""Reader of the EPOS data-recorder export (semicolon separated) of the screw-drive rig.

Format (Maxon EPOS Studio): a variable number of `Key:;value` header lines, a line of column names
(`;Velocity actual value averaged;Torque actual value averaged`), a units line `ms;rpm;%`, then one
line per sample. Time ms → s, velocity rpm → rad/s, torque % of the motor's nominal torque → N m.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from .._presets import EPOS_NOMINAL_TORQUE_NM, RPM_RAD_S
from .._tables import DataFileError, read_text

EPOS_UNITS = ("ms", "rpm", "%")
_SCALE = (1e-3, RPM_RAD_S, EPOS_NOMINAL_TORQUE_NM / 100.0)


@dataclasses.dataclass(frozen=True)
class EposExport:
    """One EPOS export in SI: time t (s), motor velocity (rad/s), motor torque (N m); `header`
    holds the `Key:` lines as text, `source` the file and `units_line` its line number."""

    t: np.ndarray
    velocity: np.ndarray
    torque: np.ndarray
    header: dict
    source: str
    units_line: int


def is_epos(path) -> bool:
    """Whether `path` looks like an EPOS export (a `Key:;value` first line)."""
    try:
        first = read_text(path).lstrip().split("\n", 1)[0]
    except DataFileError:
        return False
    return ":;" in first


def read_epos(path) -> EposExport:
    """Parse an EPOS export into SI arrays (see the module docstring).

    Raises DataFileError naming the file and the line for: no `ms;rpm;%` units line, a sample
    line that is not three numbers (a truncated last line included), time that does not
    increase, or no samples at all. Fewer samples than the header's `Recorded samples` are
    accepted here (a transient cut short is still a transient); a steady-state folder refuses
    them (`read_epos_steady`). The count read is kept in `header` ("samples read").
    """
    path = Path(path)
    lines = read_text(path).splitlines()
    header, units_at = {}, None
    for lineno, raw in enumerate(lines, start=1):
        fields = [f.strip().strip('"') for f in raw.split(";")]
        if tuple(fields[:3]) == EPOS_UNITS:
            units_at = lineno
            break
        if ":" in fields[0] and len(fields) > 1:
            header[fields[0].rstrip(":").strip('"')] = ";".join(fields[1:])
    if units_at is None:
        raise DataFileError(
            f"{path}, line {len(lines)}: no units line {';'.join(EPOS_UNITS)} found (expected an "
            "EPOS export: Key:;value lines, column names, units, samples)"
        )
    rows = []
    for lineno in range(units_at + 1, len(lines) + 1):
        raw = lines[lineno - 1].strip()
        if not raw:
            continue
        fields = raw.split(";")
        try:
            values = [float(x) for x in fields]
        except ValueError:
            values = []
        if len(values) != 3 or not np.all(np.isfinite(values)):
            raise DataFileError(
                f"{path}, line {lineno}: {raw[:60]!r} is not three numbers "
                f"({';'.join(EPOS_UNITS)}); a truncated or edited file?"
            )
        rows.append((lineno, values))
    if len(rows) < 2:
        raise DataFileError(f"{path}, line {units_at}: fewer than two samples after the units line")
    arr = np.asarray([v for _, v in rows]) * np.asarray(_SCALE)
    steps = np.flatnonzero(np.diff(arr[:, 0]) <= 0)
    if steps.size:
        lineno = rows[steps[0] + 1][0]
        raise DataFileError(f"{path}, line {lineno}: time does not increase")
    header["samples read"] = str(len(rows))
    return EposExport(arr[:, 0], arr[:, 1], arr[:, 2], header, str(path), units_at)
