"""The one reader of TOML configuration files (`tribojax frf CONFIG.toml`).

`read_config(path, schema)` parses the file with the standard library's `tomllib` and checks
every entry against a schema {table: {key: kind}} with kinds "number", "int", "string",
"vector" (list of numbers), "matrix" (list of equal-length lists of numbers), and a trailing "?"
for optional keys. A table name ending in "[]" is an array of tables. Any problem raises
`DataFileError` naming the file, the table and key (and the line for TOML syntax errors).
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

from .._tables import DataFileError


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _check(kind: str, v) -> bool:
    if kind == "number":
        return _number(v)
    if kind == "int":
        return isinstance(v, int) and not isinstance(v, bool)
    if kind == "string":
        return isinstance(v, str)
    if kind == "vector":
        return isinstance(v, list) and len(v) > 0 and all(_number(x) for x in v)
    if kind == "matrix":
        return (
            isinstance(v, list)
            and len(v) > 0
            and all(isinstance(r, list) and len(r) == len(v[0]) for r in v)
            and all(_number(x) for r in v for x in r)
        )
    raise ValueError(f"unknown schema kind {kind!r}")


def _table(path, where: str, table, spec: dict) -> dict:
    if not isinstance(table, dict):
        raise DataFileError(f"{path}: [{where}] must be a table")
    for key in table:
        if key not in spec:
            raise DataFileError(
                f"{path}: [{where}] has an unknown key {key!r} (allowed: {', '.join(sorted(spec))})"
            )
    for key, kind in spec.items():
        optional = kind.endswith("?")
        kind = kind.rstrip("?")
        if key not in table:
            if not optional:
                raise DataFileError(f"{path}: [{where}] is missing the key {key!r} ({kind})")
            continue
        if not _check(kind, table[key]):
            raise DataFileError(f"{path}: [{where}] {key} = {table[key]!r} is not a valid {kind}")
    return table


def read_config(path, schema: dict) -> dict:
    """The checked contents of the TOML file `path` (see the module docstring)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFileError(f"{path}: no such file") from None
    except tomllib.TOMLDecodeError as err:
        raise DataFileError(f"{path}: not valid TOML: {err}") from None
    for name in data:
        if name.rstrip("[]") not in {k.rstrip("[]") for k in schema}:
            raise DataFileError(f"{path}: unknown table [{name}]")
    out = {}
    for name, spec in schema.items():
        if name.endswith("[]"):
            key = name[:-2]
            items = data.get(key, [])
            if not isinstance(items, list):
                raise DataFileError(f"{path}: [[{key}]] must be an array of tables")
            out[key] = [_table(path, f"{key} {i + 1}", t, spec) for i, t in enumerate(items)]
        elif name in data:
            out[name] = _table(path, name, data[name], spec)
        elif not all(k.endswith("?") for k in spec.values()):
            raise DataFileError(f"{path}: the table [{name}] is missing")
        else:
            out[name] = {}
    return out
