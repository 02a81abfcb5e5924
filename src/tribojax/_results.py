"""Result codes: optimistix's `RESULTS` (itself lineax's plus the nonlinear-solver outcomes) and
the outcomes of tribojax's fits. A fit reports one member (`FitResult.result`); a code returned
by `optimistix.least_squares` is promoted unchanged (`RESULTS.promote`).
"""

from __future__ import annotations

import jax
import optimistix as optx


class RESULTS(optx.RESULTS):  # pyright: ignore
    """An `equinox.Enumeration` of outcomes: every member of `optimistix.RESULTS` plus

    - `model_failed`: the model could not be evaluated at the returned parameters (an ODE solve
      or a load balance failed there; its residuals carry the failed-evaluation value).
    - `model_failed_at_start`: the model could not be evaluated at the start values and the
      solver did not move away from them.
    - `short_of_optimum`: the solver stopped on its noise-floor rule
      (`LevenbergMarquardt.noise_floor`), but the Gauss-Newton step still left is above the
      fit's tolerance in standard errors.
    - `not_converged`: the fit did not converge, cause not recorded (a `FitResult` built with
      `converged=False` and no result).
    - `continuation_failed`, `continuation_incomplete`: a pseudo-arclength continuation
      (`frequency_response`) stopped on a failed corrector, or ran out of points.

    `RESULTS[member]` is the message; `result_name(member)` the member's name.
    """

    model_failed = (
        "The model could not be evaluated at the fitted parameters (an ODE solve or a contact load "
        "balance failed there). Try another start or a larger solver budget."
    )
    model_failed_at_start = (
        "The model could not be evaluated at the start values. Give a start closer to the data."
    )
    short_of_optimum = (
        "The solver stopped on its noise-floor rule, but the Gauss-Newton step still left is too "
        "large (in standard errors): not at an optimum. Try another start or more steps."
    )
    not_converged = "The fit did not converge."
    continuation_failed = (
        "The continuation stopped: the corrector did not converge even at the minimum step. Try a "
        "smaller minimum step, more harmonics or AFT samples, or another start."
    )
    continuation_incomplete = (
        "The continuation used all its points before reaching the end of the parameter range. "
        "Give more points or a larger maximum step."
    )


def result_name(result) -> str:
    """The name of a concrete `RESULTS` member (e.g. "successful"), for JSON reports."""
    result = RESULTS.promote(result) if not isinstance(result, RESULTS) else result
    # equinox keeps the members by name in `_name_to_item` (no public iteration)
    for name, item in RESULTS._name_to_item.items():
        if bool(item == result):
            return name
    raise ValueError(f"{result!r} is not a concrete RESULTS member")


def result_code(result):
    """The integer array inside a `RESULTS` member (traceable): what a stored program returns."""
    result = result if isinstance(result, RESULTS) else RESULTS.promote(result)
    return jax.tree_util.tree_leaves(result)[0]


def result_from_code(code) -> RESULTS:
    """The `RESULTS` member of an integer code from `result_code`."""
    return jax.tree_util.tree_unflatten(jax.tree_util.tree_structure(RESULTS.successful), [code])
