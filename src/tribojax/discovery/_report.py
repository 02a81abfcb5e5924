"""Step 5 of discovery, the report: the outcome of `discover` (discovery.json), its verdict and
remaining misfit, and its parameter/strength tables."""

from __future__ import annotations

import dataclasses

import numpy as np

from .._fit._measures import rms
from .._fit._noise import excess_rmse, noise_consistent, noise_test_parts
from .._model import FittedModel, effect_strengths, saved_record_model
from ._verdict import correlations, flexible_correction, verdict


@dataclasses.dataclass(frozen=True)
class DiscoveryReport:
    """Outcome of `discover`. `as_dict()` is the discovery.json contract (plus extra keys).

    effects: names in the order added ("none" in `effect` when empty).
    baseline_rmse, final_rmse: RMS residual (output units) of the baseline and the final model.
    regions: flagged stretches of the baseline residual (see `find_regions`), each with
        rmse_before / rmse_after.
    candidates: first-round ranking against the baseline: name, score (Rao LM statistic), dof,
        p_value (Bonferroni over the effect's grid), nuisance at the best grid point, and, for
        refitted candidates, delta_bic (None if not refitted).
    rounds: every greedy round's candidate list.
    strengths: per added effect, {strength name: {"value", "std_error", "unit"}} plus nuisance.
    baseline_fit, final_fit: parameter values and std errors, converged, steps, message.
    noise_std, noise_estimated, rho: the noise model used for regions.
    verdict: "none", "explained", "partly_explained" or "unexplained" (see `_verdict`).
    excess_rmse_before / excess_rmse_after: RMS misfit beyond the noise of the baseline and the
        final model, sqrt(max(rmse² − σ², 0)) (output units).
    heldout_excess_before / heldout_excess_after: the same excess of the two-fold held-out
        residual (each fold predicted by the model fitted on the other alone; the final model's
        nuisance values fixed), output units; None when the baseline passes the noise test
        (nothing to hold out) or a fold's fit failed. "explained" needs it at least halved.
    misfit: where a remaining misfit lives: noise-test p-values of the baseline and final
        residuals, the final residual's flagged regions, its correlations with the measured
        signals and a flexible (linear-spline) correction in the best signal.
    x, y, baseline_y, final_y, segment, signals: arrays for plots (not in as_dict).
    fitted: the final model (baseline + the effects added) as a `FittedModel`, saved under
        "fitted_model" (None when the baseline fit failed); `tribojax.predict` evaluates it on
        another record.
    """

    kind: str
    effects: tuple[str, ...]
    baseline_rmse: float
    final_rmse: float
    regions: list
    candidates: list
    rounds: list
    strengths: dict
    baseline_fit: dict
    final_fit: dict
    noise_std: float
    noise_estimated: bool
    rho: float
    settings: dict
    labels: dict
    verdict: str
    excess_rmse_before: float
    excess_rmse_after: float
    heldout_excess_before: float | None
    heldout_excess_after: float | None
    misfit: dict
    x: np.ndarray = dataclasses.field(repr=False)
    y: np.ndarray = dataclasses.field(repr=False)
    baseline_y: np.ndarray = dataclasses.field(repr=False)
    final_y: np.ndarray = dataclasses.field(repr=False)
    segment: np.ndarray = dataclasses.field(repr=False)
    signals: dict = dataclasses.field(repr=False, default_factory=dict)  # measured, for plots
    fitted: FittedModel | None = None  # the final model as a value (`tribojax.predict` takes it)

    @property
    def effect(self) -> str:
        """The first added effect when explained or partly explained; else the verdict."""
        if self.verdict in ("explained", "partly_explained"):
            return self.effects[0]
        return self.verdict

    @property
    def converged(self) -> bool:
        return bool(self.baseline_fit["converged"])

    def as_dict(self) -> dict:
        return {
            "effect": self.effect,
            "verdict": self.verdict,
            "excess_rmse_before": self.excess_rmse_before,
            "excess_rmse_after": self.excess_rmse_after,
            "heldout_excess_before": self.heldout_excess_before,
            "heldout_excess_after": self.heldout_excess_after,
            "misfit": self.misfit,
            "effects": list(self.effects),
            "baseline_rmse": self.baseline_rmse,
            "final_rmse": self.final_rmse,
            "regions": self.regions,
            "candidates": self.candidates,
            "kind": self.kind,
            "converged": self.converged,
            "rounds": self.rounds,
            "strengths": self.strengths,
            "baseline_fit": self.baseline_fit,
            "final_fit": self.final_fit,
            "noise_std": self.noise_std,
            "noise_estimated": self.noise_estimated,
            "rho": self.rho,
            "settings": self.settings,
            "labels": self.labels,
            "fitted_model": None if self.fitted is None else self.fitted.as_dict(),
        }

    def summary(self) -> str:
        """A few lines for people."""
        unit = self.labels.get("y_unit", "")
        lines = [
            f"verdict: {self.verdict}; effect: {self.effect}"
            + (f"  (all: {', '.join(self.effects)})" if self.effects else ""),
            f"rmse: baseline {self.baseline_rmse:.4g} {unit} -> final {self.final_rmse:.4g} {unit}"
            f" (noise sd {self.noise_std:.3g}{' estimated' if self.noise_estimated else ''})",
            f"excess misfit beyond the noise: {self.excess_rmse_before:.3g} -> "
            f"{self.excess_rmse_after:.3g} {unit}" + _heldout_line(self, unit),
            *_evidence_line(self),
            f"flagged regions: {len(self.regions)}",
        ]
        for rg in self.regions[:6]:
            lines.append(
                f"  [{rg['start']:.4g}, {rg['end']:.4g}] seg {rg['segment']}: rmse "
                f"{rg['rmse_before']:.3g} -> {rg['rmse_after']:.3g}, p = {rg['p_value']:.2g}"
            )
        for name, st in self.strengths.items():
            parts = [
                f"{k} = {v['value']:.4g} ± {v['std_error']:.2g} {v['unit']}"
                for k, v in st.items()
                if isinstance(v, dict) and "value" in v
            ]
            lines.append(f"  {name}: " + "; ".join(parts))
        if self.verdict in ("partly_explained", "unexplained"):
            corr = self.misfit.get("correlations", [])[:3]
            lines.append(
                "remaining misfit correlates with: "
                + ", ".join(f"{c['signal']} ({c['correlation']:+.2f})" for c in corr)
            )
            fc = self.misfit.get("correction")
            if fc:
                lines.append(
                    f"a term in {fc['signal']} could close {100 * fc['gap_closed']:.0f}%"
                    " of the remaining excess"
                )
        if not self.baseline_fit["converged"]:
            lines.append(f"WARNING: baseline fit did not converge: {self.baseline_fit['message']}")
        return "\n".join(lines)


def _fit_dict(baseline, state, scale: float) -> dict:
    p = len(baseline.param_names)
    vals = dict(zip(baseline.param_names, state.values[:p].tolist()))
    stds = dict(zip(baseline.param_names, state.std_errors[:p].tolist()))
    return {
        "parameters": vals,
        "std_errors": stds,
        "unidentified": baseline.unidentified(vals, stds),
        "units": dict(zip(baseline.param_names, baseline.param_units)),
        "converged": state.converged,
        "steps": state.steps,
        "message": state.message,
        "effects": list(state.effects),
        "rss": state.rss * scale**2,
    }


def _misfit(run, rf, state):
    """Noise tests of the final residual `rf`, the verdict, the excess misfits and, where a
    misfit remains, its regions, signal correlations and flexible correction."""
    baseline, data, nz = run.baseline, run.data, run.noise
    n_final = len(baseline.param_names) + sum(d.k + d.n_nuisance for d in state.designs)
    base_ok, p0 = run.base_test
    final_ok, p1, remaining = noise_consistent(
        rf,
        nz.sigma,
        nz.rho,
        data.segment,
        data.x,
        n_final,
        alpha=run.alpha,
        n_windows=run.n_windows,
        estimated=not data.noise_std,
    )
    e0, e1 = excess_rmse(run.r0, nz.sigma), excess_rmse(rf, nz.sigma)
    held = (None, None) if base_ok else (run.heldout(run.base_state), run.heldout(state))
    held_ms = (None, None) if base_ok else (run.heldout_ms(run.base_state), run.heldout_ms(state))
    v = verdict(
        len(state.effects),
        base_ok,
        final_ok,
        e0,
        e1,
        None if held[0] is None else held,
        sigma=nz.sigma,
        heldout_ms=None if held_ms[0] is None else held_ms,
    )
    if not baseline.noise_gate:  # no noise test: the ΔBIC selection alone decides
        v = "explained" if state.effects else "none"
    misfit = {
        "baseline_noise_p_value": p0,
        "final_noise_p_value": p1,
        "baseline_consistent": base_ok,
        "final_consistent": final_ok,
    }
    if held_ms[0] is not None:  # what the held-out gate compares (`_refits._generalises`)
        misfit["heldout_rms"] = [float(np.sqrt(m)) if m is not None else None for m in held_ms]
    if not base_ok and baseline.noise_gate:  # which part of the test finds the misfit
        parts = noise_test_parts(
            run.r0,
            *run.base_noise,
            data.segment,
            data.x,
            len(baseline.param_names),
            run.alpha,
            run.n_windows,
            not data.noise_std,
        )
        misfit["baseline_evidence"] = {
            "whole_record_p": parts["p_whole"],
            "periodic_line_p": parts["p_line"],
            "windows_flagged": len(parts["regions"]),
        }
    if v in ("partly_explained", "unexplained"):
        signals = {**baseline.signals(), "model": np.asarray(state.prediction)}
        for rg in remaining:
            rg.update(baseline.region_info(rg))
        misfit["regions"] = remaining
        misfit["correlations"] = correlations(rf, signals)
        misfit["correction"] = flexible_correction(rf, signals, nz.sigma)
    return misfit, v, e0, e1, held


def _evidence_line(rep) -> list[str]:
    """Where the baseline fails the noise test with no excess over the noise's mean square
    (a local or periodic misfit): the part of the test that finds it."""
    ev = rep.misfit.get("baseline_evidence")
    if ev is None or rep.excess_rmse_before > 0:
        return []
    return [
        "misfit within the noise's mean square, found by the noise test: whole record p = "
        f"{ev['whole_record_p']:.2g}, periodic line p = {ev['periodic_line_p']:.2g}, "
        f"{ev['windows_flagged']} window(s) flagged"
    ]


def _heldout_line(rep, unit):
    if rep.heldout_excess_before is None:
        return ""
    after = "failed" if rep.heldout_excess_after is None else f"{rep.heldout_excess_after:.3g}"
    line = f"; held out: {rep.heldout_excess_before:.3g} -> {after} {unit}"
    rms_ = rep.misfit.get("heldout_rms")
    if rep.heldout_excess_before == 0 and rms_ and rms_[1] is not None:  # the gate's figures
        line += f" (rms {rms_[0]:.3g} -> {rms_[1]:.3g} {unit})"
    return line


def report(run, state, rounds: list, settings: dict) -> DiscoveryReport:
    """The `DiscoveryReport` of a run (`discover`'s `_Run`) that ended at `state`."""
    baseline, data, y = run.baseline, run.data, run.y
    rf = y - state.prediction
    for rg in run.regions:
        rg["rmse_before"] = rms(run.r0[rg["i0"] : rg["i1"]])
        rg["rmse_after"] = rms(rf[rg["i0"] : rg["i1"]])
    misfit, v, e0, e1, held = _misfit(run, rf, state)
    unit = data.y_label.split("(")[-1].rstrip(")") if "(" in data.y_label else ""
    return DiscoveryReport(
        kind=baseline.kind,
        effects=state.effects,
        baseline_rmse=rms(run.r0),
        final_rmse=rms(rf),
        regions=run.regions,
        candidates=rounds[0] if rounds else [],
        rounds=rounds,
        strengths=effect_strengths(state),
        baseline_fit=_fit_dict(baseline, run.base_state, run.scale),
        final_fit=_fit_dict(baseline, state, run.scale),
        noise_std=run.noise.sigma,
        noise_estimated=not data.noise_std,
        rho=run.noise.rho,
        settings=settings,
        verdict=v,
        excess_rmse_before=e0,
        excess_rmse_after=e1,
        heldout_excess_before=held[0],
        heldout_excess_after=held[1],
        misfit=misfit,
        labels={"x": data.x_label, "y": data.y_label, "y_unit": unit},
        x=np.asarray(data.x),
        y=y,
        baseline_y=run.base_state.prediction,
        final_y=state.prediction,
        segment=np.asarray(data.segment),
        signals={**baseline.signals(), "model": np.asarray(state.prediction)},
        fitted=saved_record_model(state) if state.converged else None,
    )
