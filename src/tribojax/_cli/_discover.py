"""`tribojax discover FILE.csv [--out DIR] [--force]`: the discovery workflow on a user record.

Several records (loops or histories at two or more band tensions, e.g. brfd files) go to the
tension discovery instead (`tribojax.discovery.discover_tension`, history element `--model`,
default the band brake): which components of the tension law they demand; discovery.json is
`TensionDiscovery.as_dict` with "fitted_model" (the final law's model) and "source". Records at
one tension from two or more folders go to the campaign discovery (each folder a campaign,
`tribojax.discovery.discover_campaigns`): which parameters moved between them; "fitted_model"
is then the last folder's campaign.

The record (its format detected, or named by `--format`) goes to the baseline of its kind
(`_DISCOVERY`: a slip run, a loop or history, a friction curve). Writes DIR/discovery.json
(`DiscoveryReport.as_dict`, with "fitted_model" what `tribojax predict` takes, and "decimation":
how `reduce_record` reduced a long record, a loop to its first whole cycles that fit) and
DIR/discovery.png, and prints a summary.

Exit codes: 0 done; 2 malformed input or refused output; 3 the baseline fit did not converge
(discovery.json is still written, with "converged": false).
"""

from __future__ import annotations

from pathlib import Path

from .._io._records import read_record
from .._predict import fitted_model, load_model, saved_if_converged
from ..discovery import (
    curve_baseline,
    discover,
    discover_campaigns,
    discover_tension,
    loop_baseline,
    plot_curve_discovery,
    plot_discovery,
    slip_baseline,
)
from ._common import (
    CommandError,
    claim_outputs,
    decimate_factor,
    error,
    progress,
    reduce_record,
    with_band_tension,
    write_json_atomic,
)


def _plot_series(report, record, path) -> bool:
    return plot_discovery(report, path)


# per record kind: its discovery baseline and figure (a kind not listed has no baseline yet)
_DISCOVERY = {
    "slip_run": (slip_baseline, _plot_series),
    "loop": (loop_baseline, _plot_series),
    "friction_curve": (curve_baseline, plot_curve_discovery),
}


def run_discover(args) -> int:
    """Run `tribojax discover` with parsed `args`; the exit status (see the module docstring)."""
    files = args.file if isinstance(args.file, list) else [args.file]
    if len(files) > 1:
        return _run_tension(args, [Path(f) for f in files])
    if getattr(args, "model", None) is not None:
        raise CommandError("--model is for several records (a tension discovery)")
    src = Path(files[0])
    out_dir = Path(args.out)
    target, figure = out_dir / "discovery.json", out_dir / "discovery.png"
    start = load_model(args.from_model) if args.from_model else None
    with claim_outputs(src, [target, figure], force=args.force, inputs=[args.from_model]):
        record = with_band_tension(read_record(src, args.format), args.band_tension, src)
        if record.kind not in _DISCOVERY:
            raise CommandError(
                f"{src}: discovery has no baseline for a {type(record).__name__} "
                "yet; fit it with `tribojax fit`"
            )
        make_baseline, plot = _DISCOVERY[record.kind]
        record, reduction = (
            reduce_record(record, args, whole_cycles=True) if record.reducible else (record, None)
        )
        if args.initial is not None and record.kind != "loop":
            raise CommandError(
                f"--initial is for loops and histories; {src} is {record.description}"
            )
        try:
            baseline = (
                make_baseline(record)
                if args.initial is None
                else loop_baseline(record, initial=args.initial)
            )
            with progress(args, "discover"):
                report = discover(baseline, max_effects=args.max_effects, start=start)
        except ValueError as exc:
            if str(src) in str(exc) or Path(str(record.source)).name in str(exc):
                raise
            raise ValueError(f"{src}: {exc}") from exc
        data = report.as_dict()
        data["source"] = str(src)
        if report.fitted is not None:  # named by the file, with the record's conditions
            data["fitted_model"] = fitted_model(report, str(src), [record]).as_dict()
        data["decimation"] = reduction.as_dict() if reduction else None
        write_json_atomic(target, data, exclusive=not args.force)
        drew = plot(report, record, figure)
    print(f"{src}: {report.kind} record, {len(report.y)} samples")
    print(report.summary())
    print(f"wrote {target}" + (f" and {figure}" if drew else " (no figure: matplotlib missing)"))
    if not report.converged:
        return error(
            f"the baseline fit did not converge: {report.baseline_fit['message']}", status=3
        )
    return 0


def _run_tension(args, paths) -> int:
    """`tribojax discover A B ...`: the tension discovery of records at several band tensions."""
    out_dir = Path(args.out)
    target = out_dir / "discovery.json"
    for flag, name in (("from_model", "--from"), ("initial", "--initial")):
        if getattr(args, flag) is not None:
            raise CommandError(
                f"{name} is for one record; a tension discovery fits every record from rest"
            )
    with claim_outputs(paths[0], [target], force=args.force, inputs=paths[1:]):
        loops = []
        for src in paths:
            record = with_band_tension(read_record(src, args.format), args.band_tension, src)
            if record.kind != "loop":
                raise CommandError(
                    f"{src}: a discovery over several records takes loops or histories (at "
                    f"several band tensions); this is {record.description}"
                )
            loops.append(record)
        model = getattr(args, "model", None) or "band_brake"
        folders = [str(Path(p).parent) for p in paths]
        campaigns = len({lp.band_tension for lp in loops}) < 2 and len(set(folders)) > 1
        with progress(args, "discover"):
            if campaigns:  # one tension, several folders: what moved between the campaigns
                groups = {f: [lp for lp, g in zip(loops, folders) if g == f] for f in folders}
                report = discover_campaigns(groups, model, decimate=decimate_factor(args) or 1)
                final = report.final[folders[-1]]  # the last campaign's: the newest given
            else:
                report = discover_tension(loops, model, decimate=decimate_factor(args) or 1)
                final = report.final
        data = report.as_dict()
        data["source"] = "; ".join(str(p) for p in paths)
        saved = saved_if_converged(final, data["source"], loops)
        data["fitted_model"] = None if saved is None else saved.as_dict()
        write_json_atomic(target, data, exclusive=not args.force)
    if campaigns:
        print(f"{len(loops)} records in {len(set(folders))} campaigns (folders)")
    else:
        print(f"{len(loops)} records at {len(report.settings['tensions_N'])} band tensions")
    print(report.summary())
    print(f"wrote {target}")
    if not report.converged:
        return error(f"the final fit did not converge: {final.fit.message}", status=3)
    return 0
