"""Fits of the history models (`_history_model`) to measured displacement histories: one
parameter set fitted to one or several records at once (`fit_history`), which predicts others
(`predict_history`)."""

from __future__ import annotations

import dataclasses

import jax.numpy as jnp
import numpy as np

from .._checks import check_range
from .._fit._engine import least_squares_fit
from .._fit._noise import noise_consistent, noise_estimate
from .._fit._result import FitResult, fit_statistics, thrown
from .._fit._solver import LevenbergMarquardt
from .._io._hysteresis_loop import HysteresisLoop
from .._limits import JOINT_SCALE_RATIO
from .._results import RESULTS
from ._fit import NOISE_TOL
from ._history_model import (
    HISTORY_MODELS,
    _HistoryResiduals,
    _nrmse,
    _records,
    _Transform,
    campaign_spec,
    history_force,
    law_spec,
)


def _default_start(model: str, records) -> dict:
    f = np.concatenate([np.asarray(r[2]) for r in records])
    u = np.concatenate([np.asarray(r[1]) for r in records])
    lo, hi = np.percentile(f, [2, 98])
    F, K = 0.5 * (hi - lo), 40.0 * 0.5 * (hi - lo) / max(np.ptp(u), 1e-12)
    v = max(max(float(np.max(np.abs(np.diff(r[1]) / np.diff(r[0])))) for r in records), 1e-9)
    base = {"n": 2.0, "v_s": 0.1 * v, **_starts(F, K, 0.5 * (hi + lo), records)}
    return {name: base[name] for name, _ in HISTORY_MODELS[model]}


def _starts(F, K, f0, records) -> dict:
    """Start values of every model's parameters but n and v_s from a slip force F (N), a
    stiffness K (N/m) and an offset f0 (N); the band brake's: the slip force both ways,
    clearances of 3 % of the displacement range, a drag of 6 % of the slip force across them,
    and the exponential rise reaching the slip force over half the elastic travel F/K."""
    gap = max(0.03 * max(float(np.ptp(np.asarray(r[1]))) for r in records), 1e-12)
    k_gap, A = 0.06 * F / gap, 0.15 * F
    beta = float(np.log1p((F - k_gap * gap) / A)) / (0.5 * F / K)
    return {
        "mu_N": F,
        "K_d": K,
        "K": K,
        "F_y": F,
        "sigma0": K,
        "F_c": 0.9 * F,
        "F_s": 1.1 * F,
        "f0": f0,
        "F_pos": F,
        "F_neg": F,
        "gap_pos": gap,
        "gap_neg": gap,
        "k_gap": k_gap,
        "A_pos": A,
        "A_neg": A,
        "beta_pos": beta,
        "beta_neg": beta,
    }


@dataclasses.dataclass(frozen=True)
class HistoryFit:
    """A history fit: the model name, the `FitResult` (parameters with standard errors), the
    NRMSE over the fitted records, the decimation used and `band_tension` (N), the reference
    tension its slip forces belong to (None: the records gave none)."""

    model: str
    fit: FitResult
    nrmse: float
    decimate: int
    band_tension: float | None = None

    @property
    def names(self) -> tuple:
        """Every parameter's name (the element's, f0, the tension law's), fitted or held."""
        return _spec_names(self.model, self.fit)

    @property
    def values(self) -> np.ndarray:
        """Every parameter's value in the order of `names` (held ones from `fit.fixed`)."""
        got = self._every_value()
        return np.asarray([got[n] for n in self.names], dtype=float)

    def _every_value(self) -> dict:
        return {**dict(zip(self.fit.names, np.asarray(self.fit.values).tolist())), **self.fit.fixed}

    def for_campaign(self, label: str) -> HistoryFit:
        """This fit with campaign `label`'s own values (`fit_history`'s `per_campaign`, fitted
        as "<name>@<label>") in place of the shared ones; the first campaign's are the shared."""
        got = self._every_value()
        own = {n[: -len(label) - 1]: v for n, v in got.items() if n.endswith(f"@{label}")}
        return dataclasses.replace(
            self, fit=dataclasses.replace(self.fit, fixed={**self.fit.fixed, **own})
        )

    def as_dict(self) -> dict:
        return {
            "model": self.model,
            "nrmse": self.nrmse,
            "decimate": self.decimate,
            "band_tension_N": self.band_tension,
            **self.fit.as_dict(),
        }


def _refuse_repeats(loops) -> None:
    """ValueError for a record given twice (the same samples): counted twice, it would shrink
    the standard errors by √2 without any new information."""
    seen: dict = {}
    for i, lp in enumerate(loops):
        key = (np.asarray(lp.u).tobytes(), np.asarray(lp.f).tobytes())
        if key in seen:
            where = f" ({lp.source})" if getattr(lp, "source", None) else ""
            raise ValueError(
                f"loops[{i}]{where} has the same samples as loops[{seen[key]}]: give "
                "each record once (a repeat would count its data twice)"
            )
        seen[key] = i


def _refuse_mixed_scales(loops, records) -> None:
    """ValueError when two records' force scales (sd of the force over the band-tension ratio,
    taken as 1 at a slack band) differ by more than `JOINT_SCALE_RATIO`."""
    top = max(rec[4] for rec in records)
    scales = [rec[3] / (rec[4] / top if rec[4] > 0 else 1.0) for rec in records]
    hi, lo = int(np.argmax(scales)), int(np.argmin(scales))
    if scales[lo] > 0 and scales[hi] / scales[lo] > JOINT_SCALE_RATIO:
        raise ValueError(
            f"loops[{hi}] ({loops[hi].source}) has a force sd of {scales[hi]:.3g} N, "
            f"{scales[hi] / scales[lo]:.3g} times that of loops[{lo}] ({loops[lo].source}, "
            f"{scales[lo]:.3g} N): records more than {JOINT_SCALE_RATIO:g}x apart are not fitted "
            "together unless asked (mixed_scales=True; tribojax fit --mixed-scales)"
        )


def fit_history(
    loops,
    model: str = "jenkins",
    *,
    start=None,
    decimate: int = 1,
    max_steps: int = 300,
    rtol: float = 1e-8,
    n_starts=(2.0,),
    mixed_scales: bool = False,
    tension_law: str = "auto",
    fixed=None,
    band_tension=None,
    campaigns=None,
    per_campaign=(),
    throw: bool = True,
) -> HistoryFit:
    """Fit one friction element (+ a force offset f0, N) to one or several measured histories.

    Args:
        loops: a `HysteresisLoop` or a sequence of them (one parameter set for all); any
            displacement history (periodic or not). Each is driven from rest at its first sample.
        model: "jenkins" (μN N, K_d N/m), "mindlin" (μN, K_d; Iwan form with 64 elements),
            "lugre" (σ0 N/m, F_c N, F_s N, v_s m/s; σ1 = σ2 = 0, α = 1, β = 2) or
            "bouc_wen" (K N/m, F_y N, n; b = 1/2) or "band_brake" (`BandBrake`: slip forces
            F_pos, F_neg N, clearances gap_pos, gap_neg m, drag k_gap N/m, engagement A_pos,
            A_neg N and beta_pos, beta_neg 1/m); each with f0.
        start: dict of start values (missing keys: from a Jenkins fit to the same records, which
            starts at the force's 2–98 % half range as the slip force and a stiffness 40 times
            its ratio to the displacement range).
        n_starts: Bouc–Wen only, without a start for n: each value given is a start of n and
            the lowest residual is kept (default one start, n = 2; `BOUC_WEN_STARTS` for a
            thorough fit, three times the work).
        decimate: keep every `decimate`-th sample (1: all). Records with a `band_tension` (all
            or none) share one parameter set, the slip forces at the first record's tension;
            records at two or more tensions add the tension law's parameters after f0
            (`law_spec`: T_res, and γ from three tensions on; `_history_model` docstring).
        tension_law: "auto" (the fullest law the records' tensions determine), "proportional"
            (T/T_ref), "residual" (T_res) or "growing" (T_res and γ); `law_spec`.
        fixed: dict of parameters held at the values given, not fitted (a new campaign
            calibrated by one test: every parameter but those that move, from an earlier fit);
            a tension law's parameters held need no second tension.
        band_tension: the tension (N) the slip forces are fitted at (default: the first
            record's; an earlier fit's `band_tension` when its values are held or started from).
        max_steps, rtol: the budget and relative tolerance (atol 1e-3 rtol) of
            `LevenbergMarquardt.noise_floor`.
        mixed_scales: fit records whose force scales (sd of the force, at the reference band
            tension) differ by more than `JOINT_SCALE_RATIO` (100x) together; refused otherwise
            (ValueError naming both): each record is weighted by its own scale, and a record
            that far from the others is a unit error or another device.
        campaigns, per_campaign: a label per record (its test campaign) and the parameters
            (the element's and f0) fitted per campaign: the first label's records use the
            shared values, each other campaign its own, fitted as "<name>@<label>"
            (`HistoryFit.for_campaign`; `tribojax.discovery.discover_campaigns`).
        throw: raise `tribojax.FitError` when the fit does not succeed (default); False
            returns it with `.fit.result` saying so.
    Returns:
        `HistoryFit`: parameters and standard errors (`least_squares_fit`, the noise scale
        estimated from the residuals; positive parameters fitted as logarithms) and the NRMSE.
    """
    if model not in HISTORY_MODELS:
        raise ValueError(f"model must be one of {sorted(HISTORY_MODELS)}, got {model!r}")
    decimate = int(check_range(decimate, "decimate", 1, None, lo_open=False))
    loops = [loops] if isinstance(loops, HysteresisLoop) else list(loops)
    _refuse_repeats(loops)
    tensions = {lp.band_tension for lp in loops if lp.band_tension is not None}
    law = law_spec(model, len(tensions), tension_law)
    held_law = {n for n, _ in law_spec(model, 3, "growing")} & set(fixed or {})
    law = tuple(kv for kv in law_spec(model, 3, "growing") if kv in law or kv[0] in held_law)
    if held_law and any(lp.band_tension is None for lp in loops):
        raise ValueError(
            f"fixed holds the tension law's {sorted(held_law)}, but a record has no "
            "band_tension: give each record's (band_tension=..., N; --band-tension)"
        )
    records, ref = _records(loops, decimate, band_tension, law=tuple(n for n, _ in law))
    if not mixed_scales:
        _refuse_mixed_scales(loops, records)
    spec = HISTORY_MODELS[model] + law
    init = {**_default_start(model, records), **_law_start(law, tensions)}
    if model != "jenkins" and set(init) - set(start or {}):
        # the Jenkins fit (exact increments, fast) gives the slip force, stiffness and offset
        jenkins = fit_history(
            loops,
            "jenkins",
            decimate=decimate,
            mixed_scales=True,
            tension_law=tension_law,
            throw=False,
        )
        mu_N, K_d, f0 = jenkins.fit.values[:3]
        init.update({k: v for k, v in _starts(mu_N, K_d, f0, records).items() if k in init})
        for name, v in zip(jenkins.fit.names[3:], jenkins.fit.values[3:]):
            init.update({k: float(v) for k, _ in law if k.startswith(name)})
    own, swaps = campaign_spec(model, loops, campaigns, per_campaign, spec)
    spec = spec + own
    init.update(start or {})
    init.update({n: init[n.split("@")[0]] for n, _ in own if n not in (start or {})})
    for what, given in (("start", start), ("fixed", fixed)):
        unknown = set(given or {}) - {n for n, _ in spec}
        if unknown:
            raise ValueError(f"{what} has unknown key(s) {sorted(unknown)} for model {model!r}")
    held = _held(spec, fixed or {})
    spec = tuple(kv for kv in spec if kv[0] not in (fixed or {}))
    force_scale = float(max(abs(init["f0"]), max(r[3] for r in records)))
    scale = tuple(1.0 / max(tensions) if n.startswith("gamma") else force_scale for n, _ in spec)
    tr = _Transform(tuple(pos for _, pos in spec), scale)
    law_names = tuple(n for n, _ in law)
    fn = _HistoryResiduals(model, tr, law=law_names, reference=ref, held=held, swaps=swaps)

    def solve(values):
        theta = jnp.asarray(
            [np.log(values[n]) if pos else values[n] / c for (n, pos), c in zip(spec, scale)]
        )
        before, start_theta = np.inf, theta
        for _ in range(3):  # a noise-floor stop short of the optimum restarts where it stopped
            fit = least_squares_fit(
                fn,
                theta,
                records,
                names=tuple(n for n, _ in spec),
                transform=tr,
                max_steps=max_steps,
                jac="fwd",
                solver=LevenbergMarquardt.noise_floor(rtol, 1e-3 * rtol),
                optimum_tol=1.0,
                throw=False,
            )
            if fit.result != RESULTS.short_of_optimum:
                break
            if np.array_equal(np.asarray(fit.theta), np.asarray(start_theta)):
                # not one step from the start lowered the cost: a failed fit, not a stop
                message = f"no step from the start lowered the cost: {fit.message}"
                return dataclasses.replace(fit, message=message)
            cost = float(np.sum(np.square(fit.residuals)))
            s2 = cost / max(fit.residuals.size - len(spec), 1)
            if before - cost < NOISE_TOL * s2:
                return _stationary(fit, before - cost, s2)
            before, theta = cost, jnp.asarray(fit.theta)
        return fit

    if model == "bouc_wen" and "n" not in (start or {}):
        fits = [solve({**init, "n": float(n)}) for n in n_starts]
        fit = min(fits, key=lambda f: float(np.sum(f.residuals**2)))
    else:
        fit = solve(init)
    nrmse_all = _nrmse(fit.residuals, records)
    fit = dataclasses.replace(_noise_rule(fit, records, loops, tr), fixed=dict(fixed or {}))
    t_ref = loops[0].band_tension if band_tension is None else float(band_tension)
    return HistoryFit(model, thrown(fit, throw), nrmse_all, decimate, t_ref)


def _held(spec, fixed: dict) -> tuple:
    """(index, value) of the held parameters; ValueError for a positive one at or below 0."""
    out = []
    for i, (name, positive) in enumerate(spec):
        if name in fixed:
            lo = 0.0 if positive else None
            out.append((i, float(check_range(fixed[name], f"fixed[{name!r}]", lo, None))))
    return tuple(out)


def _spec_names(model: str, fit: FitResult) -> tuple:
    every = {*fit.names, *fit.fixed}
    law = [n for n, _ in law_spec(model, 3) if n in every]
    return tuple(n for n, _ in HISTORY_MODELS[model]) + tuple(law)


def _stationary(fit: FitResult, gain: float, s2: float) -> FitResult:
    """`fit` as a stationary stop: successful, its message saying so and what the last pass
    gained. A restart that lowers the cost by less than `NOISE_TOL` residual variances (the
    record model's stationary rule, `_model._fit`) has stopped where no step descends: at a
    play operator's kink the Gauss–Newton model promises a step that no trial step realises."""
    note = (
        f"stationary: no descent step (a restart from the stop gained {max(gain, 0.0) / s2:.3g} "
        f"residual variances, less than {NOISE_TOL:g}; the Gauss–Newton step left, which "
        f"no trial step realises: {fit.message})"
    )
    return dataclasses.replace(fit, result=RESULTS.successful, converged=True, message=note)


def _law_start(law, tensions) -> dict:
    """Start values of the tension law (`law_spec`): a residual tension of a quarter of the
    highest set tension, no growth of the wrap."""
    return {n: 0.25 * max(tensions) if pos else 0.0 for n, pos in law}


def _noise_rule(fit: FitResult, records, loops, transform) -> FitResult:
    """The fit's statistics under the one noise rule of every fit (`noise_consistent`): the
    residual in units of each record's stated noise sd (`noise_std`, when every record states
    one) or of its first-difference estimate (`noise_estimate`), its reduced χ² and the verdict
    (χ², windows, Fisher's g; segments: the records). With stated noise consistent with the
    residual the standard errors are those of the stated noise, else scaled by the residual.
    The fit itself weights each record by its force's sd (unchanged)."""
    r0 = np.asarray(fit.residuals, dtype=float)
    if fit.jacobian is None or not np.all(np.isfinite(r0)):
        return fit
    sizes = [len(rec[2]) for rec in records]
    seg = np.repeat(np.arange(len(records)), sizes)
    std = np.repeat([rec[3] for rec in records], sizes)
    r = r0 * std  # N
    stated = all(lp.noise_std is not None for lp in loops)
    try:
        each = (
            [lp.noise_std for lp in loops]
            if stated
            else [noise_estimate(r[seg == i])[0] for i in range(len(records))]
        )
        sigma = np.repeat(each, sizes)
        z = r / sigma
        _, rho = noise_estimate(z, seg)
    except ValueError:  # records of a few samples: no estimate, the statistics as they were
        return fit
    if not np.all(np.isfinite(z)):
        return fit
    x = np.concatenate([np.asarray(rec[0]) for rec in records])
    ok = noise_consistent(z, 1.0, rho, seg, x, len(fit.names), estimated=not stated)[0]
    J = np.asarray(fit.jacobian) * (std / sigma)[:, None]
    return fit_statistics(
        fit.theta,
        z,
        J,
        names=fit.names,
        transform=transform,
        sigma_known=stated,
        result=fit.result,
        steps=fit.steps,
        message=fit.message,
        noise_consistent=ok,
    )


def predict_history(fit: HistoryFit, loop: HysteresisLoop, *, decimate=None, initial="rest"):
    """(predicted force N, NRMSE) of a fitted model on another record (`history_force`).

    `decimate` defaults to the fit's. A fit with a band tension scales its slip forces to the
    record's tension (module docstring); the record must have one. `initial`: "rest" (default)
    or "measured" (`INITIAL_STATES`).
    """
    dec = fit.decimate if decimate is None else int(decimate)
    law = fit.names[len(HISTORY_MODELS[fit.model]) :]
    return history_force(fit.model, fit.values, loop, dec, fit.band_tension, initial, law)
