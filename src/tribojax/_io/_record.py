"""`AbstractRecord`: what every user record answers, whatever its kind.

The records are one family in equinox's abstract/final pattern: this abstract base declares the
interface, and each kind is a final (never subclassed) frozen dataclass:

    SlipRun            kind "slip_run"            t, accel (drive), slip (response, m)
    HysteresisLoop     kind "loop"                t, u (drive), f (response, N)
    FrictionCurve      kind "friction_curve"      steady points: velocity, friction, scatter
    FrictionTransient  kind "friction_transient"  t, velocity, friction

Code that treats the kinds differently (the command line, `decimate_record`) asks the record
or looks its `kind` up in a table, never tests its class: a new kind is one new subclass.
"""

from __future__ import annotations

import abc
from typing import ClassVar

import numpy as np

from .._limits import SAMPLE_LIMITS
from ._files import implausible


class AbstractRecord(abc.ABC):
    """A user record: a measured (or synthetic) data set with the file it came from.

    Every concrete record sets the ClassVars
    - `kind`: its name in tables and in `fit.json` ("slip_run", "loop", "friction_curve",
      "friction_transient");
    - `description`: the kind in words, with its article ("a slip run"), for messages;
    - `reducible`: True for a time series of a drive and a response with a white-noise sd
      `noise_std` (None when unknown), which `tribojax.decimate_record` can reduce by block
      local quadratics; such a record also sets `response_unit` and implements `series` and
      `resampled`;
    and has `source` (the file or folder it came from, "<array>" when built in memory) and a
    length (`len`: its samples, or its points for a curve). The concrete records are final
    (module docstring): subclassing one raises TypeError.
    """

    kind: ClassVar[str]
    description: ClassVar[str]
    reducible: ClassVar[bool] = False
    response_unit: ClassVar[str | None] = None
    source: str

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        for base in cls.__mro__[1:]:  # a record class that sets its kind is concrete: final
            if issubclass(base, AbstractRecord) and "kind" in vars(base):
                raise TypeError(
                    f"{base.__name__} is a final record class and cannot be "
                    f"subclassed (subclass AbstractRecord for a new kind)"
                )

    def _set_series(self, names, *, time: str | None = None) -> None:
        """Replace the fields `names` of this frozen record by read-only float64 copies, checked:
        1-D, finite, of one length, within `SAMPLE_LIMITS` where the name has one, and `time`
        (one of them) strictly increasing. ValueError names the source, the field and the sample.
        """
        arrays = {}
        for name in names:
            x = np.array(getattr(self, name), dtype=np.float64)  # a copy: the caller's is kept
            if x.ndim != 1:
                raise ValueError(f"{self.source}: {name} must be 1-D, got shape {x.shape}")
            bad = np.flatnonzero(~np.isfinite(x))
            if bad.size:
                raise ValueError(f"{self.source}: {name}[{bad[0]}] is {x[bad[0]]} (must be finite)")
            far = implausible(x, name) if name in SAMPLE_LIMITS else None
            if far:
                raise ValueError(f"{self.source}: {name}[{far[0]}] = {far[1]}")
            x.setflags(write=False)
            arrays[name] = x
        if len({len(x) for x in arrays.values()}) > 1:
            raise ValueError(
                f"{self.source}: {', '.join(names)} must have the same length, got "
                f"{', '.join(str(len(x)) for x in arrays.values())}"
            )
        for name, x in arrays.items():
            object.__setattr__(self, name, x)
        object.__setattr__(self, "_length", len(arrays[names[0]]))
        t = arrays.get(time)
        steps = np.flatnonzero(np.diff(t) <= 0) if t is not None else ()
        if len(steps):
            i = steps[0] + 1
            raise ValueError(
                f"{self.source}: time is not strictly increasing at sample {i} "
                f"(t = {t[i]:g} s after {t[i - 1]:g} s)"
            )

    @abc.abstractmethod
    def __post_init__(self) -> None:
        """Check the fields and freeze the series (`_set_series`), raising ValueError that names
        the source and the field."""

    def __len__(self) -> int:
        """The number of samples (points, for a curve)."""
        return self._length

    def series(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t, drive, response): the channels a block reduction acts on (`reducible` records).

        Raises ValueError for a record that is not such a time series."""
        raise ValueError(f"{self.source}: {self.description} is not a drive/response series")

    def resampled(self, t, drive, response, *, noise_std):
        """The record with the channels of `series` replaced (reduced or cut samples) and the
        response's noise sd `noise_std`; the other fields kept (`reducible` records)."""
        raise ValueError(f"{self.source}: {self.description} is not a drive/response series")

    def extent(self) -> dict:
        """The conditions the record spans, {quantity: (min, max, unit)} (e.g. a loop's
        amplitude, force, velocity, normal load): what a model fitted on it has seen
        (`FittedModel.fitted_range`; `tribojax.predict` says where a record lies beyond it).
        Default: none."""
        return {}

    def cycle_times(self) -> np.ndarray | None:
        """Times of the upward mean-crossings of the drive (the starts of whole cycles) for a
        periodic record; None for a record without cycles."""
        return None


def extent_of(records) -> dict:
    """The conditions `records` span together: per quantity of their `extent` with one unit,
    [min, max] over the records and its unit ({quantity: {"min", "max", "unit"}})."""
    out: dict = {}
    for rec in records:
        for name, (lo, hi, unit) in rec.extent().items():
            have = out.setdefault(name, {"min": float(lo), "max": float(hi), "unit": unit})
            if have["unit"] == unit:
                have["min"], have["max"] = min(have["min"], float(lo)), max(have["max"], float(hi))
    return out


def metadata_extent(record, names) -> dict:
    """{name: (value, value, "N")} for each set metadata force `names` of `record` (a normal
    load, a band tension)."""
    values = {n: getattr(record, n, None) for n in names}
    return {n: (float(v), float(v), "N") for n, v in values.items() if v is not None}
