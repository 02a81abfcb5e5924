"""Measurement: do `tribojax fit` and `tribojax discover`'s baseline agree on the same samples?

    python benchmarks/fit_vs_discover.py [--out FILE] [--quick] [--decimate N] [--oversample K]
                                         [--workdir DIR]

Records are made independently of the library's model code by the discovery study's generators:
`benchmarks/discovery_records.py` (slip runs: SciPy LSODA on the slip ODE, paper drive) and
`benchmarks/discovery_loop_records.py` (loops: own NumPy stop operator). Only clean records (no
hidden effect): two slip runs (0.6 kPa low noise with sidecar noise, s1066; 2 kPa high noise
without, s1069) and two loops (low noise with sidecar noise, s2029; high noise without, s2032);
`--quick` runs the first of each. The generators' own records are short (slip 461 samples at
5 ms; loops 200 samples per cycle): here they are sampled `--oversample` (default 4) times more
densely (the generators' N_SAMPLES / SPC raised for the call; nothing else changes: same seeds,
rigs and noise sd per sample), so that `--decimate 4` (block local quadratics) brings them back
to the study's sampling (slip 460 samples at 5 ms, loops 200 per cycle). Both commands get the
same file and the same `--decimate`, so they start from the same reduced samples (the table
shows the reduced size each command reports, "red.").

Each record is written (CSV + `<stem>.json` sidecar, `tribojax.write_slip_run`/`write_loop`)
to a temporary folder, then, as subprocesses (`tribojax` on PATH, fresh output folders):

    tribojax fit FILE --out D1 --decimate N [--alpha 1 for slip runs]  (loops: jenkins, steady)
    tribojax discover FILE --out D2 --decimate N

and D1/fit.json is compared with D2/discovery.json's "baseline_fit": for each shared parameter
|p_fit − p_disc| / se, se the larger of the two standard errors; the noise verdicts (fit.json
"noise_consistent", discovery.json misfit "baseline_consistent"); the samples each compares
(fit.json "n_data", the count discover prints) and the wall time of each command (the whole
subprocess, start-up and compilation included). Prints a table and writes `--out` (default
benchmarks-out/fit_vs_discover.json), one entry per record. A measurement, not a test: exit
status 0 whatever the results (a failed command is recorded with its exit status and stderr).

Table columns: "n fit/disc" the samples each compares (a loop's discover baseline is driven from
the first upward mean-crossing and compared from the first reversal on, so fewer than the fit's),
"red." the reduced record's size, "noise ok" the two verdicts (different tests: fit a global
reduced chi2; discover a global chi2, Fisher's g and windowed regions, any of which fails it),
"sigma" the noise sd each used (output units), "rms" the baseline's rms residual.
The code measured is the `tribojax` the script imports and the subprocesses run; to measure
another checkout, set PYTHONPATH=CHECKOUT/src (the subprocesses inherit it).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import tribojax as tj

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from benchmarks import discovery_loop_records as dlr  # noqa: E402
from benchmarks import discovery_records as dr  # noqa: E402

SLIP_SPECS = (
    dr.RecordSpec("clean", "-", 0.6, "paper", "low", True, 1066),
    dr.RecordSpec("clean", "-", 2.0, "paper", "high", False, 1069),
)
LOOP_SPECS = (
    dlr.LoopRecordSpec("clean", "-", "low", True, 2029),
    dlr.LoopRecordSpec("clean", "-", "high", False, 2032),
)
COMMAND_TIMEOUT_S = 1800
CURVE = ROOT.parent / "shared/data/real/screwdrive/driveNo1/steady_state/0.096kg"


@dataclasses.dataclass(frozen=True)
class MeasuredCurve:
    """A measured friction curve (a folder the `epos_steady` reader takes), compared as is."""

    label: str
    path: Path
    kind: str = "curve"


@contextlib.contextmanager
def _denser(module, name, value):
    """Temporarily set a generator's module constant (its record length)."""
    old = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, old)


def write_record(spec, folder: Path, oversample: int) -> tuple[Path, int]:
    """(CSV path, samples) of `spec`'s record, `oversample` times denser, written to `folder`."""
    loop = getattr(spec, "kind", "slip") == "loop"
    stem = re.sub(r"[^A-Za-z0-9]+", "_", spec.label).strip("_")
    path = folder / f"{stem}.csv"
    note = f"{spec.label}, sampled {oversample}x denser than the discovery study's record"
    if loop:
        with _denser(dlr, "SPC", dlr.SPC * oversample):
            rec = dlr.make_loop_record(spec)
        tj.write_loop(rec, path, comment=note)
        return path, len(rec.t)
    with _denser(dr, "N_SAMPLES", (dr.N_SAMPLES - 1) * oversample + 1):
        rec = dr.make_record(spec)
    tj.write_slip_run(rec, path, comment=note)
    return path, len(rec.t)


def _tribojax() -> str:
    exe = shutil.which("tribojax") or str(Path(sys.executable).with_name("tribojax"))
    return exe


def run_command(args: list[str], out_dir: Path, json_name: str) -> dict:
    """Run `tribojax ARGS` as a subprocess; its exit status, wall time, output and JSON."""
    cmd = [_tribojax(), *args]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=COMMAND_TIMEOUT_S)
        rc, stdout, stderr = proc.returncode, proc.stdout, proc.stderr
    except subprocess.TimeoutExpired as exc:
        rc, stdout, stderr = "timeout", str(exc.stdout or ""), str(exc.stderr or "")
    wall = time.perf_counter() - t0
    target = out_dir / json_name
    data = json.loads(target.read_text()) if target.exists() else None
    return {
        "command": " ".join(["tribojax", *args]),
        "rc": rc,
        "wall_s": wall,
        "stdout": stdout,
        "stderr_tail": stderr[-2000:],
        "json": data,
    }


def _reduced(data) -> int | None:
    dec = (data or {}).get("decimation") or {}
    return dec.get("samples")


def compare(spec, path: Path, n_file: int, work: Path, decimate: str) -> dict:
    """Run both commands on `path` (with `--decimate` unless it is "default": no options) and
    compare the fit with discover's baseline fit; for a loop also `tj.fit_loop(tj.read_loop(path))`
    (Python's defaults) with the command's fit."""
    kind = getattr(spec, "kind", "slip")
    loop = kind == "loop"
    d1, d2 = work / f"{path.stem}_fit", work / f"{path.stem}_discover"
    options = [] if decimate == "default" else ["--decimate", decimate]
    fit = run_command(["fit", str(path), "--out", str(d1), *options], d1, "fit.json")
    disc = run_command(["discover", str(path), "--out", str(d2), *options], d2, "discovery.json")
    fj, dj = fit["json"] or {}, disc["json"] or {}
    base = dj.get("baseline_fit") or {}
    m = re.search(r": \w+ record, (\d+) samples", disc["stdout"])
    p_fit, s_fit = fj.get("parameters") or {}, fj.get("std_errors") or {}
    p_disc, s_disc = base.get("parameters") or {}, base.get("std_errors") or {}
    params = {}
    for name in [k for k in p_fit if k in p_disc]:
        se = max(float(s_fit.get(name, float("nan"))), float(s_disc.get(name, float("nan"))))
        diff = abs(float(p_fit[name]) - float(p_disc[name]))
        params[name] = {
            "fit": p_fit[name],
            "fit_se": s_fit.get(name),
            "discover": p_disc[name],
            "discover_se": s_disc.get(name),
            "abs_diff": diff,
            "diff_over_se": diff / se if se > 0 else None,
        }
    misfit = dj.get("misfit") or {}
    python = None
    if loop and p_fit:  # Python's defaults on the same file
        py = tj.fit_loop(tj.read_loop(path), throw=False)
        python = {
            name: {
                "python": float(v),
                "cli": p_fit[name],
                "relative_diff": abs(float(v) / p_fit[name] - 1.0),
            }
            for name, v in zip(py.names, py.values)
        }
    return {
        "label": spec.label,
        "kind": kind,
        "file": path.name,
        "python_fit_loop": python,
        "samples_in_file": n_file,
        "decimate": decimate,
        "parameters": params,
        "only_in_fit": sorted(set(p_fit) - set(p_disc)),
        "only_in_discover": sorted(set(p_disc) - set(p_fit)),
        "fixed_in_fit": fj.get("fixed"),
        "noise_consistent_fit": fj.get("noise_consistent"),
        "noise_consistent_discover": misfit.get("baseline_consistent"),
        "discover_baseline_noise_p_value": misfit.get("baseline_noise_p_value"),
        "discover_verdict": dj.get("verdict"),
        "discover_effects": dj.get("effects"),
        "fit_reduced_chi2": fj.get("reduced_chi2"),
        "n_fit": fj.get("n_data"),
        "n_discover": int(m.group(1)) if m else None,
        "reduced_fit": _reduced(fj),
        "reduced_discover": _reduced(dj),
        "sigma_fit": fj.get("sigma"),
        "sigma_discover": dj.get("noise_std"),
        "sigma_source_fit": fj.get("sigma_source"),
        "noise_estimated_discover": dj.get("noise_estimated"),
        "rms_fit": fj.get("rms_residual"),
        "rms_discover": dj.get("baseline_rmse"),
        "converged_fit": fj.get("converged"),
        "converged_discover": base.get("converged"),
        "model_fit": fj.get("model"),
        "wall_fit_s": fit["wall_s"],
        "wall_discover_s": disc["wall_s"],
        "rc_fit": fit["rc"],
        "rc_discover": disc["rc"],
        "command_fit": fit["command"],
        "command_discover": disc["command"],
        "stderr_fit": fit["stderr_tail"] if fit["rc"] != 0 else "",
        "stderr_discover": disc["stderr_tail"] if disc["rc"] != 0 else "",
    }


def _g(x, fmt=".4g") -> str:
    if x is None:
        return "-"
    if isinstance(x, bool):
        return str(x)
    return format(x, fmt)


def table(rows) -> str:
    lines = [f"{'record':34s} {'param':6s} {'fit ± se':>22s} {'discover ± se':>22s} {'|Δ|/se':>8s}"]
    for r in rows:
        params = r["parameters"] or {"(none)": None}
        for i, (name, p) in enumerate(params.items()):
            lab = r["label"] if i == 0 else ""
            if p is None:
                lines.append(f"{lab:34s} {name:6s}")
                continue
            a = f"{_g(p['fit'])} ± {_g(p['fit_se'], '.2g')}"
            b = f"{_g(p['discover'])} ± {_g(p['discover_se'], '.2g')}"
            lines.append(
                f"{lab:34s} {name:6s} {a:>22s} {b:>22s} {_g(p['diff_over_se'], '8.2f'):>8s}"
            )
    lines.append("")
    lines.append(
        f"{'record':34s} {'n fit/disc':>11s} {'red. fit/disc':>13s} "
        f"{'noise ok fit/disc':>17s} {'sigma fit/disc':>19s} {'rms fit/disc':>19s} "
        f"{'wall s fit/disc':>15s} {'rc':>5s}"
    )
    for r in rows:
        n = f"{_g(r['n_fit'])}/{_g(r['n_discover'])}"
        red = f"{_g(r['reduced_fit'])}/{_g(r['reduced_discover'])}"
        ok = f"{_g(r['noise_consistent_fit'])}/{_g(r['noise_consistent_discover'])}"
        sig = f"{_g(r['sigma_fit'], '.3g')}/{_g(r['sigma_discover'], '.3g')}"
        rms = f"{_g(r['rms_fit'], '.3g')}/{_g(r['rms_discover'], '.3g')}"
        wall = f"{r['wall_fit_s']:.0f}/{r['wall_discover_s']:.0f}"
        rc = f"{r['rc_fit']}/{r['rc_discover']}"
        lines.append(
            f"{r['label']:34s} {n:>11s} {red:>13s} {ok:>17s} {sig:>19s} {rms:>19s} "
            f"{wall:>15s} {rc:>5s}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="benchmarks-out/fit_vs_discover.json", help="JSON written")
    ap.add_argument("--quick", action="store_true", help="one slip run and one loop")
    ap.add_argument(
        "--decimate",
        default="default",
        help="--decimate of both commands (default: none given, as a new user runs them)",
    )
    ap.add_argument(
        "--curve",
        default=str(CURVE),
        help="a measured friction curve compared too (default the screw drive's "
        "0.096 kg steady-state folder; skipped when absent)",
    )
    ap.add_argument(
        "--oversample",
        type=int,
        default=4,
        help="records sampled this many times denser than the study's (default 4)",
    )
    ap.add_argument(
        "--workdir",
        default=None,
        help="keep the records and command outputs here (default: a temporary folder, removed)",
    )
    args = ap.parse_args(argv)
    specs = [*SLIP_SPECS[:1], *LOOP_SPECS[:1]] if args.quick else [*SLIP_SPECS, *LOOP_SPECS]
    curve = Path(args.curve)
    if curve.exists():
        specs.append(
            MeasuredCurve(f"measured curve {curve.parent.parent.name}/{curve.name}", curve)
        )
    tmp = None
    if args.workdir:
        work = Path(args.workdir)
        work.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="fit_vs_discover_")
        work = Path(tmp.name)
    rows = []
    t_start = time.perf_counter()
    try:
        for spec in specs:
            try:
                path, n = (
                    (spec.path, len(tj.read_record(spec.path)))
                    if isinstance(spec, MeasuredCurve)
                    else write_record(spec, work, args.oversample)
                )
                row = compare(spec, path, n, work, args.decimate)
            except Exception as exc:  # a measurement: record and go on
                row = {"label": spec.label, "error": f"{type(exc).__name__}: {exc}"}
                print(f"{spec.label}: {row['error']}", flush=True)
                rows.append(row)
                continue
            rows.append(row)
            print(
                f"{row['label']}: fit {row['wall_fit_s']:.0f} s (rc {row['rc_fit']}), "
                f"discover {row['wall_discover_s']:.0f} s (rc {row['rc_discover']})",
                flush=True,
            )
    finally:
        if tmp is not None:
            tmp.cleanup()
    ok_rows = [r for r in rows if "error" not in r]
    text = table(ok_rows)
    print()
    print(text)
    for r in ok_rows:
        for name, c in (r.get("python_fit_loop") or {}).items():
            print(
                f"{r['label']}: tj.fit_loop {name} = {c['python']:.8g}, CLI {c['cli']:.8g} "
                f"(relative difference {c['relative_diff']:.1e})"
            )
    res = {
        "what": "tribojax fit vs tribojax discover's baseline fit on the same records",
        "tribojax_module": str(Path(tj.__file__).resolve().parent),
        "tribojax_executable": _tribojax(),
        "decimate": args.decimate,
        "oversample": args.oversample,
        "quick": args.quick,
        "total_wall_s": time.perf_counter() - t_start,
        "records": rows,
    }
    out = Path(args.out)
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(res, indent=1, default=str))
        print(f"wrote {out}")
    except OSError as exc:
        print(f"could not write {out}: {exc}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    main()
    sys.exit(0)
