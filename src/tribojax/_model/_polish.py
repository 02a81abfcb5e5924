"""A record model's fit taken on to its minimum in residual variances (`polish`).

`fit_model`'s stops count in s² = RSS/(n − p) of the residual unit, at least 1 (a residual
variance below the noise's is chance). Where the unit is not the record's stated noise sd (a
record without one: the first-difference estimate of the data's noise, which the signal inflates
to several noise sd) a stop is coarser than that in the noise's own variances: the stationary
stop of a Stribeck + mode fit of the study's s1038 left 0.55 unit variances, 11 noise variances,
and the noise test of the two copies of that record (1e-3 noise sd apart) then read p on either
side of its level. docs/discovery.md, "Stability".
"""

from __future__ import annotations

import numpy as np

from ._fit import GAIN_TOL, fit_model


def polish(baseline, fit, y=None):
    """`fit` (a `RecordFit` of `baseline` with its effects) refitted from its stop with the stops
    counted in residual variances (`fit_model`'s `floor` = 0), when its residual unit is not the
    record's stated noise sd and a Gauss–Newton step from its stop still promises `GAIN_TOL`
    residual variances or more; the refit kept when it converged lower. Else `fit` itself."""
    data = baseline.data()
    if not fit.converged or (data.noise_std and fit.scale == float(data.noise_std)):
        return fit
    n = np.asarray(fit.residuals).size
    s2 = fit.rss / max(n - fit.theta.size, 1)
    if not s2 > 0 or (fit.gain_left or 0.0) * max(s2, 1.0) < GAIN_TOL * s2:
        return fit
    y = np.asarray(data.y if y is None else y, dtype=float)
    again = fit_model(
        baseline, fit.designs, fit.theta, y, fit.scale, fit.effects, ceiling=fit.rss, floor=0.0
    )
    return again if again.converged and again.rss < fit.rss else fit
