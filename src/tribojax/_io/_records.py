"""`read_record`: load a user record, chosen by its format (detected, or named by `format`)."""

from __future__ import annotations

from pathlib import Path

from .._limits import RECORD_FORMATS as RECORD_FORMATS
from .._tables import DataFileError, separator_hint
from ._brfd import read_brfd
from ._epos import is_epos
from ._files import csv_header, data_line_number
from ._friction_curve import (
    CURVE_COLUMNS,
    TRANSIENT_COLUMNS,
    FrictionCurve,
    FrictionTransient,
    read_epos_steady,
    read_epos_transient,
    read_friction_curve,
)
from ._hysteresis_loop import LOOP_COLUMNS, LOOP_FILE_COLUMNS, HysteresisLoop, read_loop
from ._slip_run import SLIP_COLUMNS, SlipRun, read_slip_run

_READERS = {
    "slip": read_slip_run,
    "loop": read_loop,
    "brfd": read_brfd,
    "epos_steady": read_epos_steady,
    "epos": read_epos_transient,
    "curve": read_friction_curve,
}


def detect_format(path) -> str:
    """The record format of `path` (one of `RECORD_FORMATS`): a folder → "epos_steady" (EPOS
    steady-state exports), `*.json` → "brfd", a `Key:;value` first line → "epos" (a transient),
    else by the CSV header (slip run, loop, friction curve or transient)."""
    path = Path(path)
    if path.is_dir():
        return "epos_steady"
    if path.suffix.lower() == ".json":
        return "brfd"
    if is_epos(path):
        return "epos"
    fields = csv_header(path)
    header = set(fields)
    if set(SLIP_COLUMNS) <= header:
        return "slip"
    if set(LOOP_FILE_COLUMNS) <= header or set(LOOP_COLUMNS) <= header:
        return "loop"
    if set(CURVE_COLUMNS) <= header or set(TRANSIENT_COLUMNS) <= header:
        return "curve"
    raise DataFileError(
        f"{path}, line {data_line_number(path, -1)}: header {list(fields)} is neither a slip "
        f"run ({','.join(SLIP_COLUMNS)}), a loop ({','.join(LOOP_FILE_COLUMNS)}, or legacy "
        f"{','.join(LOOP_COLUMNS)}), a friction curve ({','.join(CURVE_COLUMNS)}) nor a "
        f"transient ({','.join(TRANSIENT_COLUMNS)}){separator_hint(','.join(fields))}"
    )


def read_record(
    path, format: str | None = None
) -> SlipRun | HysteresisLoop | FrictionCurve | FrictionTransient:
    """Load a user record in SI units, its format detected (`detect_format`) or given.

    format: "slip" (`read_slip_run`), "loop" (`tribojax.read_loop`), "brfd" (the friction-damper
    JSON, `read_brfd`), "epos_steady" (a folder of EPOS steady-state exports → one
    `FrictionCurve`), "epos" (one EPOS export → `FrictionTransient`), "curve" (a friction-curve or
    transient CSV with its units sidecar). Anything else: ValueError listing these.
    """
    if format is None:
        format = detect_format(path)
    if format not in _READERS:
        raise ValueError(f"format = {format!r} is not one of {list(RECORD_FORMATS)}")
    if format == "epos_steady" and not Path(path).is_dir():
        raise DataFileError(f"{path}: format 'epos_steady' needs a folder of EPOS exports")
    return _READERS[format](path)
