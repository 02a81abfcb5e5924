"""The `tribojax` command line.

tribojax reproduce [--out DIR]   wang2022 Table 3 (published inputs and calibrated), JSON + figure
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path


def _json_default(obj):
    import numpy as np

    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    raise TypeError(f"cannot serialise {type(obj).__name__}")


def _finite(obj):
    """Replace NaN/inf by None so the output is strict JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


def write_json_atomic(path: Path, data) -> None:
    """Write strict JSON to `path` via a temporary file, so a failure leaves no partial file."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(_finite(data), f, indent=2, default=_json_default, allow_nan=False)
        f.write("\n")
    os.replace(tmp, path)


def _print_table3(rows, out=sys.stdout) -> None:
    head = (
        f"{'kPa':>5} {'F/N':>8} | {'F_s paper':>9} {'calib':>7} {'publ.':>7} | "
        f"{'K_tau paper':>11} {'calib':>9} {'publ.':>9} | {'C_tau paper':>11} {'calib':>7} | "
        f"{'z_max paper':>11} {'calib':>7}"
    )
    print(head, file=out)
    print("-" * len(head), file=out)
    for r in rows:
        p, c, u = r["paper"], r["calibrated"], r["published_inputs"]
        print(
            f"{r['vacuum_kPa']:5.1f} {r['load_N']:8.4f} | {p['Fs_N']:9.4f} {c['Fs_N']:7.4f} "
            f"{u['Fs_N']:7.3f} | {p['Ktau_N_per_m']:11.4e} {c['Ktau_N_per_m']:9.3e} "
            f"{u['Ktau_N_per_m']:9.2e} | {p['Ctau_Ns_per_m']:11.2f} {c['Ctau_Ns_per_m']:7.1f} | "
            f"{p['zmax_nm']:11.3f} {c['zmax_nm']:7.3f}",
            file=out,
        )


def _plot_table3(rows, path: Path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: figure skipped (pip install 'tribojax[plot]')")
        return False
    load = [r["load_N"] for r in rows]
    keys = [
        ("Fs_N", "max static friction F_s (N)"),
        ("Ktau_N_per_m", "tangential stiffness K_τ (N/m)"),
        ("Ctau_Ns_per_m", "tangential damping C_τ (N s/m)"),
        ("zmax_nm", "max tangential deformation z_max (nm)"),
    ]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5), constrained_layout=True)
    for ax, (key, label) in zip(axes.flat, keys):
        ax.plot(load, [r["paper"][key] for r in rows], "ko", label="wang2022 Table 3")
        ax.plot(load, [r["calibrated"][key] for r in rows], "C0-", label="calibrated (G, μ_t, σ_s)")
        ax.plot(load, [r["published_inputs"][key] for r in rows], "C3--", label="published inputs")
        ax.set_yscale("log")
        ax.set_xlabel("normal load F (N)")
        ax.set_ylabel(label)
    axes.flat[0].legend(fontsize=8)
    fig.suptitle("wang2022 Table 3: fractal contact parameters of the reticle/chuck pair")
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def _reproduce_slip_tables(result: dict, out_dir: Path) -> None:
    """wang2022 Tables 4–7 (slip dynamics) into `result`, a table on screen and table4to7.png."""
    from ._reproduce_slip import plot_figure10, print_tables4to7, reproduce_tables4to7

    print("wang2022 Tables 4-7: slip simulations, alpha fitted to Tables 4 and 6 ...")
    slip = reproduce_tables4to7()
    print_tables4to7(slip)
    result.update(slip)
    out_dir.mkdir(parents=True, exist_ok=True)
    if plot_figure10(slip, out_dir / "figure10.png"):
        print(f"wrote {out_dir / 'figure10.png'}")


def cmd_reproduce(args) -> int:
    from ._reproduce import calibrate_table3, max_rel_error, reproduce_table3

    out_dir = Path(args.out)
    t0 = time.perf_counter()
    print("wang2022 Table 3: calibrating G, mu_t, sigma_s (optimistix Levenberg-Marquardt) ...")
    fit = calibrate_table3()
    result = reproduce_table3(fit)
    rows = result["table3"]
    _print_table3(rows)
    cal = result["table3_calibration"]
    print(
        "calibrated: "
        + ", ".join(
            f"{k} = {v:.4g} ± {cal['std_errors'][k]:.2g}" for k, v in cal["parameters"].items()
        )
        + f" (M = {cal['fixed']['M']:g}; converged: {cal['converged']}, {cal['steps']} steps)"
    )
    errs = {
        (key, rng): max_rel_error(rows, key, rng)
        for key in ("Fs_N", "Ktau_N_per_m")
        for rng in ((0.6, 10.0), (20.0, 20.0))
    }
    for (key, rng), e in errs.items():
        where = f"{rng[0]:g} kPa" if rng[0] == rng[1] else f"{rng[0]:g}-{rng[1]:g} kPa"
        print(f"max |calibrated/paper - 1| of {key} at {where}: {100 * e:.1f} %")
    result["table3_acceptance"] = {
        "Fs_max_rel_error_0p6_to_10kPa": errs[("Fs_N", (0.6, 10.0))],
        "Ktau_max_rel_error_0p6_to_10kPa": errs[("Ktau_N_per_m", (0.6, 10.0))],
        "Fs_rel_error_20kPa": errs[("Fs_N", (20.0, 20.0))],
        "Ktau_rel_error_20kPa": errs[("Ktau_N_per_m", (20.0, 20.0))],
    }
    if not cal["converged"]:
        print(f"WARNING: the calibration did not converge: {cal['message']}", file=sys.stderr)
    _reproduce_slip_tables(result, out_dir)
    from . import __version__

    result["tribojax_version"] = __version__
    json_path = out_dir / "reproduction.json"
    write_json_atomic(json_path, result)
    fig_path = out_dir / "table3.png"
    wrote_fig = _plot_table3(rows, fig_path)
    print(f"wrote {json_path}" + (f" and {fig_path}" if wrote_fig else ""))
    print(f"done in {time.perf_counter() - t0:.1f} s")
    return 0 if cal["converged"] else 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="tribojax", description="Rough-surface contact and friction models (JAX)."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser("reproduce", help="reproduce wang2022's tables from bundled data")
    rep.add_argument("--out", default="tribojax-out", help="output folder (default tribojax-out)")
    rep.set_defaults(func=cmd_reproduce)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
