"""`read_record`: load a user record, a slip run or a hysteresis loop, chosen by its CSV header."""

from __future__ import annotations

from pathlib import Path

from ._files import csv_header, data_line_number
from ._loop import LOOP_COLUMNS, LOOP_FILE_COLUMNS, HysteresisLoop, read_loop
from ._slip_run import SLIP_COLUMNS, SlipRun, read_slip_run
from ._tables import DataFileError


def read_record(path) -> SlipRun | HysteresisLoop:
    """Load a user record, a `SlipRun` or a `HysteresisLoop`, chosen by the CSV header.

    `time_s,stage_accel_m_s2,slip_m` → `read_slip_run`; `time_s,displacement_m,force_N` or the
    legacy `t_s,u_m,f_N` → `tribojax.read_loop`. Anything else: DataFileError listing these.
    """
    path = Path(path)
    fields = csv_header(path)
    header = set(fields)
    if set(SLIP_COLUMNS) <= header:
        return read_slip_run(path)
    if set(LOOP_FILE_COLUMNS) <= header or set(LOOP_COLUMNS) <= header:
        return read_loop(path)
    raise DataFileError(
        f"{path}, line {data_line_number(path, -1)}: header {list(fields)} is neither a slip "
        f"run ({','.join(SLIP_COLUMNS)}) nor a loop ({','.join(LOOP_FILE_COLUMNS)}, or legacy "
        f"{','.join(LOOP_COLUMNS)})"
    )
