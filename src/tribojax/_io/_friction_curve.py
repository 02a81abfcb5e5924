"""Steady friction curves and friction transients: records, the EPOS folder reader and files.

Units are carried with the record (a sidecar on disk); a folder of EPOS steady-state exports,
one file per commanded speed, reads as one curve (`read_epos_steady`).
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path
from typing import ClassVar, final

import numpy as np

from .._tables import DataFileError, read_json, read_table
from ._epos import read_epos
from ._files import csv_header, sidecar_path, write_record_files
from ._record import AbstractRecord

CURVE_COLUMNS = ("velocity", "friction", "friction_scatter", "velocity_scatter", "samples")
TRANSIENT_COLUMNS = ("time_s", "velocity", "friction")
_UNIT_KEYS = ("velocity_unit", "friction_unit")


def _si_units() -> dict:
    return {"velocity_unit": "m/s", "friction_unit": "N"}


@final
@dataclasses.dataclass(frozen=True)
class FrictionCurve(AbstractRecord):
    """Steady friction versus velocity: per point the mean `velocity`, the mean `friction`, the
    standard deviation of the friction samples `friction_scatter` (> 0) and of the velocity
    samples `velocity_scatter` (>= 0), and the number of independent `samples` (>= 1) averaged:
    the count for independent samples, fewer for correlated ones (`effective_samples`).

    `units` {"velocity_unit", "friction_unit"} (SI, e.g. "rad/s" and "N m" for a motor, "m/s"
    and "N" for a slider); `source` the file or folder it came from. The friction has the sign
    of the velocity for a dissipative contact. Construction checks shapes, finiteness, the
    scatter's sign and at least two points (ValueError).
    """

    velocity: np.ndarray
    friction: np.ndarray
    friction_scatter: np.ndarray
    velocity_scatter: np.ndarray
    samples: np.ndarray
    units: dict = dataclasses.field(default_factory=_si_units)
    source: str = "<array>"

    kind: ClassVar[str] = "friction_curve"
    description: ClassVar[str] = "a friction curve"

    def __post_init__(self):
        self._set_series(CURVE_COLUMNS)
        if len(self.velocity) < 2:
            raise ValueError(f"{self.source}: a friction curve needs at least two points")
        if np.any(self.friction_scatter <= 0) or np.any(self.velocity_scatter < 0):
            raise ValueError(f"{self.source}: friction_scatter must be > 0, velocity_scatter >= 0")
        if np.any(self.samples < 1):
            raise ValueError(f"{self.source}: samples must be >= 1")
        if set(self.units) != set(_UNIT_KEYS):
            raise ValueError(f"{self.source}: units must have the keys {list(_UNIT_KEYS)}")

    def extent(self) -> dict:
        """The range of |velocity| and the peak |friction|, in the curve's units
        (`AbstractRecord.extent`)."""
        v, f = np.abs(self.velocity), float(np.max(np.abs(self.friction)))
        return {
            "velocity": (float(v.min()), float(v.max()), self.units["velocity_unit"]),
            "friction": (f, f, self.units["friction_unit"]),
        }

    @property
    def friction_error(self) -> np.ndarray:
        """Standard error of each mean friction, scatter/√samples (same unit as friction)."""
        return self.friction_scatter / np.sqrt(self.samples)

    def direction(self, sign: int) -> FrictionCurve:
        """The points whose velocity has the sign of `sign` (+1 or −1)."""
        keep = np.sign(self.velocity) == np.sign(sign)
        return dataclasses.replace(self, **{c: getattr(self, c)[keep] for c in CURVE_COLUMNS})


@final
@dataclasses.dataclass(frozen=True)
class FrictionTransient(AbstractRecord):
    """A measured friction transient: a start–stop run (rest, one direction, rest, the other)."""

    kind: ClassVar[str] = "friction_transient"
    description: ClassVar[str] = "a friction transient"

    t: np.ndarray
    """Sample times, s, strictly increasing."""
    velocity: np.ndarray
    """Velocity samples, in `units["velocity_unit"]`."""
    friction: np.ndarray
    """Friction samples, in `units["friction_unit"]`."""
    units: dict = dataclasses.field(default_factory=_si_units)
    """{"velocity_unit", "friction_unit"}, as for `FrictionCurve`."""
    source: str = "<array>"

    def __post_init__(self):
        self._set_series(("t", "velocity", "friction"), time="t")


EPOS_UNITS_SI = {"velocity_unit": "rad/s", "friction_unit": "N m"}
"""Units of an EPOS export converted to SI: velocity rad/s, torque N m."""

BATCHES = 10
"""Batch count for the batch-means standard error of a correlated record (`effective_samples`)."""


def effective_samples(x) -> float:
    """The number of independent samples a correlated series `x` is worth for its mean: n_eff =
    s² / SE², with s the samples' standard deviation and SE the batch-means standard error of the
    mean (the series cut into `BATCHES` equal consecutive batches; SE = std of the batch means /
    √BATCHES). Clipped to [1, len(x)]: never more than the count (an anticorrelated or short
    series keeps n). Why: docs/data.md, "Correlated samples"."""
    x = np.asarray(x, dtype=float)
    n = len(x)
    if n < 2 * BATCHES:
        return float(n)
    m = n // BATCHES
    means = x[: m * BATCHES].reshape(BATCHES, m).mean(axis=1)
    se2 = np.var(means, ddof=1) / BATCHES
    s2 = np.var(x, ddof=1)
    return float(np.clip(s2 / se2, 1.0, n)) if se2 > 0 else float(n)


def read_epos_steady(folder) -> FrictionCurve:
    """One steady friction curve from a folder of EPOS steady-state exports (`*.csv`, one per
    commanded speed): each file gives one point, the means and scatters of its velocity (rad/s)
    and torque (N m) samples, and the torque's `effective_samples` (the samples are correlated).
    The direction is the measured velocity's sign (not the file name). Points are sorted by
    velocity. DataFileError (naming the file and line) for a bad export, a file that is not one
    steady point (fewer samples than its header announces, or a velocity that reverses:
    `_check_steady_point`), two files with the same samples, or a folder without exports."""
    folder = Path(folder)
    files = sorted(folder.glob("*.csv"))
    if not files:
        raise DataFileError(f"{folder}: no EPOS exports (*.csv) in this folder")
    rows, seen = [], {}
    for path in files:
        ex = read_epos(path)
        _check_steady_point(path, ex)
        key = hashlib.sha256(ex.velocity.tobytes() + ex.torque.tobytes()).hexdigest()
        if key in seen:
            raise DataFileError(
                f"{path}: the same samples as {seen[key]} (a duplicate export, "
                "e.g. a copy of a file?); keep one of them"
            )
        seen[key] = path.name
        scatter = float(np.std(ex.torque, ddof=1))
        if not scatter > 0:
            raise DataFileError(f"{path}, line {ex.units_line + 1}: the torque is constant")
        rows.append(
            (
                float(np.mean(ex.velocity)),
                float(np.mean(ex.torque)),
                scatter,
                float(np.std(ex.velocity, ddof=1)),
                effective_samples(ex.torque),
            )
        )
    rows.sort()
    cols = dict(zip(CURVE_COLUMNS, np.asarray(rows).T))
    return FrictionCurve(**cols, units=dict(EPOS_UNITS_SI), source=str(folder))


STEADY_OPPOSITE_MAX = 0.01  # share of samples against the mean's direction in a steady point


def _check_steady_point(path, ex) -> None:
    """DataFileError unless the export `ex` is one steady point: every sample its header
    announces (`Recorded samples`) is there, and the velocity keeps one direction (at most
    `STEADY_OPPOSITE_MAX` of the samples against the mean's; a start-stop run reverses)."""
    announced = ex.header.get("Recorded samples")
    n = ex.t.size
    if announced is not None:
        try:
            count = int(float(announced.split(";")[0]))
        except ValueError:
            why = f"{path}: 'Recorded samples' is {announced!r}, not a count"
            raise DataFileError(why) from None
        if count != n:
            raise DataFileError(
                f"{path}, line {ex.units_line + n}: {n} samples, but the header "
                f"announces {count} (a cut or edited export?)"
            )
    direction = np.sign(np.mean(ex.velocity))
    against = float(np.mean(np.sign(ex.velocity) == -direction)) if direction else 1.0
    if against > STEADY_OPPOSITE_MAX:
        raise DataFileError(
            f"{path}: not a steady point: {100 * against:.0f} % of the samples "
            "move against the mean direction (a start-stop export?); a "
            "steady-state folder holds one commanded speed per file"
        )


def read_epos_transient(path) -> FrictionTransient:
    """A start–stop EPOS export as a `FrictionTransient` (t s, velocity rad/s, torque N m)."""
    ex = read_epos(path)
    return FrictionTransient(ex.t, ex.velocity, ex.torque, dict(EPOS_UNITS_SI), str(path))


def _read_units(path) -> dict:
    side = sidecar_path(path)
    if not side.is_file():
        raise DataFileError(f"{side}: sidecar not found; it must give {list(_UNIT_KEYS)}")
    data, _ = read_json(side)
    if not isinstance(data, dict) or not all(isinstance(data.get(k), str) for k in _UNIT_KEYS):
        raise DataFileError(f"{side}, line 1: needs text values for {list(_UNIT_KEYS)}")
    return {k: data[k] for k in _UNIT_KEYS}


def write_friction_curve(
    curve: FrictionCurve, path, comment="", *, provenance=None, overwrite=False
) -> None:
    """Write a curve as CSV `velocity,friction,friction_scatter,velocity_scatter,samples` plus a
    sidecar {"velocity_unit", "friction_unit", provenance...}, atomically; refuses to replace
    existing files unless `overwrite`."""
    cols = [getattr(curve, c) for c in CURVE_COLUMNS]
    write_record_files(
        path,
        CURVE_COLUMNS,
        cols,
        {**curve.units, **(provenance or {})},
        overwrite=overwrite,
        comment=comment,
        digits=12,
    )


def write_friction_transient(
    tr: FrictionTransient, path, comment="", *, provenance=None, overwrite=False
) -> None:
    """Write a transient as CSV `time_s,velocity,friction` plus the units sidecar, atomically."""
    write_record_files(
        path,
        TRANSIENT_COLUMNS,
        [tr.t, tr.velocity, tr.friction],
        {**tr.units, **(provenance or {})},
        overwrite=overwrite,
        comment=comment,
        digits=12,
    )


def read_friction_curve(path) -> FrictionCurve | FrictionTransient:
    """Load a curve CSV (`write_friction_curve`) or a transient CSV (`write_friction_transient`)
    with its units sidecar; DataFileError naming file and line for anything malformed."""
    path = Path(path)
    transient = set(TRANSIENT_COLUMNS) <= set(csv_header(path))
    cols = TRANSIENT_COLUMNS if transient else CURVE_COLUMNS
    table = read_table(path, columns=cols)
    units = _read_units(path)
    try:
        if transient:
            return FrictionTransient(*(table[c] for c in cols), units=units, source=str(path))
        return FrictionCurve(**{c: table[c] for c in cols}, units=units, source=str(path))
    except ValueError as err:
        raise DataFileError(str(err)) from None
