"""Argument types of the `tribojax` subcommands: each refuses a bad value naming the option,
the value and the allowed range (standard library and `tribojax._presets` only: no JAX)."""

from __future__ import annotations

import argparse
import math

from .. import _presets as P


def positive_float(flag: str):
    """An argparse type: a finite number > 0, refused naming `flag`, the value and the range."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(
                f"{flag} = {text!r} is outside the allowed range (0, inf)"
            )
        return value

    return parse


def band_tension(text: str) -> float:
    """A band tension for `--band-tension`: N, or lbf with an `lb` suffix (`30lb`)."""
    raw = text.strip().lower()
    lbf = raw.endswith(("lbf", "lb"))
    number = raw.removesuffix("lbf").removesuffix("lb").strip() if lbf else raw.removesuffix("n")
    try:
        value = float(number) * (P.LBF_N if lbf else 1.0)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(
            f"--band-tension = {text!r} is outside the allowed range: "
            "a tension >= 0 in N (0: a slack band), or in lbf as '30lb'"
        )
    return value


def whole_number(name: str):
    """An argparse type: a whole number >= 1, refused naming `name` and the value."""

    def parse(text: str) -> int:
        if not (text.strip().isdigit() and int(text) >= 1):
            raise argparse.ArgumentTypeError(
                f"{name} = {text!r} is outside the allowed range: a whole number >= 1"
            )
        return int(text)

    return parse
