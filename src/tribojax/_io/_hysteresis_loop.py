"""Measured hysteresis loops (wu2015 Section 5): the record, its files and synthetic loops.

A loop record is a time series (t, u, f) of a contact under periodic tangential displacement
(wu2015 Section 5: displacement from the vibrometer, force from the piezo sensor). On disk it is
a CSV with a sidecar `<stem>.json` (`read_loop`, `write_loop`). Whole cycles are located from
the upward mean-crossings of u (`cycle_starts`); the analysis (wu2015 Eq 6, K_eq, C_eq) and the
fit of μN and K_d are `tribojax.analyse_loop` and `tribojax.fit_loop`.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import ClassVar, final

import jax
import jax.numpy as jnp
import numpy as np

from .._dynamics._profiles import DisplacementHistory
from .._tables import DataFileError, read_table
from ._files import (
    csv_header,
    data_line_number,
    implausible,
    positive_or_none,
    read_sidecar,
    sidecar_text,
    write_record_files,
)
from ._record import AbstractRecord, metadata_extent

LOOP_COLUMNS = ("t_s", "u_m", "f_N")  # the legacy format, no sidecar needed
LOOP_FILE_COLUMNS = ("time_s", "displacement_m", "force_N")
# the loop's optional metadata: field -> (sidecar key, unit)
_METADATA = {
    "normal_load": ("normal_load_N", "N"),
    "frequency": ("frequency_Hz", "Hz"),
    "noise_std": ("noise_std_N", "N"),
    "band_tension": ("band_tension_N", "N"),
}


@final
@dataclasses.dataclass(frozen=True)
class HysteresisLoop(AbstractRecord):
    """A measured (or synthetic) loop: times t (s, increasing), displacement u (m), force f (N).

    Optional metadata (keyword-only): `normal_load` (N) of the contact, the drive `frequency`
    (Hz) and `noise_std` (N), the standard deviation of the force noise (`fit_loop` uses it as
    the residual scale when given), and `band_tension` (N), the set tension of a band brake (the
    friction damper's load knob: `fit_history` scales the slip forces with it; 0 for a slack
    band). Construction checks lengths, finiteness, increasing time, positive metadata and
    that at least one whole cycle of u is present (ValueError). `source` names the file it
    came from, if any.
    `periodic=False` marks an arbitrary displacement history (an earthquake record, a ramped
    sine): no whole cycle is required, and only the history (time-domain) route applies to it
    (`fit_loop(model="history")`, `fit_history`).
    """

    t: np.ndarray
    u: np.ndarray
    f: np.ndarray
    source: str = "<array>"
    normal_load: float | None = dataclasses.field(default=None, kw_only=True)
    frequency: float | None = dataclasses.field(default=None, kw_only=True)
    noise_std: float | None = dataclasses.field(default=None, kw_only=True)
    periodic: bool = dataclasses.field(default=True, kw_only=True)
    band_tension: float | None = dataclasses.field(default=None, kw_only=True)

    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "a hysteresis loop"
    reducible: ClassVar[bool] = True
    response_unit: ClassVar[str] = "N"

    def __post_init__(self):
        self._set_series(("t", "u", "f"), time="t")
        for name, (_, unit) in _METADATA.items():  # a band may be slack: 0 N
            zero = name == "band_tension"
            value = positive_or_none(getattr(self, name), name, self.source, unit, zero=zero)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "periodic", bool(self.periodic))
        if self.periodic and len(cycle_starts(self.t, self.u)) < 2:
            raise ValueError(
                f"{self.source}: fewer than one whole cycle of u (need two upward crossings of "
                "its mean); record a longer stretch"
            )

    def profile(self) -> DisplacementHistory:
        """The loop's drive: the measured displacement u(t) (m), linear between samples.

        An element is driven through it by `tribojax.drive(element, h.displacements, h.times)`
        (what `fit_loop(model="history")` does with the loop's samples).
        """
        return DisplacementHistory(self.t, self.u)

    def series(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t, u, f): the displacement drives, the force responds."""
        return self.t, self.u, self.f

    def resampled(self, t, drive, response, *, noise_std) -> HysteresisLoop:
        """The loop on new samples (t, u, f) with force noise sd `noise_std`."""
        return dataclasses.replace(self, t=t, u=drive, f=response, noise_std=noise_std)

    def extent(self) -> dict:
        """The displacement amplitude (half the peak-to-peak, m), peak |force| (N) and peak
        |velocity| (m/s), and the normal load and band tension (N) when known
        (`AbstractRecord.extent`)."""
        amp = 0.5 * float(np.ptp(self.u))
        f = float(np.max(np.abs(self.f)))
        v = float(np.max(np.abs(np.diff(self.u) / np.diff(self.t))))
        return {
            "amplitude": (amp, amp, "m"),
            "force": (f, f, "N"),
            "velocity": (v, v, "m/s"),
            **metadata_extent(self, ("normal_load", "band_tension")),
        }

    def cycle_times(self) -> np.ndarray | None:
        """`cycle_starts(t, u)` for a periodic loop; None for an arbitrary history."""
        return cycle_starts(self.t, self.u) if self.periodic else None


_LOOP_SIDECAR = {key: name == "frequency" for name, (key, _) in _METADATA.items()}
# an arbitrary history ("drive": "history" in the sidecar) needs no frequency
_HISTORY_SIDECAR = {**_LOOP_SIDECAR, "frequency_Hz": False}
LOOP_DRIVES = ("harmonic", "history")
_LOOP_UNITS = dict(_METADATA.values())
FREQUENCY_TOLERANCE = 0.1  # relative mismatch allowed between the sidecar and the record


def read_loop(path) -> HysteresisLoop:
    """Load a loop: CSV `time_s,displacement_m,force_N` plus sidecar `<stem>.json`, or legacy.

    The sidecar holds {"frequency_Hz" (required, > 0), "normal_load_N", "noise_std_N" and
    "band_tension_N" (optional, ≥ 0)}; the legacy columns `t_s,u_m,f_N` take the same sidecar
    if present. SI units, `#` comment lines allowed. The sidecar's frequency must agree with the
    record's cycle spacing within 10 % (catches rad/s given as Hz). A sidecar with `"drive":
    "history"` marks an arbitrary displacement history (`periodic=False`): then "normal_load_N"
    and "frequency_Hz" are optional.

    Raises DataFileError naming the file (and the line) for NaN/non-numeric entries, time that
    does not increase, fewer than one whole cycle, or a missing/malformed/inconsistent sidecar.
    """
    path = Path(path)
    header = set(csv_header(path))
    new = set(LOOP_FILE_COLUMNS) <= header
    cols = LOOP_FILE_COLUMNS if new else LOOP_COLUMNS
    table = read_table(path, columns=cols)
    t, u, f = (table[c] for c in cols)
    for column, name, x in ((cols[1], "u", u), (cols[2], "f", f)):
        far = implausible(x, name)
        if far:
            lineno = data_line_number(path, far[0])
            raise DataFileError(f"{path}, line {lineno}: {column} = {far[1]}")
    steps = np.flatnonzero(np.diff(t) <= 0)
    if steps.size:
        lineno = data_line_number(path, steps[0] + 1)
        raise DataFileError(
            f"{path}, line {lineno}: time {cols[0]} = {t[steps[0] + 1]} does not increase"
        )
    drive = sidecar_text(path, "drive", LOOP_DRIVES) or "harmonic"
    schema = _LOOP_SIDECAR if drive == "harmonic" else _HISTORY_SIDECAR
    side = read_sidecar(
        path, schema, _LOOP_UNITS, required=new, text_keys=("drive",), zero_keys=("band_tension_N",)
    )
    side = side or {}
    try:
        loop = HysteresisLoop(
            t,
            u,
            f,
            source=str(path),
            periodic=drive == "harmonic",
            **{name: side.get(key) for name, (key, _) in _METADATA.items()},
        )
    except ValueError as err:
        raise DataFileError(str(err)) from None
    if loop.frequency is not None and loop.periodic:
        starts = cycle_starts(loop.t, loop.u)
        measured = (len(starts) - 1) / (starts[-1] - starts[0])
        if abs(loop.frequency / measured - 1) > FREQUENCY_TOLERANCE:
            raise DataFileError(
                f"{path.with_suffix('.json')}: frequency_Hz = {loop.frequency:g} disagrees with "
                f"the record's {measured:.6g} Hz (from the mean-crossings of its displacement) "
                f"by more than {FREQUENCY_TOLERANCE:.0%}; give the frequency in Hz, not rad/s"
            )
    return loop


def write_loop(
    loop: HysteresisLoop, path, comment: str = "", *, overwrite: bool = False, legacy=None
) -> None:
    """Write a loop as CSV (17 digits) with optional `#` comment lines, atomically.

    With `frequency` set, the format `time_s,displacement_m,force_N` plus a sidecar
    `<stem>.json` (an arbitrary history, `periodic=False`, always takes this format, with
    `"drive": "history"` in its sidecar); otherwise (or with legacy=True) the legacy
    `t_s,u_m,f_N` without one (by default a ValueError when the loop states metadata that
    format cannot keep: a noise sd, normal load or band tension). Refuses (FileExistsError) if
    a target exists, unless `overwrite=True`.
    """
    has_meta = not loop.periodic or loop.frequency is not None
    lost = [name for name in _METADATA if getattr(loop, name) is not None]
    if legacy is None and not has_meta and lost:  # never drop silently what the loop states
        raise ValueError(
            f"write_loop: the legacy t_s,u_m,f_N format cannot keep {lost}; give "
            "the loop its drive frequency (frequency=, Hz) for the format with a "
            "sidecar, or legacy=True to drop them"
        )
    legacy = (not has_meta) if legacy is None else bool(legacy)
    if not legacy and not has_meta:
        raise ValueError("the time_s,displacement_m,force_N format needs the loop's frequency")
    side = None
    if not legacy:
        side = {} if loop.periodic else {"drive": "history"}
        side.update(
            {
                key: getattr(loop, name)
                for name, (key, _) in _METADATA.items()
                if getattr(loop, name) is not None
            }
        )
    header = LOOP_COLUMNS if legacy else LOOP_FILE_COLUMNS
    write_record_files(
        path, header, (loop.t, loop.u, loop.f), side, overwrite=overwrite, comment=comment
    )


CROSSING_BAND = 1e-4  # of u's peak to peak: a sample this close to the mean is on it


def cycle_starts(t, u) -> np.ndarray:
    """Times of the upward crossings of u's mid-range (linear interpolation between samples).
    A sample within `CROSSING_BAND`·(peak to peak) of it counts as on it, so that a record
    that starts (or passes a sample) at its mean finds the same cycles whatever the last bits."""
    x = u - 0.5 * (u.max() + u.min())
    on = np.abs(x) <= CROSSING_BAND * (u.max() - u.min())
    xs = np.where(on, 0.0, x)
    i = np.flatnonzero((xs[:-1] <= 0) & (xs[1:] > 0))
    return np.maximum(t[i], t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i]))


def synthetic_loop(
    element,
    A,
    omega,
    *,
    cycles: int = 3,
    samples_per_cycle: int = 400,
    noise: float = 0.0,
    seed: int = 0,
    normal_load=None,
) -> HysteresisLoop:
    """A steady loop of `element` under u = A sin ωt, with Gaussian force noise (N) from `seed`.

    The record starts at u = 0 on the rising branch and spans `cycles` + 1/4 periods, so that
    `analyse_loop` finds `cycles` whole cycles. Its `frequency` is ω/2π, `noise_std` the noise
    (None if 0) and `normal_load` as given (N).
    """
    n = cycles * samples_per_cycle + samples_per_cycle // 4 + 1
    t = np.arange(n) / samples_per_cycle * (2.0 * np.pi / omega)
    theta = omega * t - 0.5 * np.pi  # u = A cos θ = A sin ωt
    f = np.asarray(jax.vmap(lambda th: element.steady_loop(th, A))(jnp.asarray(theta)))
    rng = np.random.default_rng(seed)
    return HysteresisLoop(
        t,
        A * np.sin(omega * t),
        f + noise * rng.standard_normal(n),
        normal_load=normal_load,
        frequency=float(omega) / (2.0 * np.pi),
        noise_std=float(noise) if noise > 0 else None,
    )
