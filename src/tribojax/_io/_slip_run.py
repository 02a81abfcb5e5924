"""User data records: slip runs (wang2022-style rig), their files, synthetic runs and loaders.

A slip run is what the reticle rig of wang2022 (Section 4, Figure 9) measures: the stage
acceleration a(t) and the slip Δx = x_stage − x_body of the body it carries, sampled at times t.
On disk it is a CSV with the columns `time_s,stage_accel_m_s2,slip_m` (SI units, `#` comment
lines allowed) and a sidecar `<stem>.json` next to it:

    {"mass_kg": 0.321, "normal_load_N": 17.4, "noise_std_m": 2e-10}

(`mass_kg` required; `normal_load_N` and `noise_std_m` optional; a "comment" string allowed; any
other key is refused, so that a misspelt key is not silently ignored).

Hysteresis loops (wu2015-style, `time_s,displacement_m,force_N` plus a sidecar) are
`tribojax.HysteresisLoop` records, read by `tribojax.read_loop`; `read_record` dispatches on the
CSV header. Every loader error is a `DataFileError` naming the file, the line and the reason.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from .._dynamics._profiles import MeasuredProfile
from .._presets import WANG2022_RETICLE_MASS_KG
from ._tables import DataFileError, read_table

SLIP_COLUMNS = ("time_s", "stage_accel_m_s2", "slip_m")
LOOP_FILE_COLUMNS = ("time_s", "displacement_m", "force_N")
LEGACY_LOOP_COLUMNS = ("t_s", "u_m", "f_N")

_SLIP_SIDECAR = {"mass_kg": True, "normal_load_N": False, "noise_std_m": False}


def _positive_or_none(value, name: str, source: str, unit: str, *, required=False):
    """A finite float > 0 (or None where allowed); ValueError naming the field otherwise."""
    if value is None:
        if required:
            raise ValueError(f"{source}: {name} is required ({unit})")
        return None
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ValueError(f"{source}: {name} must be a number ({unit}), got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(
            f"{source}: {name} = {value:g} {unit} is outside the allowed range (0, inf)"
        )
    return value


@dataclasses.dataclass(frozen=True)
class SlipRun:
    """A measured or synthetic slip run: t (s), stage acceleration (m/s²), slip Δx (m).

    `mass` (kg) is the driven body's mass; `normal_load` (N) the normal load of the contact, if
    known (needed to fit surface parameters across loads); `noise_std` (m) the standard deviation
    of the slip noise, None when unknown (a fit then estimates it from its residuals).

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

    def __post_init__(self):
        src = self.source
        arrays = [np.array(x, dtype=np.float64) for x in (self.t, self.accel, self.slip)]
        for name, x in zip(("t", "accel", "slip"), arrays):
            if x.ndim != 1:
                raise ValueError(f"{src}: {name} must be 1-D, got shape {x.shape}")
            bad = np.flatnonzero(~np.isfinite(x))
            if bad.size:
                raise ValueError(f"{src}: {name}[{bad[0]}] is {x[bad[0]]} (must be finite)")
            x.setflags(write=False)
            object.__setattr__(self, name, x)
        if not (len(self.t) == len(self.accel) == len(self.slip)):
            raise ValueError(
                f"{src}: t, accel and slip must have the same length, got "
                f"{len(self.t)}, {len(self.accel)}, {len(self.slip)}"
            )
        if len(self.t) < 2:
            raise ValueError(f"{src}: a slip run needs at least 2 samples, got {len(self.t)}")
        if self.t[0] < 0:
            raise ValueError(f"{src}: t[0] = {self.t[0]:g} s must be >= 0 (the run starts at rest)")
        steps = np.flatnonzero(np.diff(self.t) <= 0)
        if steps.size:
            i = steps[0] + 1
            raise ValueError(
                f"{src}: time is not strictly increasing at sample {i} "
                f"(t = {self.t[i]:g} s after {self.t[i - 1]:g} s)"
            )
        mass = _positive_or_none(self.mass, "mass", src, "kg", required=True)
        object.__setattr__(self, "mass", mass)
        for name, unit in (("normal_load", "N"), ("noise_std", "m")):
            object.__setattr__(self, name, _positive_or_none(getattr(self, name), name, src, unit))

    def __len__(self) -> int:
        return len(self.t)

    def profile(self) -> MeasuredProfile:
        """The stage acceleration as a `MeasuredProfile` (linear between samples)."""
        return MeasuredProfile(self.t, self.accel)


# ---------------------------------------------------------------------------------------------
# sidecars


def sidecar_path(path) -> Path:
    """The sidecar `<stem>.json` beside a record's CSV."""
    path = Path(path)
    return path.with_suffix(".json")


def _key_line(text: str, key: str) -> int | None:
    """1-based line of the first occurrence of `"key"` in a JSON text (for error messages)."""
    needle = json.dumps(key)
    for lineno, line in enumerate(text.splitlines(), start=1):
        if needle in line:
            return lineno
    return None


def read_sidecar(csv_path, schema: dict[str, bool], units: dict[str, str], *, required=True):
    """Read and validate the sidecar of `csv_path`: a JSON object of positive numbers.

    Args:
        schema: key -> whether it is required. Keys outside it (and "comment") are refused.
        units: key -> unit, for messages.
        required: whether the sidecar file itself must exist.
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
    try:
        text = side.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise DataFileError(f"{side}: cannot be read ({err})") from err
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise DataFileError(f"{side}, line {err.lineno}: not valid JSON ({err.msg})") from None
    if not isinstance(data, dict):
        raise DataFileError(
            f"{side}, line 1: must be a JSON object {{...}}, got {type(data).__name__}"
        )
    unknown = [k for k in data if k not in schema and k != "comment"]
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
            out[key] = _positive_or_none(value, f"{key!r}", where, units[key], required=req)
        except ValueError as err:
            raise DataFileError(str(err)) from None
    return out


def _write_text_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_record_files(path, header, columns, sidecar: dict | None, *, overwrite, comment):
    """Write a CSV (and its sidecar) atomically; refuse existing files unless `overwrite`."""
    path = Path(path)
    targets = [path] + ([sidecar_path(path)] if sidecar is not None else [])
    if path.suffix.lower() != ".csv":
        raise ValueError(f"{path}: a record file must end in .csv (its sidecar is <stem>.json)")
    if not overwrite:
        existing = [str(p) for p in targets if p.exists()]
        if existing:
            raise FileExistsError(
                f"{existing[0]} exists; refusing to overwrite it (pass overwrite=True, or choose "
                "another name)"
            )
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [f"# {c}" for c in comment.splitlines()] + [",".join(header)]
    lines += [",".join(f"{v:.17g}" for v in row) for row in zip(*columns)]
    if sidecar is not None:
        _write_text_atomic(targets[1], json.dumps(sidecar, indent=2) + "\n")
    _write_text_atomic(path, "\n".join(lines) + "\n")


def data_line_number(path, row: int) -> int:
    """1-based line number of data row `row` (0-based) of a CSV with comments and a header."""
    seen = -1  # the header is row -1
    for lineno, raw in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), start=1):
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
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as err:
        raise DataFileError(f"{path}: cannot be read ({err})") from err
    for raw in lines:
        text = raw.strip()
        if text and not text.startswith("#"):
            return tuple(f.strip() for f in text.split(","))
    raise DataFileError(f"{path}: no header line")


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
    _check_time(path, t, "time_s")
    if len(t) < 2:
        raise DataFileError(f"{path}: a slip run needs at least 2 data rows, got {len(t)}")
    units = {"mass_kg": "kg", "normal_load_N": "N", "noise_std_m": "m"}
    side = read_sidecar(path, _SLIP_SIDECAR, units)
    return SlipRun(
        t,
        table["stage_accel_m_s2"],
        table["slip_m"],
        mass=side["mass_kg"],
        normal_load=side["normal_load_N"],
        noise_std=side["noise_std_m"],
        source=str(path),
    )


def _check_time(path, t, column):
    if t[0] < 0:
        raise DataFileError(
            f"{path}, line {data_line_number(path, 0)}: {column} = {t[0]:g} must be >= 0"
        )
    steps = np.flatnonzero(np.diff(t) <= 0)
    if steps.size:
        i = steps[0] + 1
        raise DataFileError(
            f"{path}, line {data_line_number(path, i)}: {column} = {t[i]:g} does not increase "
            f"(previous row {t[i - 1]:g})"
        )


def write_slip_run(run: SlipRun, path, *, overwrite: bool = False, comment: str = "") -> None:
    """Write `run` as CSV (`time_s,stage_accel_m_s2,slip_m`, 17 digits) plus sidecar JSON.

    Refuses (FileExistsError) if the CSV or its sidecar exists, unless `overwrite=True`; both are
    written through temporary files, so a failure leaves no partial file.
    """
    side = {"mass_kg": run.mass}
    if run.normal_load is not None:
        side["normal_load_N"] = run.normal_load
    if run.noise_std is not None:
        side["noise_std_m"] = run.noise_std
    write_record_files(path, SLIP_COLUMNS, (run.t, run.accel, run.slip), side,
                       overwrite=overwrite, comment=comment)  # fmt: skip


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
    from .._dynamics._profiles import TrapezoidProfile
    from .._dynamics._slip import simulate_slip

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


def run_profile(run: SlipRun):
    """The run's a(t) as a `PiecewiseLinearProfile` through only its kinks.

    Samples where the acceleration's slope does not change (relative 1e-9 of the largest slope
    change scale) are dropped, so the solver stops only at true kinks: for a sampled trapezoid
    that is the 8 corners, not thousands of samples. Exact: linear interpolation through the
    kept nodes equals that through all samples to rounding.
    """
    from .._dynamics._profiles import PiecewiseLinearProfile

    t, a = run.t, run.accel
    if len(t) < 3:
        return PiecewiseLinearProfile(t, a)
    slope = np.diff(a) / np.diff(t)
    scale = max(float(np.max(np.abs(a))), 1e-300) / float(t[-1] - t[0])
    kink = np.abs(np.diff(slope)) > 1e-9 * scale
    keep = np.concatenate([[True], kink, [True]])
    return PiecewiseLinearProfile(t[keep], a[keep])


def simulate_run(element, run: SlipRun, **kw):
    """The model's slip on the run's own times and acceleration (a `SlipSolution`).

    Calls `simulate_slip(element, profile, run.mass, ts=run.t, t_end=run.t[-1], **kw)` from rest
    at t = 0, with the run's acceleration interpolated linearly between samples (`run_profile`:
    the solver stops at its kinks). Keywords go to `simulate_slip`.
    """
    from .._dynamics._slip import simulate_slip

    profile = kw.pop("profile", None) or run_profile(run)
    return simulate_slip(element, profile, run.mass, ts=run.t, t_end=float(run.t[-1]), **kw)


# ---------------------------------------------------------------------------------------------
# dispatch


def read_record(path):
    """Load a user record, a `SlipRun` or a `HysteresisLoop`, chosen by the CSV header.

    `time_s,stage_accel_m_s2,slip_m` → `read_slip_run`; `time_s,displacement_m,force_N` or the
    legacy `t_s,u_m,f_N` → `tribojax.read_loop`. Anything else: DataFileError listing these.
    """
    from ._loop import read_loop

    path = Path(path)
    header = set(csv_header(path))
    if set(SLIP_COLUMNS) <= header:
        return read_slip_run(path)
    if set(LOOP_FILE_COLUMNS) <= header or set(LEGACY_LOOP_COLUMNS) <= header:
        return read_loop(path)
    raise DataFileError(
        f"{path}, line {data_line_number(path, -1)}: header {sorted(header)} is neither a slip "
        f"run ({','.join(SLIP_COLUMNS)}) nor a loop ({','.join(LOOP_FILE_COLUMNS)}, or legacy "
        f"{','.join(LEGACY_LOOP_COLUMNS)})"
    )
