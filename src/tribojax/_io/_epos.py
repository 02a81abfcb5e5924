"""Reader of the EPOS data-recorder export (semicolon separated) of the screw-drive rig.

Format (Maxon EPOS Studio): a variable number of `Key:;value` header lines, a line of column names
(`;Velocity actual value averaged;Torque actual value averaged`), a units line `ms;rpm;%`, then one
line per sample. Time ms → s, velocity rpm → rad/s, torque % of the motor's nominal torque → N m.

A spreadsheet's re-save is read as far as it can be (docs/data.md, "Your measurements");
lines that look edited are listed in `EposExport.flagged` and in one `DataFileWarning`.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

from .._presets import EPOS_NOMINAL_TORQUE_NM, RPM_RAD_S
from .._tables import DataFileError, DataFileWarning, read_text

EPOS_UNITS = ("ms", "rpm", "%")
_SCALE = (1e-3, RPM_RAD_S, EPOS_NOMINAL_TORQUE_NM / 100.0)


@dataclasses.dataclass(frozen=True)
class EposExport:
    """One EPOS export in SI: time t (s), motor velocity (rad/s), motor torque (N m); `header`
    holds the `Key:` lines as text, `source` the file and `units_line` its line number;
    `flagged` the lines that look edited ("line N: why")."""

    t: np.ndarray
    velocity: np.ndarray
    torque: np.ndarray
    header: dict
    source: str
    units_line: int
    flagged: tuple = ()


def _fields(raw: str) -> list[str]:
    """A line's `;` fields without quotes, surrounding blanks or a spreadsheet's trailing empty
    fields (`;;`, `,,`)."""
    return [f.strip().strip('"').strip() for f in raw.rstrip(" \t\r,;").split(";")]


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if np.isfinite(value) else None


def _decimals(text: str) -> int:
    return len(text.split(".", 1)[1]) if "." in text else 0


def is_epos(path) -> bool:
    """Whether `path` looks like an EPOS export (a `Key:;value` first line, quoted or not)."""
    try:
        first = _fields(read_text(path).lstrip().split("\n", 1)[0])
    except DataFileError:
        return False
    return len(first) > 1 and first[0].endswith(":")


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
        fields = _fields(raw)
        if tuple(fields[:3]) == EPOS_UNITS:
            units_at = lineno
            break
        if lineno > 1 and len(fields) >= 3 and all(_number(f) is not None for f in fields[:3]):
            raise DataFileError(
                f"{path}, line {lineno}: a sample before the units line {';'.join(EPOS_UNITS)}; "
                f"line {lineno - 1} should be it but reads {lines[lineno - 2][:60]!r}"
            )
        if ":" in fields[0] and len(fields) > 1:
            header[fields[0].rstrip(":")] = ";".join(fields[1:])
    if units_at is None:
        raise DataFileError(
            f"{path}, line {len(lines)}: no units line {';'.join(EPOS_UNITS)} found (expected an "
            "EPOS export: Key:;value lines, column names, units, samples)"
        )
    rows, texts, flagged = [], [], []
    for lineno in range(units_at + 1, len(lines) + 1):
        fields = _fields(lines[lineno - 1])
        if fields == [""]:
            continue
        values = [_number(f) for f in fields[:3]]
        if len(values) != 3 or None in values:
            raise DataFileError(
                f"{path}, line {lineno}: {lines[lineno - 1].strip()[:60]!r} is not three numbers "
                f"({';'.join(EPOS_UNITS)}); a truncated or edited file?"
            )
        extra = [f for f in fields[3:] if f]
        if extra:
            flagged.append(f"line {lineno}: extra field {';'.join(extra)[:40]!r} ignored")
        rows.append((lineno, values))
        texts.append(fields[:3])
    if len(rows) < 2:
        raise DataFileError(f"{path}, line {units_at}: fewer than two samples after the units line")
    flagged += _looks_edited(rows, texts, header)
    arr = np.asarray([v for _, v in rows]) * np.asarray(_SCALE)
    steps = np.flatnonzero(np.diff(arr[:, 0]) <= 0)
    if steps.size:
        lineno = rows[steps[0] + 1][0]
        raise DataFileError(f"{path}, line {lineno}: time does not increase")
    header["samples read"] = str(len(rows))
    if flagged:
        more = f"; and {len(flagged) - 5} more" if len(flagged) > 5 else ""
        warnings.warn(
            f"{path}: {len(flagged)} line(s) look edited, read as written: "
            f"{'; '.join(flagged[:5])}{more}",
            DataFileWarning,
            stacklevel=2,
        )
    return EposExport(arr[:, 0], arr[:, 1], arr[:, 2], header, str(path), units_at, tuple(flagged))


def _looks_edited(rows, texts, header) -> list[str]:
    """Lines whose values are written unlike the export writes them: more decimals than the
    column's usual count, or a time off the `Sampling period` grid (ms) of the header."""
    out = []
    # the exporter drops trailing zeros ('-35' for -35.0), so only more decimals is an edit
    usual = [Counter(_decimals(t[c]) for t in texts).most_common(1)[0][0] for c in range(3)]
    try:
        period = float(header.get("Sampling period", "").split(";")[0])
    except ValueError:
        period = 0.0
    t0 = rows[0][1][0]
    for (lineno, values), text in zip(rows, texts):
        odd = [
            f"{EPOS_UNITS[c]} value {text[c]!r} has {_decimals(text[c])} decimals, the "
            f"column {usual[c]}"
            for c in range(3)
            if _decimals(text[c]) > usual[c]
        ]
        if period > 0 and abs((values[0] - t0) / period - round((values[0] - t0) / period)) > 1e-3:
            odd.append(f"time {text[0]} ms is off the {period:g} ms sampling grid")
        if odd:
            out.append(f"line {lineno}: " + ", ".join(odd))
    return out
