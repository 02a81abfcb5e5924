"""The records of a batch: paths, folders and globs expanded to record paths, each given a
unique output name (its stem)."""

from __future__ import annotations

import glob
from pathlib import Path

from .._io._epos import is_epos

# files the single commands write: never taken for records when a folder is expanded
OUTPUT_NAMES = {"fit.json", "discovery.json", "prediction.json", "batch.json"}
RECORD_SUFFIXES = {".csv", ".json", ".txt"}
_GLOB = set("*?[")


class BatchUsageError(ValueError):
    """A batch request that names nothing to run (a missing path, an empty glob)."""


def _is_epos_folder(folder: Path) -> bool:
    """A folder of EPOS exports only: one friction curve (the single commands read it so)."""
    files = [p for p in folder.iterdir() if p.is_file() and not p.name.startswith(".")]
    return bool(files) and all(is_epos(p) for p in files)


def _records_in(folder: Path, skip: Path | None) -> list[Path]:
    if _is_epos_folder(folder):
        return [folder]
    found = []
    for p in sorted(folder.iterdir()):
        if p.name.startswith(".") or (skip is not None and p.resolve() == skip):
            continue
        if p.is_dir():
            found += _records_in(p, skip)
        elif p.suffix.lower() in RECORD_SUFFIXES and p.name not in OUTPUT_NAMES:
            sidecar = p.suffix.lower() == ".json" and p.with_suffix(".csv").exists()
            if not sidecar and (p.suffix.lower() != ".txt" or is_epos(p)):
                found.append(p)
    return found


def expand_records(given, out=None) -> list[Path]:
    """The record paths of `given` (paths, folders, globs), in the order given, each once.

    A folder of EPOS exports is one record (a friction curve); another folder stands for the
    records in it and its subfolders: CSV files, JSON files that are not a CSV's sidecar,
    EPOS exports, but not the files the commands write nor the output folder `out`. A glob
    (`*`, `?`, `[`) is expanded in sorted order. BatchUsageError for a path that does not
    exist, a glob that matches nothing, or no record at all."""
    skip = Path(out).resolve() if out is not None else None
    paths: list[Path] = []
    for item in map(str, given):
        if _GLOB & set(item):
            matches = sorted(glob.glob(item, recursive=True))
            if not matches:
                raise BatchUsageError(f"{item}: the pattern matches no file")
        else:
            matches = [item]
        for m in map(Path, matches):
            if not m.exists():
                raise BatchUsageError(f"{m}: no such file or folder")
            paths += _records_in(m, skip) if m.is_dir() else [m]
    seen, unique = set(), []
    for p in paths:
        if p.resolve() not in seen:
            seen.add(p.resolve())
            unique.append(p)
    if not unique:
        raise BatchUsageError(f"no record found in {', '.join(map(str, given))}")
    return unique


def unique_stems(paths) -> list[str]:
    """An output name per record: its stem (a folder's name), lengthened by its parent
    folders ("driveNo1__steady_state__0.096kg") where two records would share it."""
    parts = [
        Path(p).resolve().with_suffix("").parts if Path(p).is_file() else Path(p).resolve().parts
        for p in paths
    ]
    names = ["__".join(q[-1:]) for q in parts]
    depth = 1
    while len(set(names)) < len(names):
        depth += 1
        clash = {n for n in names if names.count(n) > 1}
        names = ["__".join(q[-depth:]) if n in clash else n for n, q in zip(names, parts)]
        if depth > max(map(len, parts)):
            break
    counts: dict[str, int] = {}
    out = []
    for n in names:  # the same name left (a file and its stem-twin): numbered
        counts[n] = counts.get(n, 0) + 1
        out.append(n if names.count(n) == 1 else f"{n}__{counts[n]}")
    return out
