"""Long records: block reduction by local quadratics, with the noise model it implies.

A rig sampling at 10 kHz for minutes, or a fast one over one cycle, gives millions of samples;
fits and discovery need far fewer to resolve the dynamics. `decimate_record` splits the record
into consecutive blocks of `factor` samples and replaces each block by the value at its mean time
of a least-squares quadratic in time fitted to the block, for every channel (t, drive,
response). For white noise of standard deviation σ the reduced value has standard deviation
σ·√g with g = [(XᵀX)⁻¹]₀₀, X = [1, τ, τ²] the block's design (g ≈ 9/(4·factor) for uniform
sampling). The estimate is exact for a signal that is quadratic (indeed cubic) over the block;
its bias is that of the fourth derivative, about 2.2e-4·h⁴·|x''''| for a block of duration h
(for a ring-down of angular frequency ω: 2.2e-4·(hω)⁴ of its amplitude), where a plain block
mean is biased by h²·x''/24.

σ is the record's stated noise when it has one (`noise_std`); otherwise it is estimated from the
scatter of the samples about their block quadratics, s² = ΣRSS/Σ(n − 3). With a stated σ the same
scatter tests the reduction: `block_chi2` = ΣRSS/(σ²·Σ(n − 3)) stays near 1 when the quadratics
follow the signal within each block (it grows when the blocks are too long for the dynamics).
A trailing remainder of fewer than `factor` samples is dropped (`samples_used` says how many
were kept).

The drive is not smoothed: a reduced slip run keeps the original's full-resolution acceleration
profile (`SlipRun.drive`), since a velocity error of the drive stays in the slip for good
(docs/performance.md); its reduced `accel` column serves start values and plots. A loop's
displacement is reduced like its force (the steady-loop model takes u sample by sample).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ._fit._noise import ALPHA, chi2_sf
from ._io._record import AbstractRecord
from ._limits import DECIMATION_MAX_SAMPLES as DECIMATION_MAX_SAMPLES
from ._limits import DISCOVER_MAX_SAMPLES as DISCOVER_MAX_SAMPLES

# A loop keeps at least this many reduced samples per cycle: the steady-loop model takes the
# amplitude from the extreme samples of u, which a coarser reduction cuts (docs/discovery.md).
MIN_SAMPLES_PER_CYCLE = 256

METHOD = "block local quadratic"
MIN_FACTOR = 4  # smallest automatic block: 3 coefficients of the quadratic + 1 dof of scatter


@dataclasses.dataclass(frozen=True)
class Decimation:
    """How a record was reduced (`decimate_record`); `as_dict` is the JSON form.

    factor: samples per block (1: not reduced). samples_used: original samples kept (the whole
    blocks); samples: reduced samples. noise_std: the reduced response's noise sd (m for slip,
    N for force), noise_std_original the per-sample σ it comes from, noise_source where σ came
    from. block_chi2: the within-block scatter over σ² (None when σ was estimated from it).
    cycles_kept: the whole cycles of a loop kept by `whole_cycles` (None: all samples kept).
    """

    factor: int
    method: str
    samples_in_record: int
    samples_used: int
    samples: int
    noise_model: str
    noise_source: str | None
    noise_std_original: float | None
    noise_std: float | None
    block_chi2: float | None = None
    blocks_follow_signal: bool | None = None
    cycles_kept: int | None = None

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def _factor(record: AbstractRecord, n: int, max_samples: int) -> int:
    factor, cap = max(1, math.ceil(n / max_samples)), n
    starts = record.cycle_times()
    if starts is not None:  # a periodic record keeps MIN_SAMPLES_PER_CYCLE per cycle
        per_cycle = n * (starts[-1] - starts[0]) / (len(starts) - 1) / (record.t[-1] - record.t[0])
        cap = max(1, int(per_cycle // MIN_SAMPLES_PER_CYCLE))
        factor = min(factor, cap)
    if 1 < factor < MIN_FACTOR:  # a block quadratic and its scatter need MIN_FACTOR samples
        factor = MIN_FACTOR if cap >= MIN_FACTOR else 1
    return factor


def _whole_cycles(record: AbstractRecord, n_keep: int) -> AbstractRecord:
    """A periodic record's first samples, ending just after an upward crossing, at most `n_keep`
    of them (at least two crossings, one whole cycle)."""
    t, drive, resp = record.series()
    ends = np.searchsorted(t, record.cycle_times()) + 1  # one sample past each crossing
    fits = ends[ends <= n_keep]
    end = int(fits[-1]) if len(fits) >= 2 else int(ends[1])
    return record.resampled(t[:end], drive[:end], resp[:end], noise_std=record.noise_std)


def _block_quadratics(t, channels, factor: int):
    """Values at the block mean times of quadratics fitted per block; g; RSS of each channel."""
    B = len(t) // factor
    tb = t[: B * factor].reshape(B, factor)
    tc = tb.mean(axis=1)
    half = 0.5 * (tb[:, -1] - tb[:, 0])
    x = (tb - tc[:, None]) / half[:, None]  # in [-1, 1]
    X = np.stack([np.ones_like(x), x, x * x], axis=-1)  # (B, n, 3)
    XtX = np.einsum("bni,bnj->bij", X, X)
    inv = np.linalg.inv(XtX)
    g = inv[:, 0, 0]
    values, rss = [], []
    for y in channels:
        yb = y[: B * factor].reshape(B, factor)
        coef = np.einsum("bij,bj->bi", inv, np.einsum("bni,bn->bi", X, yb))
        values.append(coef[:, 0])
        rss.append(np.sum((yb - np.einsum("bni,bi->bn", X, coef)) ** 2, axis=1))
    return tc, values, g, rss


def decimate_record(
    record, factor=None, *, max_samples: int = DECIMATION_MAX_SAMPLES, whole_cycles: bool = False
):
    """Reduce a long `SlipRun` or `HysteresisLoop` by block local quadratics (module docstring).

    Args:
        record: a `reducible` record (`AbstractRecord.series`): a `SlipRun` (channels t,
            accel, slip; response slip) or `HysteresisLoop` (t, u, f; response f).
        factor: samples per block (≥ 1); None chooses the smallest factor that leaves at most
            `max_samples` samples (for a loop at most what keeps `MIN_SAMPLES_PER_CYCLE` reduced
            samples per cycle).
        max_samples: the target size when `factor` is None.
        whole_cycles: loops only: when the reduced loop would still exceed `max_samples` (many
            cycles at few samples each), keep only its first whole cycles that fit (the rest is
            dropped and `samples_used` says so). What `tribojax fit` and `discover` do with a
            loop, so that both fit the same samples (discovery's cost grows with the record).
    Returns:
        (reduced record, `Decimation`). The reduced record is of the same type with its
        `noise_std` set to the reduced noise σ·√g (module docstring); with factor 1 the record
        itself. Its `source` is the original's.
    Raises:
        ValueError for a factor < 1 or one leaving fewer than 4 samples (or, for a loop, less
        than one whole cycle).
    """
    if not getattr(record, "reducible", False):  # a record kind with a drive/response series
        raise ValueError(f"record must be a SlipRun or a HysteresisLoop, got {type(record)}")
    t, drive, resp = record.series()
    unit = record.response_unit
    n = len(t)
    if whole_cycles and record.cycle_times() is not None and factor is None:
        keep = _factor(record, n, int(max_samples)) * int(max_samples)
        if keep < n:
            record = _whole_cycles(record, keep)
            t, drive, resp = record.series()
    if factor is None:
        if int(max_samples) < 4:
            raise ValueError(f"max_samples = {max_samples} is outside the allowed range [4, inf)")
        factor = _factor(record, len(t), int(max_samples))
    if isinstance(factor, bool) or int(factor) != factor or factor < 1 or factor == 2:
        raise ValueError(
            f"factor = {factor!r} must be 1 or an integer >= 3 (a block quadratic needs 3 samples)"
        )
    factor = int(factor)
    sigma = record.noise_std
    cycles = None if len(t) == n else len(record.cycle_times()) - 1
    if factor == 1:
        return record, Decimation(
            1,
            "none",
            n,
            len(t),
            len(t),
            "white, per sample",
            None if sigma is None else "the record's noise_std",
            sigma,
            sigma,
            cycles_kept=cycles,
        )
    if len(t) // factor < 4:
        raise ValueError(
            f"{record.source}: factor = {factor} leaves {len(t) // factor} samples of "
            f"{len(t)}; at least 4 are needed"
        )
    tc, (dc, rc), g, (_, rss) = _block_quadratics(t, (drive, resp), factor)
    dof = (len(tc) * (factor - 3)) if factor > 3 else 0
    total = float(np.sum(rss))
    if sigma is not None:
        source = "the record's noise_std"
        chi2 = total / (sigma**2 * dof) if dof > 0 else None
    else:
        if dof == 0:
            raise ValueError(
                f"{record.source}: without a stated noise_std the noise is estimated from the "
                f"scatter within blocks, which needs factor >= 4 (got {factor})"
            )
        sigma = math.sqrt(total / dof)
        source = "estimated from the scatter of the samples about their block quadratics"
        chi2 = None
    reduced_std = float(sigma * math.sqrt(float(np.mean(g))))
    # the χ² part of the one noise test (`noise_consistent`), on the block residuals
    follow = None if chi2 is None else bool(chi2_sf(chi2 * dof, dof) >= ALPHA / 3)
    info = Decimation(
        factor=factor,
        method=METHOD,
        samples_in_record=n,
        samples_used=len(tc) * factor,
        cycles_kept=cycles,
        samples=len(tc),
        noise_std_original=float(sigma),
        noise_std=reduced_std,
        noise_source=source,
        block_chi2=chi2,
        blocks_follow_signal=follow,
        noise_model=(
            f"white noise of sd sigma per sample ({unit}); each reduced sample has sd "
            f"sigma*sqrt(g), g = {float(np.mean(g)):.4g} (local quadratic over "
            f"{factor} samples, evaluated at the block's mean time)"
        ),
    )
    return record.resampled(tc, dc, rc, noise_std=reduced_std), info
