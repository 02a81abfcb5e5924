"""Bundled published data and a validating CSV reader (the physics and `_io` read through it).

Data live in the repository's top-level `data/` folder; wheels ship a copy as `tribojax/_data`
(hatch force-include), so the loaders work from any working directory and from a non-editable
install. Every table is a CSV with `#` comment lines (source, units), one header line and rows of
numbers; a first text column is allowed where declared.
"""

from __future__ import annotations

import csv
import json
import math
from importlib import resources
from pathlib import Path

import numpy as np


class DataFileError(ValueError):
    """A data file that cannot be used; the message names the file, the line and the reason."""


class DataFileWarning(UserWarning):
    """A data file read in full, with lines that look edited (by hand or by a spreadsheet); the
    message names the file and the lines."""


class _DuplicateKey(ValueError):
    pass


def _unique_keys(pairs) -> dict:
    out = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


def read_json(path):
    """(the parsed JSON of `path`, its text): the one JSON reader of data, sidecar and model
    files (`read_text`'s encodings). DataFileError naming the file, and the line, for text that
    is not JSON, is nested too deeply to be a tribojax file, or repeats a key in one object."""
    text = read_text(path)
    try:
        return json.loads(text, object_pairs_hook=_unique_keys), text
    except _DuplicateKey as err:
        raise DataFileError(
            f"{path}: the key {err.args[0]!r} appears twice in one object (which value is meant?)"
        ) from None
    except json.JSONDecodeError as err:
        raise DataFileError(
            f"{path}, line {err.lineno}: not valid JSON ({err.msg} at column "
            f"{err.colno}; a truncated file?)"
        ) from None
    except RecursionError:
        raise DataFileError(f"{path}: JSON nested too deeply to be a tribojax file") from None


def read_text(path) -> str:
    """The text of a UTF-8 file (a leading byte-order mark is dropped); DataFileError naming the
    file, and the line of the first byte that is not UTF-8, when it cannot be read."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 16)  # checked before the rest is read (a large binary file)
            if head[:4] in (b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff"):
                raise DataFileError(
                    f"{path}: UTF-32 text (byte-order mark); save the file as UTF-8"
                )
            if head[:2] in (b"\xff\xfe", b"\xfe\xff"):
                raise DataFileError(
                    f"{path}: UTF-16 text (byte-order mark); save the file as UTF-8"
                )
            if b"\x00" in head:
                line = head[: head.index(b"\x00")].count(b"\n") + 1
                raise DataFileError(
                    f"{path}, line {line}: a NUL byte (a binary file, or "
                    "UTF-16 text without a byte-order mark); save it as UTF-8"
                )
            raw = head + f.read()
    except OSError as err:
        raise DataFileError(f"{path}: cannot be read ({err.strerror or err})") from err
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        line = raw[: err.start].count(b"\n") + 1
        raise DataFileError(
            f"{path}, line {line}: byte 0x{raw[err.start]:02x} is not UTF-8 (Windows-1252 or "
            "Latin-1 text?); save the file as UTF-8"
        ) from None


def data_dir() -> Path:
    """Folder of the bundled data: the installed copy, else the source tree's `data/`."""
    installed = resources.files("tribojax") / "_data"
    if installed.is_dir():
        return Path(str(installed))
    source = Path(__file__).resolve().parents[2] / "data"
    if source.is_dir():
        return source
    raise FileNotFoundError(
        "tribojax's bundled data were not found (neither tribojax/_data nor the source tree's "
        "data/); reinstall the package with `pip install .`"
    )


def read_table(path, *, columns=None, text_columns=()) -> dict[str, np.ndarray]:
    """Read a numeric CSV table, refusing anything malformed.

    Args:
        path: the file.
        columns: required column names (in any order); None accepts any header.
        text_columns: columns kept as strings; all others must be finite numbers.
    Returns:
        A dict column -> 1-D array (float64, or str for text columns).
    Raises:
        DataFileError naming the file, the line number and what is wrong.
    """
    path = Path(path)
    lines = read_text(path).splitlines()
    header, rows = None, []
    for lineno, raw in enumerate(lines, start=1):
        text = raw.strip()
        if not text or text.startswith("#"):
            continue
        try:
            fields = [f.strip() for f in next(csv.reader([text]))]
        except csv.Error as err:
            raise DataFileError(f"{path}, line {lineno}: {err}") from None
        if header is None:
            header = fields
            if len(set(header)) != len(header) or "" in header:
                raise DataFileError(f"{path}, line {lineno}: header has empty or repeated names")
            missing = [c for c in (columns or ()) if c not in header]
            if missing:
                raise DataFileError(
                    f"{path}, line {lineno}: missing column(s) {missing}; header "
                    f"is {header}{separator_hint(text)}"
                )
            continue
        if len(fields) != len(header):
            raise DataFileError(
                f"{path}, line {lineno}: {len(fields)} fields, the header has {len(header)}"
            )
        row = []
        for name, value in zip(header, fields):
            if name in text_columns:
                row.append(value)
                continue
            try:
                number = float(value)
            except ValueError:
                raise DataFileError(
                    f"{path}, line {lineno}: column {name!r} holds {value!r}, not a number"
                ) from None
            if not math.isfinite(number):
                raise DataFileError(f"{path}, line {lineno}: column {name!r} is {value}")
            row.append(number)
        rows.append(row)
    if header is None:
        raise DataFileError(f"{path}: no header line")
    if not rows:
        raise DataFileError(f"{path}: no data rows")
    return {
        name: np.asarray([r[j] for r in rows], dtype=str if name in text_columns else np.float64)
        for j, name in enumerate(header)
    }


def separator_hint(header: str) -> str:
    """A hint when a header line looks separated by something other than commas."""
    for sep, name in ((";", "semicolons"), ("\t", "tabs")):
        if sep in header and header.count(sep) >= header.count(","):
            return (
                f" (it looks separated by {name}: tribojax reads comma-separated values with "
                "a decimal point; export as CSV with ',' between fields and '.' in numbers)"
            )
    return ""


_WANG2022 = {
    1: ("table1_surfaces.csv", ("surface", "D", "G_m"), ("surface",)),
    2: (
        "table2_materials.csv",
        ("material", "E_Pa", "shear_modulus_Pa", "H_Pa", "yield_strength_Pa", "nu"),
        ("material",),
    ),
    3: (
        "table3_contact.csv",
        ("vacuum_kPa", "load_N", "Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m", "zmax_nm"),
        (),
    ),
    **{
        n: (f"table{n}_slip.csv", ("vacuum_kPa", "theory_nm", "measured_nm", "error_percent"), ())
        for n in (4, 5, 6, 7)
    },
}


def wang2022_table(number: int) -> dict[str, np.ndarray]:
    """wang2022 Table `number` (1–7) as published, from the bundled `data/wang2022/`."""
    if number not in _WANG2022:
        raise ValueError(f"wang2022 has Tables 1-7; got table {number!r}")
    name, cols, text = _WANG2022[number]
    return read_table(data_dir() / "wang2022" / name, columns=cols, text_columns=text)


_WU2015 = {
    1: (
        "table1_conditions.csv",
        ("condition", "material", "radius_mm", "normal_force_N", "frequency_Hz"),
        ("material",),
    ),
}


def wu2015_table(number: int = 1) -> dict[str, np.ndarray]:
    """wu2015 Table `number` (only Table 1, the experimental conditions) from `data/wu2015/`.

    Table 1: one row per condition (1–3) and normal force: material, contact radius (mm), normal
    force (N) and exciting frequency (Hz). Eq 7's fits are `tribojax.wu2015_eq7()`.
    """
    if number not in _WU2015:
        raise ValueError(f"wu2015 has one table, Table 1; got table {number!r}")
    name, cols, text = _WU2015[number]
    return read_table(data_dir() / "wu2015" / name, columns=cols, text_columns=text)
