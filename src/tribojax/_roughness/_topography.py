"""Measured topographies: a record in SI metres, plain readers, and instrument files.

Plain formats are read here, always: `.npy` (a 1-D profile or 2-D map; give `dx`), CSV or
whitespace text with two columns (x, height: a profile on a regular grid) or a matrix of heights
(a map; give `dx`). Instrument formats (Dektak CSV exports, Nanoscope `.di`, ISO 25178 `.x3p`,
MetroPro `.dat`, …) are handed to SurfaceTopography, an optional extra
(`pip install 'tribojax[topography]'`); tribojax does not re-implement its readers.
"""

from __future__ import annotations

import math
from pathlib import Path

import equinox as eqx
import numpy as np
from jaxtyping import Array, Float

from .._tables import DataFileError, read_text

UNITS = {
    "m": 1.0,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "μm": 1e-6,
    "nm": 1e-9,
    "A": 1e-10,
    "Å": 1e-10,
}
PLAIN_SUFFIXES = (".npy", ".txt", ".xyz", ".asc", ".dat", ".csv")
MIN_POINTS = 64


def unit_scale(unit: str) -> float:
    """Metres per `unit` (m, mm, um/µm, nm, Å)."""
    if unit not in UNITS:
        raise ValueError(f"unit = {unit!r} is not known; use one of {sorted(set(UNITS))}")
    return UNITS[unit]


class Topography(eqx.Module):
    """A measured or synthetic surface: a profile (1-D) or height map (2-D), in metres.

    Fields:
        heights: heights in m; shape (n,) for a profile, (ny, nx) for a map (x along the last axis).
        dx: sampling interval along x, m, > 0.
        dy: sampling interval along y, m (None for a profile).
        source: where it came from (file name or generator), for reports.
    """

    heights: Float[Array, ...]
    dx: float = eqx.field(static=True)
    dy: float | None = eqx.field(static=True, default=None)
    source: str = eqx.field(static=True, default="")

    def __check_init__(self):
        nd = np.ndim(self.heights)
        if nd not in (1, 2):
            raise ValueError(f"heights must be 1-D or 2-D, got {nd}-D")
        if not (self.dx > 0 and math.isfinite(self.dx)):
            raise ValueError(f"dx = {self.dx} m must be a positive finite sampling interval")
        if nd == 2 and not (self.dy is not None and self.dy > 0 and math.isfinite(self.dy)):
            raise ValueError(f"dy = {self.dy} m must be a positive finite sampling interval")

    @property
    def is_profile(self) -> bool:
        return np.ndim(self.heights) == 1

    @property
    def length(self) -> float:
        """Length along x, m."""
        return float(np.shape(self.heights)[-1] * self.dx)


def validate(topo: Topography) -> None:
    """Refuse what no fractal analysis can use: NaNs, too few points, a flat surface."""
    z = np.asarray(topo.heights)
    name = topo.source or "topography"
    if not np.all(np.isfinite(z)):
        bad = int(np.sum(~np.isfinite(z)))
        raise ValueError(
            f"{name}: {bad} of {z.size} heights are NaN or infinite (missing data); fill or crop "
            "them before estimating D and G"
        )
    if z.shape[-1] < MIN_POINTS:
        raise ValueError(
            f"{name}: {z.shape[-1]} points along x is too short; at least {MIN_POINTS} are needed "
            "for a scaling band of one decade"
        )
    span = float(np.ptp(z))
    if span <= 1e-12 * max(1.0, float(np.max(np.abs(z)))):
        raise ValueError(f"{name}: the surface is flat (height range {span:g} m); nothing to fit")


def _read_plain(path: Path, dx, unit: str) -> Topography:
    s = unit_scale(unit)
    if path.suffix == ".npy":
        try:
            z = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as err:
            raise DataFileError(f"{path}: not a readable .npy file ({err})") from err
        if dx is None:
            raise ValueError(
                f"{path}: a .npy file carries no sampling interval; pass dx (in {unit})"
            )
        z = np.asarray(z, dtype=np.float64)
        if z.ndim not in (1, 2):
            raise DataFileError(f"{path}: expected a 1-D or 2-D array, got shape {z.shape}")
        if not np.all(np.isfinite(z)):
            bad = np.argwhere(~np.isfinite(z))[0].tolist()
            raise DataFileError(f"{path}: the value at index {bad} is not a finite number")
        return Topography(z * s, dx=dx * s, dy=None if z.ndim == 1 else dx * s, source=path.name)
    rows, width = [], None
    for lineno, raw in enumerate(read_text(path).splitlines(), start=1):
        text = raw.strip()
        if not text or text.startswith(("#", "%")):
            continue
        fields = text.replace(",", " ").replace(";", " ").split()
        try:
            row = [float(f) for f in fields]
        except ValueError:
            if not rows:  # one header line is allowed
                continue
            raise DataFileError(f"{path}, line {lineno}: {text[:60]!r} is not a row of numbers")
        if not all(np.isfinite(row)):  # float() takes "inf" and "nan"
            raise DataFileError(
                f"{path}, line {lineno}: {text[:60]!r} holds a value that is not a finite number"
            )
        if width is not None and len(row) != width:
            raise DataFileError(
                f"{path}, line {lineno}: {len(row)} values, earlier rows have {width}"
            )
        width = len(row)
        rows.append(row)
    if not rows:
        raise DataFileError(f"{path}: no rows of numbers")
    a = np.asarray(rows)
    if width == 2 and dx is None:  # (x, z) profile
        x = a[:, 0]
        step = np.diff(x)
        if len(x) < 3 or np.any(step <= 0):
            raise DataFileError(f"{path}: the x column is not strictly increasing")
        h = (x[-1] - x[0]) / (len(x) - 1)
        drift = np.max(np.abs(x - x[0] - h * np.arange(len(x))))
        if drift > 0.5 * h:  # rounding of printed x is fine; gaps and resampling are not
            raise DataFileError(f"{path}: x is not evenly spaced (off a regular grid by {drift:g})")
        return Topography(a[:, 1] * s, dx=float(h * s), source=path.name)
    if dx is None:
        raise ValueError(f"{path}: a matrix of heights carries no sampling interval; pass dx")
    z = a[:, 0] if width == 1 else a
    return Topography(z * s, dx=dx * s, dy=None if z.ndim == 1 else dx * s, source=path.name)


def _read_instrument(path: Path) -> Topography:
    try:
        import SurfaceTopography as st
    except ImportError:
        raise ImportError(
            f"{path}: this instrument format needs SurfaceTopography; install the extra with "
            "`pip install 'tribojax[topography]'` (or save the heights as .npy/.csv)"
        ) from None
    fmt = _format_of(st, path)
    try:
        t = _open_instrument(st, path, fmt)
        z = np.ma.filled(np.ma.asarray(t.heights(), dtype=np.float64), np.nan)
        unit = t.unit
    except Exception as err:  # SurfaceTopography raises many types for unreadable files
        raise DataFileError(_unreadable(path, fmt, err)) from err
    if unit is None:
        raise DataFileError(f"{path}: the file states no length unit; read it with unit=")
    s = unit_scale(unit)
    sizes = t.physical_sizes
    dx = float(sizes[0]) / z.shape[0] * s
    if z.ndim == 1:
        return Topography(z * s, dx=dx, source=path.name)
    # SurfaceTopography stores maps as (nx, ny); tribojax uses (ny, nx), x along the last axis.
    dy = float(sizes[1]) / z.shape[1] * s
    return Topography(z.T * s, dx=dx, dy=dy, source=path.name)


_TRUNCATED = (
    "not large enough",
    "truncat",
    "not a valid zip",
    "unexpected end",
    "eof",
    "bad magic number for file header",
    "file is not a zip file",
)


def _format_of(st, path: Path) -> str | None:
    """SurfaceTopography's format name for the file's suffix when exactly one reader claims it."""
    suffix = path.suffix.lower().lstrip(".")
    if suffix == "di":
        return "di"
    names = [r.format() for r in st.IO.readers if suffix in getattr(r, "_file_extensions", ())]
    return names[0] if len(names) == 1 else None


def _open_instrument(st, path: Path, fmt: str | None):
    """The file's topography by the reader of its suffix, else by SurfaceTopography's detection
    (a misnamed file); the suffix reader's error when both fail."""
    try:
        return st.open_topography(str(path), format=fmt).topography()
    except Exception as first:
        if fmt is None:
            raise
        try:
            return st.open_topography(str(path)).topography()
        except Exception:
            raise first from None


def _unreadable(path: Path, fmt: str | None, err: Exception) -> str:
    """One message for an instrument file SurfaceTopography cannot read, saying "truncated"
    when the reader found the data shorter than its header announces."""
    text = " ".join(str(err).split())
    kind = f"a {fmt} file" if fmt else "any instrument format SurfaceTopography knows"
    if any(k in text.lower() for k in _TRUNCATED):
        return (
            f"{path}: the file is truncated or damaged ({path.stat().st_size} bytes; read as "
            f"{kind}: {text[:200]})"
        )
    return f"{path}: cannot be read as {kind} ({text[:300]})"


def read_topography(
    path, *, unit: str = "m", dx=None, instrument: bool | None = None
) -> Topography:
    """Read a profile or height map into a `Topography` in metres.

    Args:
        path: the file.
        unit: length unit of a plain file's numbers (x and heights), "m", "mm", "um", "nm".
        dx: sampling interval (in `unit`) for files that do not carry one (.npy, matrices).
        instrument: True forces SurfaceTopography, False the plain readers; None picks by
            content (plain numbers → plain reader, anything else → SurfaceTopography).
    Raises:
        DataFileError naming the file (and line) for malformed or unreadable files; ImportError
        naming the extra when an instrument file needs SurfaceTopography and it is missing.
    """
    path = Path(path)
    unit_scale(unit)  # an unknown unit is refused before anything is read
    if not path.is_file():
        raise DataFileError(f"{path}: no such file")
    if instrument is None:
        instrument = path.suffix.lower() not in PLAIN_SUFFIXES or not _looks_plain(path)
    return _read_instrument(path) if instrument else _read_plain(path, dx, unit)


def _looks_plain(path: Path) -> bool:
    """True when the file is a .npy or its first data lines are plain numbers."""
    if path.suffix == ".npy":
        return True
    try:
        with path.open("rb") as f:
            text = f.read(4096).decode("utf-8")
    except (OSError, UnicodeDecodeError):
        return False
    lines = [ln for ln in text.splitlines()[:6] if ln.strip() and not ln.lstrip().startswith("#")]
    numeric = []
    for ln in lines[:3]:  # the first line may be a header; later lines are the reader's job
        try:
            [float(f) for f in ln.replace(",", " ").replace(";", " ").split()]
            numeric.append(True)
        except ValueError:
            numeric.append(False)
    return any(numeric) and all(numeric[1:])
