"""`tribojax predict MODEL RECORD [--out DIR]`: a fitted model on a record it never saw.

MODEL is a fit.json or discovery.json (its "fitted_model": the record model with the effects
discovery added, or a history fit's element) or a saved model; RECORD any record of the model's
kind (`tribojax.read_record`; `--format` to name it). Nothing is refitted. Writes
DIR/prediction.json, DIR/prediction.csv (docs/fitting.md, "A fitted model as a value") and
DIR/prediction.png. Exit status: 0 done, 1 the model is not finite on the record, 2 bad input
(a model file of another version or without a model, a record of another kind, an output that
exists).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .._io._files import write_text_atomic
from .._io._records import read_record
from .._predict import ExtrapolationWarning, load_model, predict
from .._predict._prediction import describe_beyond
from ._common import (
    FAILED,
    CommandError,
    claim_outputs,
    plot_model_and_residual,
    refused_outputs,
    warn,
    with_band_tension,
    write_json_atomic,
)


def run_predict(args) -> int:
    """Run `tribojax predict` with parsed `args`; the exit status (module docstring)."""
    model_path, src = Path(args.model), Path(args.file)
    out = Path(args.out) if args.out is not None else Path("tribojax-out") / f"predict-{src.stem}"
    targets = [out / "prediction.json", out / "prediction.csv", out / "prediction.png"]
    why = refused_outputs(model_path, targets, force=args.force)
    if why:
        raise CommandError(why)
    model = load_model(model_path)
    with claim_outputs(src, targets, force=args.force):
        record = with_band_tension(read_record(src, args.format), args.band_tension, src)
        with warnings.catch_warnings():  # said below, once, as the command's warnings
            warnings.simplefilter("ignore", ExtrapolationWarning)
            pred = predict(model, record, initial=args.initial)
        if not (np.all(np.isfinite(pred.predicted)) and np.isfinite(pred.nrmse)):
            raise CommandError(
                "the model is not finite on this record (no file written)", status=FAILED
            )
        data = pred.as_dict()
        data["model_file"] = str(model_path)
        data["initial"] = args.initial or model.options.get("initial", "rest")
        scaled = model.options.get("band_tension_N") is not None
        if scaled:  # the slip forces scale from the model's tension to the record's
            data["band_tension_N"] = record.band_tension
            data["model_band_tension_N"] = model.options["band_tension_N"]
        write_json_atomic(targets[0], data, exclusive=not args.force)
        table = np.column_stack([pred.x, pred.measured, pred.predicted])
        rows = "\n".join(",".join(f"{v:.17g}" for v in row) for row in table)
        write_text_atomic(targets[1], ",".join(pred.columns()) + "\n" + rows + "\n")
        curves = dict(
            x=pred.x,
            data=pred.measured,
            model=pred.predicted,
            xlabel=pred.x_name,
            ylabel=pred.unit,
            resid_x=pred.x,
            resid=pred.predicted - pred.measured,
        )
        title = f"{Path(pred.record).name}: {pred.model.kind} model, NRMSE {pred.nrmse:.3g}"
        drew = plot_model_and_residual(
            targets[2],
            curves,
            title,
            (pred.x_name, f"predicted − measured ({pred.unit})"),
            labels=("measured", "predicted"),
        )
    print(
        f"{model.kind} model ({model_path}) on {src}: {pred.x.size} samples, "
        f"NRMSE {pred.nrmse:.4g}, rms error {pred.rms_error:.4g} {pred.unit}"
    )
    if scaled:
        print(
            f"slip forces scaled by the band tension: {data['model_band_tension_N']:.4g} N "
            f"(fit) -> {record.band_tension:.4g} N (record)"
        )
    print(f"wrote {targets[0]}, {targets[1].name}" + (f" and {targets[2].name}" if drew else ""))
    for d in pred.extrapolation or ():
        warn(describe_beyond(d))
    if pred.extrapolation is None:
        warn(
            f"{model_path} saves no fitted range (written before it was kept): whether the "
            "record lies beyond the conditions it was fitted on is not known"
        )
    return 0
