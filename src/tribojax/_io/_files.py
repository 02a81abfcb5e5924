"""Record files: atomic text and JSON writes, sidecars, CSV headers and line-numbered errors.

Used by the records (`SlipRun`, `HysteresisLoop`) and by the command line, so that every file the
package writes goes through one temporary-file-then-rename path and an existing user file is
never replaced unless asked. Every loader error is a `DataFileError` naming the file, the line and
the reason.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from .._limits import SAMPLE_FLOORS, SAMPLE_LIMITS
from .._tables import DataFileError, read_json, read_text


def positive_or_none(value, name: str, source: str, unit: str, *, required=False, zero=False):
    """A finite float > 0 (≥ 0 with `zero`; or None where allowed); ValueError naming the field
    otherwise."""
    if value is None:
        if required:
            raise ValueError(f"{source}: {name} is required ({unit})")
        return None
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ValueError(f"{source}: {name} must be a number ({unit}), got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and (value > 0 or zero and value == 0)):
        low = "[0" if zero else "(0"
        raise ValueError(
            f"{source}: {name} = {value:g} {unit} is outside the allowed range {low}, inf)"
        )
    return value


# ---------------------------------------------------------------------------------------------
# atomic writes


def write_text_atomic(path, text: str, *, exclusive: bool = False) -> None:
    """Write `text` (UTF-8) to `path` via a temporary file, so a failure leaves no partial file.

    The file gets the permissions of a normally created file (0666 less the umask, 0644
    usually). With `exclusive`, an existing `path` is never replaced (FileExistsError), even by a
    writer that finishes at the same time: the temporary file is hard-linked into place.
    """
    path = Path(path)
    if path.is_dir():
        raise IsADirectoryError(21, "is a folder, not a file name", str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(text)
        except OSError as err:  # e.g. a full disk: the error names the file meant
            raise OSError(err.errno, err.strerror or str(err), str(path)) from err
        mask = os.umask(0)  # the umask is read by setting it: put it back at once
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        if exclusive:
            try:
                os.link(tmp, path)
            except FileExistsError:
                why = "exists (written by another run meanwhile?); refusing to overwrite it"
                raise FileExistsError(17, why, str(path)) from None
        else:
            os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


def _json_default(obj):
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"cannot serialise {type(obj).__name__}")


def _finite(obj):
    """Replace NaN/inf by None so the output is strict JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


def write_json_atomic(path, data, *, exclusive: bool = False) -> None:
    """Write strict JSON (NaN/inf as null, NumPy values as numbers) to `path`, atomically
    (`exclusive`: never replace an existing file, see `write_text_atomic`)."""
    text = json.dumps(_finite(data), indent=2, default=_json_default, allow_nan=False)
    write_text_atomic(path, text + "\n", exclusive=exclusive)


# ---------------------------------------------------------------------------------------------
# sidecars


def sidecar_path(path) -> Path:
    """The sidecar `<stem>.json` beside a record's CSV."""
    return Path(path).with_suffix(".json")


def _key_line(text: str, key: str) -> int | None:
    """1-based line of the first occurrence of `"key"` in a JSON text (for error messages)."""
    needle = json.dumps(key)
    return next((n for n, line in enumerate(text.splitlines(), start=1) if needle in line), None)


def sidecar_text(csv_path, key: str, allowed: tuple[str, ...]) -> str | None:
    """The text value of `key` in the sidecar of `csv_path` (None if the sidecar or the key is
    absent); DataFileError naming the sidecar and the line for a value outside `allowed`."""
    side = sidecar_path(csv_path)
    if not side.is_file():
        return None
    try:
        data, text = read_json(side)
    except DataFileError:
        return None  # read_sidecar reports it
    if not isinstance(data, dict) or key not in data:
        return None
    if data[key] not in allowed:
        raise DataFileError(
            f"{side}, line {_key_line(text, key)}: {key!r} = {data[key]!r} is not one of "
            f"{list(allowed)}"
        )
    return data[key]


def read_sidecar(
    csv_path,
    schema: dict[str, bool],
    units: dict[str, str],
    *,
    required=True,
    text_keys=(),
    zero_keys=(),
):
    """Read and validate the sidecar of `csv_path`: a JSON object of positive numbers (0 allowed
    for `zero_keys`).

    Args:
        schema: key -> whether it is required. Keys outside it (and "comment") are refused.
        units: key -> unit, for messages.
        required: whether the sidecar file itself must exist.
        text_keys: keys allowed besides the schema, with text values (read by `sidecar_text`).
    Returns:
        dict key -> float (absent optional keys are None), or None when the file is absent and
        not required.
    Raises:
        DataFileError naming the sidecar, the line and the reason.
    """
    side = sidecar_path(csv_path)
    if not side.is_file():
        if not required:
            return None
        need = ", ".join(f'"{k}"' for k, req in schema.items() if req)
        raise DataFileError(
            f"{side}: sidecar not found; {Path(csv_path).name} needs a JSON file beside it with "
            f"{need} (optional: {', '.join(k for k, req in schema.items() if not req)})"
        )
    data, text = read_json(side)
    if not isinstance(data, dict):
        raise DataFileError(
            f"{side}, line 1: must be a JSON object {{...}}, got {type(data).__name__}"
        )
    unknown = [k for k in data if k not in schema and k != "comment" and k not in text_keys]
    if unknown:
        raise DataFileError(
            f"{side}, line {_key_line(text, unknown[0])}: unknown key {unknown[0]!r}; "
            f"allowed keys are {sorted(schema) + ['comment']}"
        )
    out = {}
    for key, req in schema.items():
        where = f"{side}, line {_key_line(text, key)}" if key in data else f"{side}"
        value = data.get(key)
        if value is None and key in data:
            value = "null"  # an explicit null is not a number
        try:
            zero = key in zero_keys
            out[key] = positive_or_none(
                value, f"{key!r}", where, units[key], required=req, zero=zero
            )
        except ValueError as err:
            raise DataFileError(str(err)) from None
    return out


# ---------------------------------------------------------------------------------------------
# record CSVs


def write_record_files(
    path, header, columns, sidecar: dict | None, *, overwrite, comment, digits: int = 17
):
    """Write a CSV (values with `digits` significant digits) and its sidecar atomically; refuse
    existing files unless `overwrite`."""
    path = Path(path)
    targets = [path] + ([sidecar_path(path)] if sidecar is not None else [])
    if path.suffix.lower() != ".csv":
        raise ValueError(f"{path}: a record file must end in .csv (its sidecar is <stem>.json)")
    existing = [] if overwrite else [p for p in targets if p.exists()]
    if existing:
        raise FileExistsError(
            f"{existing[0]} exists; refusing to overwrite it (pass "
            "overwrite=True, or choose another name)"
        )
    lines = [f"# {c}" for c in comment.splitlines()] + [",".join(header)]
    lines += [",".join(f"{v:.{digits}g}" for v in row) for row in zip(*columns)]
    if sidecar is not None:
        write_text_atomic(targets[1], json.dumps(sidecar, indent=2) + "\n")
    write_text_atomic(path, "\n".join(lines) + "\n")


def data_line_number(path, row: int) -> int:
    """1-based line number of data row `row` (0-based) of a CSV with comments and a header."""
    seen = -1  # the header is row -1
    for lineno, raw in enumerate(read_text(path).splitlines(), start=1):
        text = raw.strip()
        if not text or text.startswith("#"):
            continue
        if seen == row:
            return lineno
        seen += 1
    return -1


def csv_header(path) -> tuple[str, ...]:
    """The header fields of a CSV (first line that is neither blank nor a `#` comment)."""
    path = Path(path)
    for raw in read_text(path).splitlines():
        text = raw.strip()
        if text and not text.startswith("#"):
            return tuple(f.strip() for f in text.split(","))
    raise DataFileError(f"{path}: no header line")


def implausible(x, name: str) -> tuple[int, str] | None:
    """(index, message) of the first sample of `x` beyond `SAMPLE_LIMITS[name]`, or of its
    largest when every sample is below `SAMPLE_FLOORS[name]` (all zero allowed); else None
    (`name`: the record's field, "u", "f", "slip" or "accel")."""
    limit, unit = SAMPLE_LIMITS[name]
    size = np.abs(np.asarray(x, dtype=float))
    big = np.flatnonzero(size > limit)
    if big.size:
        i = int(big[0])
        return i, (
            f"{x[i]:g} {unit} is outside the plausible range [-{limit:g}, {limit:g}] "
            f"{unit} (SI units: a unit or export error?)"
        )
    floor = SAMPLE_FLOORS[name]
    if size.size and 0.0 < size.max() < floor:  # every sample tiny (all zero is allowed)
        i = int(np.argmax(size))
        return i, (
            f"{x[i]:g} {unit} is the record's largest value, below the plausible "
            f"{floor:g} {unit} (SI units: a unit or export error?)"
        )
    return None
