"""`tribojax reproduce`: wang2022 Tables 3-7 (published inputs and calibrated; slip at α = 1 and
fitted; the full-chain fit of D, G, μ_t to the measured slips) and wu2015 against Eq 7: JSON and
figures."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from .. import __version__
from .._plot import figure, save_figure
from .._reproduce import _chain_fit as chain_fit
from .._reproduce import _chain_result as tables
from .._reproduce import _robust_fit as robust_fit
from .._reproduce._fit_figure import plot_fit_measured
from .._reproduce._table3 import calibrate_table3, max_rel_error, reproduce_table3
from .._reproduce._tables4to7 import plot_figure10, print_tables4to7, reproduce_tables4to7
from .._reproduce._wu2015 import plot_wu2015, wu2015_comparison
from ._common import claim_outputs, progress, write_json_atomic


def _print_table3(rows) -> None:
    head = (
        f"{'kPa':>5} {'F/N':>8} | {'F_s paper':>9} {'calib':>7} {'publ.':>7} | "
        f"{'K_tau paper':>11} {'calib':>9} {'publ.':>9} | {'C_tau paper':>11} {'calib':>7} | "
        f"{'z_max paper':>11} {'calib':>7}"
    )
    print(head)
    print("-" * len(head))
    for r in rows:
        p, c, u = r["paper"], r["calibrated"], r["published_inputs"]
        print(
            f"{r['vacuum_kPa']:5.1f} {r['load_N']:8.4f} | {p['Fs_N']:9.4f} {c['Fs_N']:7.4f} "
            f"{u['Fs_N']:7.3f} | {p['Ktau_N_per_m']:11.4e} {c['Ktau_N_per_m']:9.3e} "
            f"{u['Ktau_N_per_m']:9.2e} | {p['Ctau_Ns_per_m']:11.2f} {c['Ctau_Ns_per_m']:7.1f} | "
            f"{p['zmax_nm']:11.3f} {c['zmax_nm']:7.3f}"
        )


def _plot_table3(rows, path: Path) -> bool:
    fig = figure("figure", figsize=(10, 7.5), constrained_layout=True)
    if fig is None:
        return False
    load = [r["load_N"] for r in rows]
    keys = [
        ("Fs_N", "max static friction F_s (N)"),
        ("Ktau_N_per_m", "tangential stiffness K_τ (N/m)"),
        ("Ctau_Ns_per_m", "tangential damping C_τ (N s/m)"),
        ("zmax_nm", "max tangential deformation z_max (nm)"),
    ]
    axes = fig.subplots(2, 2)
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


def _reproduce_fit_measured(result: dict, out_dir: Path | None = None, bar=None) -> bool:
    """The full-chain fits to the measured Tables 4–7 into result["fit_measured"]: the plain
    relative least-squares fit and the robust Student-t fit ("loss", "flagged_cells",
    "rms_relative_residual_unflagged", ..., and "robust"), one start each (the studies: the
    "*_study" keys); True if both converged. No per-evaluation progress lines (docs/cli.md,
    "Progress")."""
    print("wang2022 Tables 4-7 (measured): full-chain fit of D, G, mu_t (LM through diffrax) ...")
    fit = chain_fit.fit_measured_slips()
    block = fit.as_dict()
    measured, paper = tables.measured_slips(), tables.paper_theory_slips()
    block["paper_theory_rms_relative_residual"] = tables.rms_relative(paper, measured)
    block["symmetric_model_bound_rms_relative_residual"] = tables.symmetric_bound()[
        "rms_relative_residual"
    ]
    block["uncertainty_model"] = (
        "equal relative uncertainty per measured cell, estimated from the fit "
        "(residual = model/measured - 1); metric: RMS relative residual over the 24 cells"
    )
    block["multistart_study"] = "python -m fitting.wang2022_slip"
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
    result["fit_measured"] = block
    if not fit.converged:  # the robust fit starts from it: not attempted
        print(
            f"ERROR: the full-chain fit to the measured slips did not converge: {fit.fit.message}",
            file=sys.stderr,
        )
        return False
    if bar is not None:
        bar.step("robust fit")
    print("robust fit (Student-t maximum likelihood on the same engine) ...")
    t0 = time.perf_counter()
    robust = robust_fit.robust_fit_measured_slips(
        noise=robust_fit.HEADLINE_NOISE,
        floor_nm=robust_fit.HEADLINE_FLOOR_NM,
        nu=robust_fit.HEADLINE_NU,
        initial=fit,
    )
    rd = robust.as_dict()
    keep = ~robust.flagged
    for key in (
        "loss",
        "flagged_cells",
        "rms_relative_residual_unflagged",
        "paper_theory_rms_relative_residual_unflagged",
    ):
        block[key] = rd[key]
    block["plain_rms_relative_residual_unflagged"] = tables.rms_relative(
        fit.model_nm, measured, keep
    )
    block["robust"] = rd
    block["robust_study"] = "python -m fitting.wang2022_robust"
    flagged = ", ".join(
        f"Table {c['table']} at {c['vacuum_kPa']:g} kPa (z = {c['standardized_residual']:.1f})"
        for c in rd["flagged_cells"]
    )
    print(
        "robust fit: "
        + ", ".join(f"{k} = {rd['parameters'][k]:.4g}" for k in robust.free)
        + f"; flagged: {flagged or 'none'}; RMS rel. residual over the unflagged cells "
        f"{rd['rms_relative_residual_unflagged']:.3f} (paper theory "
        f"{rd['paper_theory_rms_relative_residual_unflagged']:.3f}, plain fit "
        f"{block['plain_rms_relative_residual_unflagged']:.3f}); converged: {robust.converged}, "
        f"{len(robust.history) - 1} rounds, {time.perf_counter() - t0:.1f} s"
    )
    fig_path = None if out_dir is None else out_dir / "fit_measured.png"
    if fig_path and plot_fit_measured(fit.model_nm, robust.model_nm, robust.flagged, fig_path):
        print(f"wrote {fig_path}")
    if not robust.converged:
        print(
            f"ERROR: the robust full-chain fit did not converge: {rd['result']} "
            f"({robust.chain.fit.message})",
            file=sys.stderr,
        )
    return robust.converged


def cmd_reproduce(args) -> int:
    """`tribojax reproduce`: 0 when every fit converged, else 1."""
    out_dir = Path(args.out)
    names = ("reproduction.json", "table3.png", "figure10.png", "wu2015.png")
    with claim_outputs(None, [out_dir / n for n in names], force=True):
        with progress(args, "reproduce", total=5) as bar:
            return _reproduce(out_dir, bar)


def _reproduce(out_dir: Path, bar) -> int:
    """The steps of `tribojax reproduce`; `bar` counts the five of them (a `Progress`)."""
    t0 = time.perf_counter()
    bar.note("Table 3 calibration")
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
    bar.step("Tables 4-7: slip simulations")
    _reproduce_slip_tables(result, out_dir)
    bar.step("full-chain fit to the measured slips")
    measured_ok = _reproduce_fit_measured(result, out_dir=out_dir, bar=bar)
    result["tribojax_version"] = __version__
    bar.step("wu2015 against Eq 7")
    result["wu2015"] = _reproduce_wu2015(out_dir)
    bar.step("writing")
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
