"""`tribojax fit FILE.csv`: fit a friction model to a user's slip run or hysteresis loop.

    tribojax fit run.csv [--out DIR] [--alpha VALUE|free]  # PreSlipLuGre F_s, K_τ, C_τ (α = 1)
    tribojax fit loop.csv [--out DIR] [--element jenkins|mindlin]  # μN and K_d (loop model)
    tribojax fit RECORD --model jenkins|mindlin|lugre|bouc_wen|best  # through the history
    tribojax fit DRIVE/steady_state/0.096kg [--model lugre]   # Coulomb + viscous (LuGre steady law)
    tribojax fit RECORD --from DIR/discovery.json  # a saved model + its effects, refitted

The record type comes from the file (`tribojax.read_record`: CSV header, brfd JSON, EPOS export
or a folder of them) or `--format`; measured records are fitted by `_fit_real`. Writes DIR/fit.json
(`tribojax.FitReport`; "decimation" and "full_record": `_fit_reduced`; "fitted_model": the model as
`tribojax predict` takes it) and DIR/fit.png (data and model, residuals). Exit status: 0
converged, 1 not converged (fit.json still written, with "converged": false), 2 bad input
(malformed file, fewer data than parameters, an output that exists or would overwrite the input).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

from .._io._records import read_record
from .._model._history_model import HISTORY_MODELS, law_spec
from .._predict import RECORD_KINDS, SAVED_KEY, FitReport, load_model
from .._predict._fit_methods import RecordModel, Saved
from ._common import (
    FAILED,
    CommandError,
    claim_outputs,
    decimate_factor,
    error,
    plot_model_and_residual,
    progress,
    warn,
    with_band_tension,
    write_json_atomic,
)
from ._fit_real import HISTORY_CHOICES, fit_curve_record, fit_history_record
from ._fit_reduced import fit_loop_reduced, fit_reduced, fit_slip

# record kinds `tribojax fit` does not fit, and what to do instead
_NOT_FITTED = {
    "friction_transient": "fit its steady curve first (tribojax.fit_transient in Python)",
}


def run_fit(args) -> int:
    """Run `tribojax fit` with parsed `args`; the exit status (see the module docstring)."""
    paths = [Path(f) for f in args.file]
    path = paths[0]
    out = Path(args.out) if args.out is not None else Path("tribojax-out") / f"fit-{path.stem}"
    if args.max_steps is not None and args.max_steps < 1:
        return error(f"--max-steps = {args.max_steps} must be at least 1")
    start = _parse_start(args.start)
    with claim_outputs(
        path, [out / "fit.json", out / "fit.png"], force=args.force, inputs=[args.from_model]
    ):
        records = [
            with_band_tension(read_record(p, args.format), args.band_tension, p) for p in paths
        ]
        full = records[0]
        if full.kind in _NOT_FITTED:
            return error(f"{path} is {full.description}: {_NOT_FITTED[full.kind]}")
        if args.model == "record" and full.kind == "loop":  # a loop's record model
            args.model = "history"
        if args.alpha is not None and full.kind != "slip_run":
            return error(f"--alpha is for slip runs; {path} is {full.description}")
        if len(records) > 1:
            _check_joint(records, paths, args)
        _check_n_starts(records, args)
        t0 = time.perf_counter()
        fits = _fit_from_model if args.from_model else _FITS[full.kind]
        saved = load_model(args.from_model) if args.from_model else None
        if args.free and (saved is None or saved.kind != "history"):
            return error("--free is for --from MODEL.json of a history model (--model ELEMENT)")
        with progress(args, "fit") as bar:
            if saved is not None and saved.kind == "history":
                result, curves = _fit_from_history(records, saved, args, start)
            elif len(records) > 1:  # one element's parameters (+ f0) for all of them
                result, curves = fit_history_record(
                    records,
                    args.model or "best",
                    args.max_steps,
                    start,
                    decimate_factor(args) or 1,
                    args.mixed_scales,
                    args.n_starts,
                    args.tension_law,
                )
            else:
                result, curves = fits(full, args, start, bar.note)
        result["wall_time_s"] = time.perf_counter() - t0
        flat = {
            k
            for d in result.get("unidentifiable", [])
            for k, c in d["direction"].items()
            if abs(c) > 1e-3
        }
        if flat and result.get(SAVED_KEY) is not None:  # not a result: no model to predict with
            result[SAVED_KEY] = None
            result["not_a_result"] = f"the data do not determine {', '.join(sorted(flat))}"
        write_json_atomic(out / "fit.json", result, exclusive=not args.force)
        drew = plot_model_and_residual(
            out / "fit.png",
            curves,
            f"{Path(result['source']).name}: {result['model']}",
            ("t (s)", f"model − data ({result['residual_unit']})"),
            title_size=9,
        )
    what = path if len(paths) == 1 else f"{len(paths)} records ({path.name}, ...)"
    print(
        f"{result['kind']} {what}: {result['n_data']} samples, fitted {', '.join(result['fitted'])}"
    )
    for name in result["fitted"]:
        v, s = result["parameters"][name], result["std_errors"][name]
        print(f"  {name:6s} = {v:.6g} ± {math.inf if name in flat else s:.2g}")
    unit = result["residual_unit"]
    if result.get("selected_by") == "bic":  # --model best: every candidate, the chosen marked
        print("  candidates, the lowest BIC chosen (*):")
        for name, c in sorted(result["candidates"].items(), key=lambda kv: kv[1]["bic"]):
            mark = "*" if name == result["model"] else " "
            note = "" if c["converged"] else "  (not converged)"
            print(f"    {mark} {name:10s} NRMSE {c['nrmse']:.4f}  BIC {c['bic']:.6g}{note}")
    print(
        f"  rms residual {result['rms_residual']:.4g} {unit}; converged: "
        f"{result['converged']} ({result['steps']} steps, {result['wall_time_s']:.1f} s)"
    )
    if "full_record" in result:
        fr = result["full_record"]
        chi2 = f", reduced chi2 {fr['reduced_chi2']:.4g}" if fr["reduced_chi2"] else ""
        rms = fr["rms_residual"]
        print(f"  on all {fr['n_data']} samples: rms residual {rms:.4g} {unit}{chi2}")
    print(f"wrote {out / 'fit.json'}" + (f" and {out / 'fit.png'}" if drew else ""))
    for text in uncertainty_warnings(result):
        warn(text)
    if not result["converged"]:
        return error(f"the fit did not converge: {result['message']}", status=FAILED)
    if flat:  # a flat direction: the value printed is not a result
        which = ", ".join(sorted(flat))
        return error(
            f"the fit stopped where the data do not determine {which} (the "
            "model does not respond to it there, e.g. an element that never slips): "
            "not a result; give another --start",
            status=FAILED,
        )
    return 0


def _parse_start(items) -> dict:
    """`--start NAME=VALUE ...` as a dict of floats (CommandError naming a malformed item)."""
    start = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if sep and name.strip() in start:
            raise CommandError(f"--start {item!r}: {name.strip()} is given twice")
        try:
            start[name.strip()] = float(value)
        except ValueError:
            sep = ""
        if sep and not math.isfinite(start[name.strip()]):
            raise CommandError(f"--start {item!r}: the value must be a finite number")
        if not sep or not name.strip():
            raise CommandError(f"--start {item!r}: expected NAME=VALUE with a number")
    return start


HARDLY_EXPLAINED = 0.9
"""A record of a joint fit with an NRMSE at or above this (the model explains under 19 % of its
variance) is named in a warning."""


def uncertainty_warnings(result: dict) -> list[str]:
    """Warnings for a fit result whose noise or identifiability is in doubt."""
    out = []
    if result.get("noise_consistent") is False and result["reduced_chi2"] < 1.0:
        out.append(
            f"the residuals are far below the stated noise (reduced chi2 = "
            f"{result['reduced_chi2']:.3g}): it is overstated, and the standard errors it gives "
            "are too large"
        )
    elif result.get("noise_consistent") is False:
        out.append(
            f"the residuals contradict the stated noise (reduced chi2 = "
            f"{result['reduced_chi2']:.3g}): standard errors are scaled by the residual"
        )
    for r in result.get("records", []):
        if r["nrmse"] >= HARDLY_EXPLAINED:
            than = "worse than" if r["nrmse"] >= 1.0 else "hardly better than"
            out.append(
                f"{r['source']}: NRMSE {r['nrmse']:.5g} — the joint model fits this "
                f"record {than} its mean force would (a constant: NRMSE 1)"
            )
    for d in result.get("unidentifiable", []):
        combo = " ".join(f"{v:+.3g}*{k}" for k, v in d["direction"].items() if abs(v) > 1e-3)
        out.append(
            f"not identifiable from these data: the direction {combo} (relative singular value "
            f"{d['relative_singular_value']:.2g}); its standard errors are not finite"
        )
    return out


def _fit_slip_record(run, args, start, note):
    """A slip run: reduced as `--decimate` asks, then the pre-slip LuGre model."""
    return fit_reduced(run, args, start, note, fit_slip)


def _check_joint(records, paths, args) -> None:
    """Several records are fitted together only as loops or histories, through an element."""
    for rec, p in zip(records, paths):
        if rec.kind != "loop":
            raise CommandError(
                f"{p} is {rec.description}: several records are fitted together "
                "only as loops or displacement histories"
            )
    if args.from_model is not None:
        raise CommandError("--from takes one record")
    if args.model not in (None, *HISTORY_CHOICES, "best"):
        raise CommandError(
            f"--model {args.model}: several records are fitted through their "
            f"histories; use {', '.join(HISTORY_CHOICES)} or best"
        )


def _check_n_starts(records, args) -> None:
    """`--n-starts` only where a Bouc–Wen history fit runs (bouc_wen, or best's candidates)."""
    if args.n_starts is None:
        return
    full = records[0]
    by_default = len(records) > 1 or (full.kind == "loop" and not full.periodic)
    model = args.model or ("best" if by_default else None)
    if full.kind != "loop" or model not in ("bouc_wen", "best"):
        raise CommandError(
            "--n-starts applies to a history fit with --model bouc_wen or best, not to "
            f"{full.description} with --model {args.model or 'its default'}"
        )


def _fit_loop_record(loop, args, start, note):
    """A loop: through its history (`--model` an element or best; default for a non-periodic
    history), else reduced as `--decimate` asks and fitted with the loop model of --element."""
    model = args.model
    if model in (*HISTORY_CHOICES, "best") or (model is None and not loop.periodic):
        return fit_history_record(
            loop,
            model or "best",
            args.max_steps,
            start,
            decimate_factor(args) or 1,
            n_starts=args.n_starts,
            tension_law=args.tension_law,
        )
    return fit_reduced(loop, args, start, note, fit_loop_reduced)


def _fit_curve_record(curve, args, start, note):
    """A friction curve (a few points, never reduced): by default its record model, Coulomb +
    viscous friction (`curve_baseline`, the baseline `discover` fits); `--model lugre`: the
    LuGre steady law with a direction asymmetry."""
    if args.model in (None, "record"):
        if start:
            raise CommandError(
                "--start does not apply to a friction curve's record model (its "
                "start is the linear least-squares fit)"
            )
        fit = RecordModel().fit(curve, max_steps=args.max_steps, throw=False)
        return _record_model_result(
            fit, curve, "Coulomb + viscous friction (the curve's record model)", units=curve.units
        )
    return fit_curve_record(curve, args.model, args.max_steps)


# the fit of each record kind (those in _NOT_FITTED excepted)
_FITS = {
    "slip_run": _fit_slip_record,
    "loop": _fit_loop_record,
    "friction_curve": _fit_curve_record,
}


def _fit_from_model(full, args, start, note):
    """`--from MODEL.json`: the saved model with its effects fitted to the record (`refit`)."""
    if start or args.alpha is not None:
        raise CommandError(
            "--start and --alpha do not apply with --from (the saved model is the "
            "start and says what is held)"
        )
    model = load_model(args.from_model)
    if model.kind not in RECORD_KINDS:
        raise CommandError(
            f"--from {args.from_model}: a {model.kind} model; --from takes a "
            "slip, loop or curve model (a history: --model ELEMENT)"
        )
    fit = Saved(model).fit(full, max_steps=args.max_steps, throw=False)
    return _record_model_result(
        fit, full, f"{model.kind} model from {args.from_model}", start_model=model.as_dict()
    )


def _fit_from_history(records, saved, args, start):
    """`--from MODEL.json` of a history model: its element refitted on the records from the
    saved values, `--free` refitted and the rest held there (default: the element's parameters
    and f0 free, a tension law held), the slip forces at the saved model's tension."""
    if start:
        raise CommandError("--start does not apply with --from (the saved model is the start)")
    names = list(saved.parameters)  # the element's, f0, any tension law's (`load_model` checked)
    element = saved.options["element"]
    own = [n for n, _ in HISTORY_MODELS[element]]
    free = list(args.free or own)
    wrong = [n for n in free if n not in names]
    if wrong:
        raise CommandError(
            f"--free {' '.join(wrong)}: not a parameter of {args.from_model} ({', '.join(names)})"
        )
    tensions = {r.band_tension for r in records if r.band_tension is not None}
    fits_law = {n for n, _ in law_spec(element, len(tensions), args.tension_law)}
    unfit = [n for n in free if n not in own and n not in fits_law]
    if unfit:
        raise CommandError(
            f"--free {' '.join(unfit)}: records at {len(tensions)} band tension(s) do not "
            f"determine it (tension law {args.tension_law!r}); leave it held"
        )
    fixed = {n: saved.parameters[n] for n in names if n not in free}
    result, curves = fit_history_record(
        records,
        element,
        args.max_steps,
        {n: saved.parameters[n] for n in free},
        decimate_factor(args) or int(saved.options.get("decimate", 1)),
        args.mixed_scales,
        None,
        args.tension_law,
        fixed=fixed,
        band_tension=saved.options.get("band_tension_N"),
    )
    result.update(start_model=saved.as_dict(), free=free)
    return result, curves


def _record_model_result(fit, full, label, **extra):
    """fit.json (`FitReport.of_record_model`) and the plot curves of a fit of the record's
    model (with any effects): the residuals in the model's output unit (a curve's weighted
    friction)."""
    report = FitReport.of_record_model(fit, full, label, **extra)
    x_name, x = RECORD_KINDS[fit.model.kind].axis(fit.model)
    curves = dict(
        x=x,
        data=report.measured,
        model=fit.prediction,
        xlabel=x_name,
        ylabel=report.unit,
        resid_x=x,
        resid=report.residuals,
    )
    return report.as_dict(), curves
