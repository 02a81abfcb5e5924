"""The `tribojax` command line.

tribojax reproduce [--out DIR]   wang2022 Table 3 (published inputs and calibrated), Tables 4–7
                                 (slip, α = 1 and fitted; full-chain fit of D, G, μ_t to the
                                 measured slips) and wu2015 vs Eq 7: JSON + figures
tribojax contact (--topography FILE | --D D --G G) --load N [...]   surface → D, G → F_s, K_τ, C_τ
tribojax hysteresis [...]        K̄, C̄ (and K_eq, C_eq) of a Jenkins/Mindlin/LuGre element
tribojax fit FILE.csv [--out DIR] fit a user's slip run or hysteresis loop: JSON + plot
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from .. import __version__
from .. import _presets as P
from .._contact._contact import FractalContact
from .._contact._surface import FractalSurface
from .._fit import _chain as chain_fit
from .._plot import pyplot, save_figure
from .._presets import wang2022_pair
from .._reproduce._table3 import calibrate_table3, max_rel_error, reproduce_table3
from .._reproduce._tables4to7 import plot_figure10, print_tables4to7, reproduce_tables4to7
from .._reproduce._wu2015 import plot_wu2015, wu2015_comparison
from .._roughness._estimate import estimate_fractal
from .._roughness._topography import read_topography
from . import _discover, _fit, _frf, _hysteresis
from ._common import write_json_atomic

__all__ = ["main", "write_json_atomic"]


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
    plt = pyplot("figure")
    if plt is None:
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
    save_figure(fig, path)
    return True


def _reproduce_slip_tables(result: dict, out_dir: Path) -> None:
    """wang2022 Tables 4–7 (slip dynamics) into `result`, a table on screen and table4to7.png."""
    print("wang2022 Tables 4-7: slip simulations, alpha fitted to Tables 4 and 6 ...")
    slip = reproduce_tables4to7()
    print_tables4to7(slip)
    result.update(slip)
    out_dir.mkdir(parents=True, exist_ok=True)
    if plot_figure10(slip, out_dir / "figure10.png"):
        print(f"wrote {out_dir / 'figure10.png'}")


def _reproduce_fit_measured(result: dict, start=None) -> bool:
    """The full-chain fit to the measured Tables 4–7 into result["fit_measured"]; True if it
    converged. One start here; the multi-start study is `python -m fitting.wang2022_slip`."""
    print("wang2022 Tables 4-7 (measured): full-chain fit of D, G, mu_t (LM through diffrax) ...")
    fit = chain_fit.fit_measured_slips(start, progress=True)
    block = fit.as_dict()
    block["paper_theory_rms_relative_residual"] = chain_fit.rms_relative(
        chain_fit.paper_theory_slips(), chain_fit.measured_slips()
    )
    block["symmetric_model_bound_rms_relative_residual"] = chain_fit.symmetric_bound()[
        "rms_relative_residual"
    ]
    block["uncertainty_model"] = (
        "equal relative uncertainty per measured cell, estimated from the fit "
        "(residual = model/measured - 1); metric: RMS relative residual over the 24 cells"
    )
    block["multistart_study"] = "python -m fitting.wang2022_slip"
    result["fit_measured"] = block
    print(
        "fit_measured: "
        + ", ".join(
            f"{k} = {block['parameters'][k]:.4g} ± {block['std_errors'][k]:.2g}" for k in fit.free
        )
        + f"; RMS rel. residual {block['rms_relative_residual']:.3f} (paper theory "
        f"{block['paper_theory_rms_relative_residual']:.3f}, any symmetric model >= "
        f"{block['symmetric_model_bound_rms_relative_residual']:.3f}); converged: "
        f"{fit.converged}, {fit.fit.steps} steps, {fit.wall_s:.1f} s"
    )
    if not fit.converged:
        print(
            f"ERROR: the full-chain fit to the measured slips did not converge: {fit.fit.message}",
            file=sys.stderr,
        )
    return fit.converged


def cmd_reproduce(args) -> int:
    """`tribojax reproduce`: 0 when every fit converged, else 1."""
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
    measured_ok = _reproduce_fit_measured(result)
    result["tribojax_version"] = __version__
    result["wu2015"] = _reproduce_wu2015(out_dir)
    json_path = out_dir / "reproduction.json"
    write_json_atomic(json_path, result)
    fig_path = out_dir / "table3.png"
    wrote_fig = _plot_table3(rows, fig_path)
    print(f"wrote {json_path}" + (f" and {fig_path}" if wrote_fig else ""))
    print(f"done in {time.perf_counter() - t0:.1f} s")
    alpha_ok = bool(result.get("alpha_fit", {}).get("converged", True))
    if not alpha_ok:
        print("WARNING: the alpha fit to Tables 4 and 6 did not converge", file=sys.stderr)
    return 0 if cal["converged"] and alpha_ok and measured_ok else 1


CONTACT_DEFAULTS = dict(
    M=P.CALIBRATED_M,
    gamma=P.WANG2022_GAMMA,
    sigma_s=P.CALIBRATED_SIGMA_S,
    mu_t=P.CALIBRATED_MU_T,
    tangential_load=P.WANG2022_TANGENTIAL_LOAD_N,
    mass=P.WANG2022_RETICLE_MASS_KG,
)  # wang2022 pair, Table-3-calibrated constants (tribojax._presets)


def cmd_contact(args) -> int:
    """`tribojax contact`: F_s, K_τ, C_τ at each load; 0 when every contact solve converged."""
    result = {"assumed": {}}
    if args.topography is not None:
        if args.D is not None or args.G is not None:
            raise SystemExit("give either --topography or --D/--G, not both")
        topo = read_topography(args.topography, unit=args.unit, dx=args.dx)
        est = estimate_fractal(
            topo, args.method, band=args.band, M=int(args.M), min_decades=args.min_decades
        )
        D, G = est.D, est.G
        result["surface"] = est.as_dict()
        print(
            f"{topo.source}: D = {D:.4f} ± {est.D_std:.4f}, G = {G:.4g} m (± {est.log10G_std:.2f} "
            f"in log10) by {est.method}, band {est.band[0]:.3g}-{est.band[1]:.3g} m"
        )
    elif args.D is not None and args.G is not None:
        D, G = args.D, args.G
        result["surface"] = {"D": D, "G": G, "method": "given"}
    else:
        raise SystemExit("give --topography FILE, or both --D and --G")
    for k in CONTACT_DEFAULTS:
        result["assumed"][k] = getattr(args, k)
    result["assumed"]["materials"] = (
        "wang2022 Table 2 pair (E* 41.28 GPa, G' 9.158 GPa, H 1.372 GPa)"
    )
    print(
        "assumed: "
        + ", ".join(f"{k} = {v:g}" for k, v in result["assumed"].items() if not isinstance(v, str))
        + "; wang2022 Table 2 materials"
    )
    pair = wang2022_pair(sigma_s=args.sigma_s)
    model = FractalContact(
        FractalSurface(D, G, args.M, gamma=args.gamma),
        pair,
        mu_t=args.mu_t,
        tangential_load=args.tangential_load,
        mass=args.mass,
    )
    rows = []
    print(f"{'load/N':>9} {'F_s/N':>10} {'K_tau/(N/m)':>12} {'C_tau/(Ns/m)':>12} {'z_max/nm':>9}")
    for load in args.load:
        out = model(load)
        row = {
            "load_N": load,
            "Fs_N": float(out.F_s),
            "Ktau_N_per_m": float(out.K_tau),
            "Ctau_Ns_per_m": float(out.C_tau),
            "zmax_m": float(out.z_max),
            "load_share": np.asarray(out.load_share).tolist(),
            "converged": bool(out.converged),
            "all_plastic": bool(out.all_plastic),
        }
        rows.append(row)
        print(
            f"{load:9.4g} {row['Fs_N']:10.4g} {row['Ktau_N_per_m']:12.4g} "
            f"{row['Ctau_Ns_per_m']:12.4g} {1e9 * row['zmax_m']:9.4g}"
        )
    result["contact"] = rows
    if args.json:
        write_json_atomic(Path(args.json), result)
        print(f"wrote {args.json}")
    return 0 if all(r["converged"] for r in rows) else 1


def _add_contact_parser(sub) -> None:
    con = sub.add_parser("contact", help="contact parameters from a topography file or D, G")
    con.add_argument("--topography", help="profile/height map (.csv, .txt, .npy, instrument files)")
    con.add_argument("--unit", default="m", help="length unit of a plain file (m, mm, um, nm)")
    con.add_argument("--dx", type=float, help="sampling interval (in --unit) for .npy/matrices")
    con.add_argument("--method", default="psd", choices=("psd", "structure", "rms"))
    con.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"), help="fit band, m")
    con.add_argument("--min-decades", type=float, default=1.0)
    con.add_argument("--D", type=float, help="surface fractal dimension (2, 3)")
    con.add_argument("--G", type=float, help="fractal roughness, m")
    con.add_argument("--load", type=float, nargs="+", required=True, help="normal load(s), N")
    for k, v in CONTACT_DEFAULTS.items():
        con.add_argument("--" + k.replace("_", "-"), dest=k, type=float, default=v)
    con.add_argument("--json", help="write the results to this JSON file")
    con.set_defaults(func=cmd_contact)


def _reproduce_wu2015(out_dir: Path) -> dict:
    """wu2015: both elements against Eq 7 (RMS over Ā in [0, 4.5]) and the C̄ peaks, + figure."""
    comparison = wu2015_comparison()
    for name in ("jenkins", "mindlin"):
        rms, peak = comparison["eq7_rms"][name], comparison["cbar_peak"][name]
        print(
            f"wu2015 {name}: RMS vs Eq 7 K̄ {rms['K']:.3f}, C̄ {rms['C']:.3f}; "
            f"C̄ peak {peak['Cbar']:.4f} at Ā = {peak['Abar']:.4f}"
        )
    out_dir.mkdir(parents=True, exist_ok=True)
    if plot_wu2015(comparison, out_dir / "wu2015.png"):
        print(f"wrote {out_dir / 'wu2015.png'}")
    return {"eq7_rms": comparison["eq7_rms"], "cbar_peak": comparison["cbar_peak"]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="tribojax", description="Rough-surface contact and friction models (JAX)."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    rep = sub.add_parser("reproduce", help="reproduce wang2022 Tables 3-7 and wu2015 K̄, C̄")
    rep.add_argument("--out", default="tribojax-out", help="output folder (default tribojax-out)")
    rep.set_defaults(func=cmd_reproduce)
    _add_contact_parser(sub)
    hys = sub.add_parser("hysteresis", help="K̄, C̄ of a Jenkins or Mindlin element (wu2015)")
    _hysteresis.add_arguments(hys)
    hys.set_defaults(func=_hysteresis.run_hysteresis)
    dis = sub.add_parser("discover", help="find the effect a slip run or loop's model is missing")
    _discover.add_arguments(dis)
    dis.set_defaults(func=_discover.run_discover)
    fit = sub.add_parser("fit", help="fit a slip run or hysteresis loop CSV (+ sidecar JSON)")
    _fit.add_arguments(fit)
    fit.set_defaults(func=_fit.run_fit)
    frf = sub.add_parser("frf", help="forced response of a structure with friction contacts")
    _frf.add_arguments(frf)
    frf.set_defaults(func=_frf.run_frf)
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
