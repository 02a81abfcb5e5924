"""Helpers shared by the subcommands: JSON output, error exit, output checks."""

from __future__ import annotations

import sys
from pathlib import Path

from .._io._files import sidecar_path, write_json_atomic

__all__ = ["error", "refused_outputs", "write_json_atomic"]

BAD_INPUT = 2  # exit status for malformed input or a refused output


def error(message: str, err=None) -> int:
    """Print `error: message` to stderr (or `err`) and return the bad-input exit status 2."""
    print(f"error: {message}", file=sys.stderr if err is None else err)
    return BAD_INPUT


def refused_outputs(src, targets, *, force: bool) -> str | None:
    """Why the output files `targets` may not be written, or None if they may.

    An output may never be the input record `src` or its sidecar; the first target (the result
    JSON) is not replaced unless `force`.
    """
    inputs = {Path(src).resolve(), sidecar_path(src).resolve()}
    for target in targets:
        if Path(target).resolve() in inputs:
            return (
                f"{target} is an input file: writing it would overwrite the input {src}; choose "
                "another --out"
            )
    first = Path(targets[0])
    if first.exists() and not force:
        return f"{first} exists; refusing to overwrite it (use --force or another --out)"
    return None
