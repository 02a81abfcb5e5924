"""User data records: slip runs (wang2022-style rig), their files, synthetic runs and loaders.

A slip run is what the reticle rig of wang2022 (Section 4, Figure 9) measures: the stage
acceleration a(t) and the slip Δx = x_stage − x_body of the body it carries, sampled at times t.
On disk it is a CSV with a sidecar `<stem>.json` (`read_slip_run`, `write_slip_run`).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import ClassVar, final

import numpy as np

from .._dynamics._profiles import AbstractProfile, MeasuredProfile, TrapezoidProfile
from .._dynamics._slip import simulate_slip
from .._presets import WANG2022_RETICLE_MASS_KG
from .._tables import DataFileError, read_table
from ._files import (
    data_line_number,
    implausible,
    positive_or_none,
    read_sidecar,
    write_record_files,
)
from ._record import AbstractRecord, metadata_extent

SLIP_COLUMNS = ("time_s", "stage_accel_m_s2", "slip_m")

_SLIP_SIDECAR = {"mass_kg": True, "normal_load_N": False, "noise_std_m": False}
# the run's metadata: field -> (sidecar key, unit)
_METADATA = {
    "mass": ("mass_kg", "kg"),
    "normal_load": ("normal_load_N", "N"),
    "noise_std": ("noise_std_m", "m"),
}


@final
@dataclasses.dataclass(frozen=True)
class SlipRun(AbstractRecord):
    """A measured or synthetic slip run: t (s), stage acceleration (m/s²), slip Δx (m).

    `mass` (kg) is the driven body's mass; `normal_load` (N) the normal load of the contact, if
    known (needed to fit surface parameters across loads); `noise_std` (m) the standard deviation
    of the slip noise, None when unknown (a fit then estimates it from its residuals).

    `drive` (keyword-only, optional) is the stage acceleration profile the model is driven by
    when it is not the samples' own: a record reduced by `tribojax.decimate_record` keeps the
    full-resolution drive of the original, so that reducing the slip does not smooth the drive
    (a velocity error of the drive is permanent in the slip). `write_slip_run` writes the
    sampled `accel`, not `drive`.

    Construction validates: 1-D float64 arrays of equal length ≥ 2, all finite, t strictly
    increasing with t[0] ≥ 0 (the model starts from rest at t = 0), mass > 0, normal_load and
    noise_std > 0 when given. A violation raises ValueError naming `source` and the sample.
    """

    t: np.ndarray
    accel: np.ndarray
    slip: np.ndarray
    mass: float
    normal_load: float | None = None
    noise_std: float | None = None
    source: str = "<array>"
    drive: AbstractProfile | None = dataclasses.field(
        default=None, kw_only=True, compare=False, repr=False
    )

    kind: ClassVar[str] = "slip_run"
    description: ClassVar[str] = "a slip run"
    reducible: ClassVar[bool] = True
    response_unit: ClassVar[str] = "m"

    def __post_init__(self):
        src = self.source
        if self.drive is not None and not isinstance(self.drive, AbstractProfile):
            raise ValueError(f"{src}: drive must be an acceleration profile, got {self.drive!r}")
        self._set_series(("t", "accel", "slip"), time="t")
        if len(self.t) < 2:
            raise ValueError(f"{src}: a slip run needs at least 2 samples, got {len(self.t)}")
        if self.t[0] < 0:
            raise ValueError(f"{src}: t[0] = {self.t[0]:g} s must be >= 0 (the run starts at rest)")
        for name, (_, unit) in _METADATA.items():
            value = positive_or_none(getattr(self, name), name, src, unit, required=name == "mass")
            object.__setattr__(self, name, value)

    def series(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t, accel, slip): the stage acceleration drives, the slip responds."""
        return self.t, self.accel, self.slip

    def resampled(self, t, drive, response, *, noise_std) -> SlipRun:
        """The run on new samples (t, accel, slip) with slip noise sd `noise_std`, still driven
        by this run's full-resolution `profile` (the class docstring's `drive`)."""
        return dataclasses.replace(
            self, t=t, accel=drive, slip=response, noise_std=noise_std, drive=self.profile()
        )

    def extent(self) -> dict:
        """The stage acceleration's peak |a| (m/s²), the drive force m·|a| it asks of the
        contact (N) and the normal load (N) when known (`AbstractRecord.extent`)."""
        a = float(np.max(np.abs(self.accel)))
        return {
            "acceleration": (a, a, "m/s²"),
            "drive_force": (self.mass * a, self.mass * a, "N"),
            **metadata_extent(self, ("normal_load",)),
        }

    def profile(self) -> MeasuredProfile:
        """The run's drive: its stage acceleration a(t) (m/s²), `MeasuredProfile.from_samples`
        (linear between the samples, stopped at its few kinks); a record with a `drive` returns
        that instead. The one definition used by `simulate_run`, `fit_slip_run` and discovery.
        """
        if self.drive is not None:
            return self.drive
        return MeasuredProfile.from_samples(self.t, self.accel)


# ---------------------------------------------------------------------------------------------
# slip runs on disk


def read_slip_run(path) -> SlipRun:
    """Load a slip run: CSV `time_s,stage_accel_m_s2,slip_m` (SI) plus sidecar `<stem>.json`.

    The sidecar holds {"mass_kg" (required, > 0), "normal_load_N", "noise_std_m" (optional,
    > 0)}. Raises DataFileError naming the file, the line and the reason for: a missing column,
    a non-numeric/NaN/inf entry, a row of the wrong length, time that does not strictly
    increase or starts below 0, fewer than 2 rows, and a missing, malformed or invalid sidecar.
    """
    path = Path(path)
    table = read_table(path, columns=SLIP_COLUMNS)
    t = table["time_s"]
    if t[0] < 0:
        raise DataFileError(
            f"{path}, line {data_line_number(path, 0)}: time_s = {t[0]:g} must be >= 0"
        )
    steps = np.flatnonzero(np.diff(t) <= 0)
    if steps.size:
        i = steps[0] + 1
        raise DataFileError(
            f"{path}, line {data_line_number(path, i)}: time_s = {t[i]:g} does "
            f"not increase (previous row {t[i - 1]:g})"
        )
    if len(t) < 2:
        raise DataFileError(f"{path}: a slip run needs at least 2 data rows, got {len(t)}")
    for column, name in (("stage_accel_m_s2", "accel"), ("slip_m", "slip")):
        far = implausible(table[column], name)
        if far:
            lineno = data_line_number(path, far[0])
            raise DataFileError(f"{path}, line {lineno}: {column} = {far[1]}")
    side = read_sidecar(path, _SLIP_SIDECAR, dict(_METADATA.values()))
    return SlipRun(
        t,
        table["stage_accel_m_s2"],
        table["slip_m"],
        source=str(path),
        **{name: side[key] for name, (key, _) in _METADATA.items()},
    )


def write_slip_run(run: SlipRun, path, *, overwrite: bool = False, comment: str = "") -> None:
    """Write `run` as CSV (`time_s,stage_accel_m_s2,slip_m`, 17 digits) plus sidecar JSON.

    Refuses (FileExistsError) if the CSV or its sidecar exists, unless `overwrite=True`; both are
    written through temporary files, so a failure leaves no partial file.
    """
    side = {
        key: getattr(run, name)
        for name, (key, _) in _METADATA.items()
        if getattr(run, name) is not None
    }
    write_record_files(
        path, SLIP_COLUMNS, (run.t, run.accel, run.slip), side, overwrite=overwrite, comment=comment
    )


# ---------------------------------------------------------------------------------------------
# model of a run


def synthetic_slip_run(
    element,
    profile=None,
    mass=WANG2022_RETICLE_MASS_KG,
    *,
    n: int = 2301,
    t_end: float = 2.3,
    noise: float = 0.0,
    seed: int = 0,
    normal_load=None,
) -> SlipRun:
    """A slip run of `element` under `profile` (default wang2022's trapezoid), with noise.

    Simulates `simulate_slip` (wang2022 Eq 27, consistent reading) at n equally spaced samples on
    [0, t_end], samples the profile's acceleration there and adds N(0, noise²) (m) to the slip
    with `numpy.random.default_rng(seed)`. `noise_std` of the run is `noise` (None if 0).

    A model of the run re-builds a(t) by linear interpolation of the samples; it equals the
    profile only if the profile's kinks lie on the sample grid (for the default trapezoid: a
    spacing dividing 5 ms, e.g. n = 2301, 461 or 231 over 2.3 s).
    """
    profile = TrapezoidProfile() if profile is None else profile
    n = int(n)
    if n < 2:
        raise ValueError(f"n = {n} samples is outside the allowed range [2, inf)")
    noise = float(noise)
    if not (math.isfinite(noise) and noise >= 0):
        raise ValueError(f"noise = {noise:g} m is outside the allowed range [0, inf)")
    t = np.linspace(0.0, float(t_end), n)
    sol = simulate_slip(element, profile, mass, ts=t, t_end=float(t_end))
    accel = np.asarray(profile.acceleration(t))
    rng = np.random.default_rng(seed)
    slip = np.asarray(sol.slip) + noise * rng.standard_normal(n)
    return SlipRun(
        t,
        accel,
        slip,
        mass=float(mass),
        normal_load=normal_load,
        noise_std=noise if noise > 0 else None,
        source=f"<synthetic seed {seed}>",
    )


def simulate_run(element, run: SlipRun, **kw):
    """The model's slip on the run's own times (a `SlipSolution`): `simulate_slip` from rest at
    t = 0, driven by `SlipRun.profile` unless a `profile` keyword is given; other keywords go to
    `simulate_slip`."""
    profile = kw.pop("profile", None) or run.profile()
    return simulate_slip(element, profile, run.mass, ts=run.t, t_end=float(run.t[-1]), **kw)
