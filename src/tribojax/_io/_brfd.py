"""Reader of the banded-rotary-friction-damper (brfd) JSON files, in SI units.

The files (ARTS-Laboratory, "Dataset-Friction-Damper-with-Backlash", CC BY-SA 4.0) hold a JSON
object whose key `data` is a matrix of rows `[time s, displacement in, friction force kip,
velocity in/s, actuator force 1 lbf, actuator force 2 lbf]` sampled at 1024 Hz; the other keys
name the units. The file name tells a (ramped) sinusoidal test from an arbitrary displacement
history (`brfd_test`) and gives the band tension (`brfd_band_tension`).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .._presets import INCH_M, KIP_N, LBF_N
from .._tables import DataFileError, read_json
from ._hysteresis_loop import HysteresisLoop

BRFD_UNITS = {"time units": "s", "displacement units": "in", "friction force units": "kip"}
BRFD_COLUMNS = 6  # time, displacement, friction force, velocity, two actuator forces
_SINE_NAME = re.compile(r"^(?P<f>[0-9.]+)Hz(?P<tension>[0-9.]+)lbtension(?P<A>[0-9.]+)amplitude$")
_HISTORY_NAME = re.compile(r"^earthquake_.+_(?P<tension>[0-9.]+)lb$")


def brfd_band_tension(path) -> float | None:
    """The band tension (N) in a brfd file name, `<f>Hz<T>lbtension<A>amplitude.json` or
    `earthquake_<name>_<T>lb.json` (T in lbf); None when the name gives none."""
    stem = Path(path).stem
    m = _SINE_NAME.match(stem) or _HISTORY_NAME.match(stem)
    return None if m is None else float(m["tension"]) * LBF_N


def brfd_test(path) -> dict | None:
    """Nominal frequency (Hz), amplitude (m) and band tension (lbf) from a sinusoidal test's file
    name `<f>Hz<T>lbtension<A>amplitude.json`; None for any other name (a history)."""
    m = _SINE_NAME.match(Path(path).stem)
    if m is None:
        return None
    return {
        "frequency_Hz": float(m["f"]),
        "amplitude_m": float(m["A"]) * INCH_M,
        "band_tension_lbf": float(m["tension"]),
    }


def _line_of_row(text: str, row: int) -> int:
    """1-based line of the `row`-th (0-based) inner list of the `data` matrix in a JSON text."""
    start = text.find('"data"')
    depth, seen = 0, -1
    for pos in range(max(start, 0), len(text)):
        ch = text[pos]
        if ch == "[":
            depth += 1
            if depth == 2:
                seen += 1
                if seen == row:
                    return text.count("\n", 0, pos) + 1
        elif ch == "]":
            depth -= 1
    return text.count("\n") + 1


def read_brfd(path, band_tension=None) -> HysteresisLoop:
    """Load one brfd test as a `HysteresisLoop` in SI units (s, m, N).

    Displacement in → m (× 0.0254), friction force kip → N (× 4448.2216); the velocity and the
    actuator forces are not kept. A sinusoidal test gets its nominal `frequency` (Hz) from the
    file name and `periodic=True`; an earthquake history `periodic=False`. `band_tension` (N):
    the band's set tension, read from either file-name pattern (`brfd_band_tension`) unless
    given; None when neither gives it. The rig's artefacts (force quantisation of
    3.56 N, actuator start-up, a displacement offset) are left in the data.

    Raises DataFileError naming the file and the line for invalid or truncated JSON, missing
    keys, units other than in/kip/s, a row that is not 6 finite numbers, or time that does not
    increase.
    """
    path = Path(path)
    obj, text = read_json(path)
    if not isinstance(obj, dict) or "data" not in obj:
        raise DataFileError(f"{path}, line 1: expected a JSON object with a 'data' matrix")
    for key, unit in BRFD_UNITS.items():
        if key in obj and obj[key] != unit:
            raise DataFileError(f"{path}, line 1: {key!r} is {obj[key]!r}, expected {unit!r}")
    data = obj["data"]
    if not isinstance(data, list) or len(data) < 3:
        raise DataFileError(f"{path}, line 1: 'data' must be a matrix of at least 3 rows")
    for i, row in enumerate(data):
        ok = isinstance(row, list) and len(row) == BRFD_COLUMNS
        ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) for x in row)
        if not ok or not np.all(np.isfinite(row)):
            raise DataFileError(
                f"{path}, line {_line_of_row(text, i)}: data row {i} is {str(row)[:80]}; "
                f"expected {BRFD_COLUMNS} finite numbers [time s, displacement in, force kip, "
                "velocity in/s, actuator forces lbf]"
            )
    arr = np.asarray(data, dtype=np.float64)
    t, u, f = arr[:, 0], arr[:, 1] * INCH_M, arr[:, 2] * KIP_N
    steps = np.flatnonzero(np.diff(t) <= 0)
    if steps.size:
        i = int(steps[0]) + 1
        raise DataFileError(
            f"{path}, line {_line_of_row(text, i)}: time {t[i]} s of data row {i} does not increase"
        )
    test = brfd_test(path)
    try:
        return HysteresisLoop(
            t,
            u,
            f,
            source=str(path),
            frequency=None if test is None else test["frequency_Hz"],
            periodic=test is not None,
            band_tension=brfd_band_tension(path) if band_tension is None else band_tension,
        )
    except ValueError as err:
        raise DataFileError(str(err)) from None
