"""Measures of a fit's residual: RMS, NRMSE, BIC and ΔBIC (one home for each)."""

from __future__ import annotations

import numpy as np


def rms(a) -> float:
    """Root mean square of `a` (NaN when empty)."""
    a = np.asarray(a, dtype=float)
    return float(np.sqrt(np.mean(a * a))) if a.size else float("nan")


def nrmse(residual, measured) -> float:
    """rms(model − measured)/std(measured): the normalised RMS error of a prediction."""
    return rms(residual) / float(np.std(np.asarray(measured, dtype=float)))


def bic(rss=None, n=None, k=None, *, log_likelihood=None) -> float:
    """Bayesian information criterion k·log n − 2·log L (k free parameters, n data); from the
    maximised `log_likelihood`, or for Gaussian errors of unknown variance from the RSS
    (−2·log L = n·log(RSS/n) up to a constant): n·log(RSS/n) + k·log n."""
    if log_likelihood is None:
        log_likelihood = -0.5 * n * np.log(rss / n)
    return float(k * np.log(n) - 2.0 * log_likelihood)


def delta_bic(rss1, rss0, n, dk, inflation=1.0) -> float:
    """BIC of a model with `dk` more parameters (RSS `rss1`) minus that of the nested one (`rss0`),
    the log-likelihood ratio divided by a variance `inflation` (AR(1) errors: (1+ρ)/(1−ρ))."""
    return float(n * np.log(rss1 / rss0) / inflation + dk * np.log(n))
