"""wu2015's loop analysis of a measured hysteresis loop and a fit of μN and K_d.

* whole cycles are located from the upward mean-crossings of u, and ω from their spacing;
* the first harmonics of u and f over those cycles (linear least squares, exact for whole cycles)
  give A and K_eq = F_c/A, C_eq = −F_s/(Aω) in the phase of u = A cos θ (wu2015 Section 5.3);
* K_d by wu2015 Eq 6, (k1 + k2)/2, the mean of the initial loading and unloading slopes at the
  reversal points;
* a least-squares fit of μN and K_d of a Jenkins or Mindlin steady loop to the force samples.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._checks import check_range
from .._dynamics._harmonic import drive
from .._friction._rate_independent import Jenkins, Mindlin
from .._io._loop import HysteresisLoop, cycle_starts
from ._engine import FitResult, least_squares_fit

_ELEMENTS = {"jenkins": Jenkins, "mindlin": Mindlin}


@dataclasses.dataclass(frozen=True)
class LoopAnalysis:
    """wu2015's quantities of a loop (SI units): see `analyse_loop`."""

    cycles: int
    omega: float
    A: float
    mu_N: float
    k1: float
    k2: float
    K_d: float
    K_eq: float
    C_eq: float
    K_bar: float
    C_bar: float
    A_bar: float
    W: float

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def analyse_loop(loop: HysteresisLoop, *, window: float = 0.05) -> LoopAnalysis:
    """Amplitude, μN, K_d (wu2015 Eq 6), K_eq and C_eq (first harmonic) of a measured loop.

    Only whole cycles (between the first and last upward mean-crossing of u) are used.
    - ω = 2π·cycles/duration; A and the phase φ from the first harmonic of u, u ≈ A cos(ωt − φ).
    - K_eq = F_c/A, C_eq = −F_s/(Aω) from the force's first harmonic F_c cos θ + F_s sin θ,
      θ = ωt − φ; K̄ = K_eq/K_d, C̄ = πωC_eq/K_d (wu2015 Section 5.3).
    - k2 (unloading from u_max) and k1 (loading from u_min): slope at the reversal of a quadratic
      fitted to the samples within `window`·(peak-to-peak u) after it, averaged over cycles;
      K_d = (k1 + k2)/2 (wu2015 Eq 6). The quadratic removes the first-order bias of a chord on a
      curved (Mindlin) branch; the window must stay inside the stick zone (Jenkins: Ā < 1/window).
    - μN = half the mean peak-to-peak force per cycle (exact in gross slip; f* < μN in partial
      slip, and noise biases it up by about the noise amplitude).
    - W = ∮ f du over the whole cycles, per cycle (J).
    """
    check_range(window, "window", 0.0, 0.5)
    for name, x, unit in (("force", loop.f, "N"), ("displacement", loop.u, "m")):
        if np.ptp(x) == 0.0:
            raise ValueError(
                f"{loop.source}: the {name} is constant ({x[0]:g} {unit}) over the whole record; "
                "a hysteresis loop needs a varying displacement and force"
            )
    starts = cycle_starts(loop.t, loop.u)
    cycles = len(starts) - 1
    omega = 2.0 * np.pi * cycles / (starts[-1] - starts[0])
    keep = (loop.t >= starts[0]) & (loop.t <= starts[-1])
    t, u, f = loop.t[keep], loop.u[keep], loop.f[keep]
    basis = np.stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)], axis=1)
    cu = np.linalg.lstsq(basis, u, rcond=None)[0]
    cf = np.linalg.lstsq(basis, f, rcond=None)[0]
    A = float(np.hypot(cu[1], cu[2]))
    phi = np.arctan2(cu[2], cu[1])
    F_c = cf[1] * np.cos(phi) + cf[2] * np.sin(phi)
    F_s = -cf[1] * np.sin(phi) + cf[2] * np.cos(phi)
    edges = np.searchsorted(loop.t, starts)
    k1, k2, swings = [], [], []
    span = window * (u.max() - u.min())
    for a, b in zip(edges[:-1], edges[1:]):
        uu, ff = loop.u[a:b], loop.f[a:b]
        swings.append(ff.max() - ff.min())
        k2.append(_reversal_slope(loop.u, loop.f, a + int(np.argmax(uu)), span))
        k1.append(_reversal_slope(loop.u, loop.f, a + int(np.argmin(uu)), span))
    k1, k2 = float(np.mean(k1)), float(np.mean(k2))
    K_d = 0.5 * (k1 + k2)
    mu_N = 0.5 * float(np.mean(swings))
    if not (K_d > 0.0 and mu_N > 0.0):
        raise ValueError(
            f"{loop.source}: the reversal slopes give K_d = {K_d:g} N/m (wu2015 Eq 6) and the "
            f"force swing mu_N = {mu_N:g} N; both must be positive for a friction hysteresis loop"
        )
    K_eq = float(F_c / A)
    C_eq = float(-F_s / (A * omega))
    W = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u))) / cycles
    return LoopAnalysis(
        cycles=cycles, omega=float(omega), A=A, mu_N=mu_N, k1=k1, k2=k2, K_d=K_d, K_eq=K_eq,
        C_eq=C_eq, K_bar=K_eq / K_d, C_bar=float(np.pi * omega * C_eq / K_d), A_bar=A * K_d / mu_N,
        W=W,
    )  # fmt: skip


def _reversal_slope(u, f, r, span) -> float:
    """df/du at the reversal sample r, from a quadratic over the following samples within span."""
    j = r + 1
    while j < len(u) and abs(u[j] - u[r]) <= span:
        j += 1
    du, df = u[r:j] - u[r], f[r:j]
    if len(du) < 4:
        raise ValueError(
            f"only {len(du)} samples within the slope window after the reversal at sample {r}; "
            "increase `window` or the sampling rate"
        )
    return float(np.polyfit(du, df, 2)[1])


def _loop_phase(loop: HysteresisLoop, analysis: LoopAnalysis):
    """Velocity sign of each sample of the steady loop, from the phase of u's first harmonic."""
    t = loop.t
    basis = np.stack([np.ones_like(t), np.cos(analysis.omega * t), np.sin(analysis.omega * t)], 1)
    cu = np.linalg.lstsq(basis, loop.u, rcond=None)[0]
    theta = np.mod(analysis.omega * t - np.arctan2(cu[2], cu[1]), 2.0 * np.pi)
    return np.where(theta < np.pi, -1.0, 1.0)


def fit_loop(
    loop: HysteresisLoop,
    element: str = "jenkins",
    *,
    sigma=None,
    window: float = 0.05,
    model: str = "steady",
    max_steps: int = 500,
    start=None,
) -> FitResult:
    """Least-squares fit of μN (N) and K_d (N/m) of a Jenkins or Mindlin element to the data.

    model="steady": the model force at each sample is the element's steady-loop force (wu2015
    Eq 1 or 2) at the measured u, on the branch given by the phase of u's first harmonic, with
    the loop amplitude A = half the peak-to-peak u. Needs a periodic record.
    model="history": the element is driven through the measured displacement history
    (`tribojax.drive`, its rate-independent time-domain form) from rest at the first upward
    mean-crossing of u; samples before the first reversal after it (the virgin loading) are not
    fitted. Works for any history (drifting or multi-harmonic amplitude); for Mindlin the
    time-domain form is the Iwan discretisation (error ~1e-5 μN).

    Parameters are fitted as logarithms (`least_squares_fit`: optimistix Levenberg–Marquardt,
    compiled once per element, model and record length), started from `analyse_loop`'s μN and
    Eq 6 K_d; standard errors from the Jacobian at the optimum. Only the product μN is
    identifiable from a loop; without gross slip (Jenkins Ā ≤ 1) μN is only bounded below.

    Args:
        element: "jenkins" or "mindlin".
        sigma: force noise, N (None: the loop's `noise_std` if set, else estimated from the
            residuals).
        model: "steady" or "history".
        max_steps: Levenberg–Marquardt step budget.
        start: dict of start values {"mu_N": N, "K_d": N/m} (missing keys from `analyse_loop`).
    Returns:
        FitResult with names ("mu_N", "K_d"); `result` (`tribojax.RESULTS`) and `converged` say
        whether LM succeeded. For a
        Jenkins loop that does not slip at the fit (Ā ≤ 1), μN's standard error is inf and
        `message` says that μN is only bounded below.
    """
    if element not in _ELEMENTS:
        raise ValueError(f"element must be one of {sorted(_ELEMENTS)}, got {element!r}")
    if model not in ("steady", "history"):
        raise ValueError(f"model must be 'steady' or 'history', got {model!r}")
    cls = _ELEMENTS[element]
    start_values, start = start, analyse_loop(loop, window=window)
    sigma = loop.noise_std if sigma is None else sigma
    scale = 1.0 if sigma is None else float(check_range(sigma, "sigma", 0.0, unit="N"))
    fn, args = _loop_problem(loop, cls, model, start, scale)
    f = args[1]
    if len(f) <= 2:
        raise ValueError(f"{loop.source}: {len(f)} samples are too few to fit mu_N and K_d")
    given = dict(start_values or {})
    unknown = set(given) - {"mu_N", "K_d"}
    if unknown:
        raise ValueError(f"start has unknown key(s) {sorted(unknown)}; allowed ['mu_N', 'K_d']")
    init = {"mu_N": start.mu_N, "K_d": start.K_d, **given}
    for key, value in init.items():
        check_range(value, f"start[{key!r}]", 0.0, np.inf)
    theta0 = jnp.log(jnp.array([init["mu_N"], init["K_d"]], dtype=jnp.float64))
    # jitted once per (element, model, record length): repeated fits reuse the compilation
    fit = least_squares_fit(
        fn,
        theta0,
        args,
        names=("mu_N", "K_d"),
        transform=jnp.exp,
        sigma_known=sigma is not None,
        max_steps=max_steps,
        jac="fwd",
    )
    A_fit = 0.5 * (float(loop.u.max()) - float(loop.u.min())) * fit.values[1] / fit.values[0]
    if cls is Jenkins and A_fit <= 1.0 + 1e-3:
        # no slip in the fitted Jenkins loop: μN is only bounded below by the peak force
        std = fit.std_errors.copy()
        cov = fit.covariance.copy()
        corr = fit.correlation.copy()
        std[0], cov[0, :], cov[:, 0] = np.inf, np.inf, np.inf
        corr[0, :], corr[:, 0] = np.nan, np.nan
        corr[0, 0] = 1.0
        msg = (f"mu_N is only bounded below (>= {fit.values[0]:.6g} N): the fitted Jenkins loop "
               f"does not slip (A_bar = {A_fit:.4g} <= 1)")  # fmt: skip
        fit = dataclasses.replace(fit, std_errors=std, covariance=cov, correlation=corr,
                                  message=msg)  # fmt: skip
    return fit


def _loop_problem(loop, cls, model, analysis, scale):
    """The residual function and its args for `fit_loop` (see there for the two models)."""
    if model == "steady":
        direction = jnp.asarray(_loop_phase(loop, analysis))
        u, f = jnp.asarray(loop.u), jnp.asarray(loop.f)
        A = jnp.asarray(0.5 * (float(loop.u.max()) - float(loop.u.min())))
        return _LoopResiduals(cls, None), (u, f, A, direction, jnp.asarray(scale))
    first = int(np.searchsorted(loop.t, cycle_starts(loop.t, loop.u)[0]))
    u_rel = loop.u[first:] - 0.5 * (loop.u.max() + loop.u.min())
    half = int(np.searchsorted(loop.t[first:], loop.t[first] + np.pi / analysis.omega))
    skip = int(np.argmax(u_rel[:half]))  # the first reversal (u_max) after the crossing
    f = jnp.asarray(loop.f[first + skip :])
    return _LoopResiduals(cls, skip), (jnp.asarray(u_rel), f, jnp.asarray(0.0), f,
                                       jnp.asarray(scale))  # fmt: skip


def loop_residuals(loop: HysteresisLoop, element: str, mu_N, K_d, *, model="steady"):
    """Model − measured force (N) of a Jenkins or Mindlin element with μN (N), K_d (N/m) on
    `loop`, as `fit_loop` computes it (steady loop, or the history from the first reversal:
    the residuals then cover the last samples only). Used to judge a fit made on a reduced
    record (`decimate_record`) on every sample of the original."""
    if element not in _ELEMENTS:
        raise ValueError(f"element must be one of {sorted(_ELEMENTS)}, got {element!r}")
    fn, args = _loop_problem(loop, _ELEMENTS[element], model, analyse_loop(loop), 1.0)
    return np.asarray(_evaluate(fn, jnp.log(jnp.array([mu_N, K_d], dtype=jnp.float64)), args))


@eqx.filter_jit
def _evaluate(fn, theta, args):
    return fn(theta, args)


class _LoopResiduals(eqx.Module):
    """(model − measured force)/σ of a loop; θ = log(μN, K_d). skip None: steady loop."""

    cls: type = eqx.field(static=True)
    skip: int | None = eqx.field(static=True)

    def __call__(self, theta, args):
        u, f, A, direction, scale = args
        el = self.cls(jnp.exp(theta[0]), 1.0, jnp.exp(theta[1]))  # only the product μN enters
        if self.skip is None:
            model = el.steady_force(u, A, direction)
        else:
            model = drive(el, u)[self.skip :]
        return (model - f) / scale
