"""Study: which missing effect do wang2022's measured Tables 4–7 support? (issue 6, real data)

    python -m fitting.wang2022_discovery [--out DIR] [--short]

Runs the discovery workflow at table level: the published model (Table 3's F_s, K_τ, C_τ,
α = 1; wang2022 Eq 27) against the 24 measured phase slips, with six named candidates
(position_error ∝ stage travel, sensor_drift, gross_sliding at low load, load_coupling,
stribeck, viscous_friction). Relative (log) residuals; noise estimated from the data. Writes
DIR/wang2022_discovery.json and .png (default folder fitting-out/wang2022_discovery) and prints
the per-load residuals before and after, per table, so the reader can see where each effect
acts — in particular at 0.6 kPa (the paper: gross relative sliding) and at 20 kPa (the paper:
fibre bending, a position error).

Flagged cells (issue 19): the cells the robust full-chain fit flags as outliers (by default from
a fresh `tj.robust_fit_measured_slips()`, or `--flagged-from reproduction.json`). For each, the
study names the accepted effect that acts on it (`position_step` names the cell it moves;
`position_error`, `sensor_drift` act on every cell, `gross_sliding` on the lowest load) and
shows the fit with it added: the discovery's final model at that cell and the full-chain fit
of D, G, μ_t with a free step in that cell (identical to leaving the cell out).
`--short` offers only position_error, gross_sliding and position_step (for CI) and skips the
chain fits unless `flagged` is given.
"""

import argparse
import json
from pathlib import Path

import numpy as np

import tribojax as tj
import tribojax.discovery as disc
from tribojax import write_json_atomic

SHORT = ("position_error", "gross_sliding", "position_step")
LOWEST_LOAD_KPA = 0.6


def _acts_on(name: str, strengths: dict, table: int, kpa: float) -> bool:
    """Whether the accepted effect `name` moves the cell (table, kPa) of the tables."""
    if name == "position_step":
        nu = strengths.get("nuisance", {})
        return nu.get("table") == table and abs(nu.get("vacuum_kPa", -1) - kpa) < 1e-9
    if name == "gross_sliding":
        return abs(kpa - LOWEST_LOAD_KPA) < 1e-9
    return name in (
        "position_error",
        "sensor_drift",
        "load_coupling",
        "stribeck",
        "viscous_friction",
    )


def name_flagged(rep, cells: list[dict], flagged: list[dict]) -> list[dict]:
    """Per flagged cell: the accepted effect acting on it (a cell-specific one first) and the
    discovery fit at that cell before and after."""
    out = []
    for f in flagged:
        t, kpa = int(f["table"]), float(f["vacuum_kPa"])
        acting = [n for n in rep.effects if _acts_on(n, rep.strengths[n], t, kpa)]
        acting.sort(key=lambda n: n != "position_step")  # the cell's own effect first
        cell = next(c for c in cells if c["table"] == t and abs(c["vacuum_kPa"] - kpa) < 1e-9)
        entry = {
            "table": t,
            "vacuum_kPa": kpa,
            "effect": acting[0] if acting else "none",
            "effects_acting": acting,
            "measured_nm": cell["measured_nm"],
            "baseline_nm": cell["baseline_nm"],
            "with_effect_nm": cell["final_nm"],
        }
        if acting:
            entry["strengths"] = rep.strengths[acting[0]]
        if "standardized_residual" in f:
            entry["standardized_residual"] = f["standardized_residual"]
        out.append(entry)
    return out


def chain_fit_with_steps(flagged: list[dict], start=None) -> dict:
    """The full-chain least-squares fit (D, G, μ_t) with a free step in each flagged cell:
    a free additive term fits its cell exactly, so this is the fit with those cells left out
    (weight 1e-12)."""
    vac = list(tj.wang2022_table(3)["vacuum_kPa"])
    w = np.ones((6, 4))
    for f in flagged:
        w[vac.index(f["vacuum_kPa"]), int(f["table"]) - 4] = 1e-12
    fit = tj.fit_measured_slips(start, weights=w)
    keep = w == 1.0
    rel = fit.model_nm / fit.target_nm - 1.0
    paper = tj.wang2022_theory_slips() / fit.target_nm - 1.0
    return {
        "parameters": fit.parameters,
        "std_errors": dict(zip(fit.free, fit.fit.std_errors.tolist())),
        "converged": fit.converged,
        "rms_relative_residual_unflagged": float(np.sqrt(np.mean(rel[keep] ** 2))),
        "paper_theory_rms_relative_residual_unflagged": float(np.sqrt(np.mean(paper[keep] ** 2))),
        "model_nm": fit.model_nm.tolist(),
    }


def run(short: bool = False, flagged: list[dict] | None = None) -> dict:
    robust = None
    if flagged is None and not short:
        robust = tj.robust_fit_measured_slips()
        flagged = robust.flagged_cells()
    base = disc.wang2022_table_baseline()
    effects = disc.wang2022_table_effects()
    if short:
        effects = [e for e in effects if e.name in SHORT]
    rep = disc.discover(base, effects=effects, max_effects=3, n_windows=4)
    vac = rep.x[:6]
    before = rep.y - rep.baseline_y
    after = rep.y - rep.final_y
    per_cell = []
    for j, table in enumerate((4, 5, 6, 7)):
        for i in range(6):
            k = 6 * j + i
            per_cell.append(
                {
                    "table": table,
                    "vacuum_kPa": float(vac[i]),
                    "measured_nm": float(np.sign(base.measured[k]) * np.exp(rep.y[k])),
                    "baseline_nm": float(np.sign(base.measured[k]) * np.exp(rep.baseline_y[k])),
                    "final_nm": float(np.sign(base.measured[k]) * np.exp(rep.final_y[k])),
                    "log_residual_before": float(before[k]),
                    "log_residual_after": float(after[k]),
                }
            )
    out = rep.as_dict()
    out["cells"] = per_cell
    out["per_load_rms_log_residual"] = {
        f"{v:g} kPa": {
            "before": float(np.sqrt(np.mean(before[i::6] ** 2))),
            "after": float(np.sqrt(np.mean(after[i::6] ** 2))),
        }
        for i, v in enumerate(vac)
    }
    if flagged is not None:
        out["flagged_cells"] = name_flagged(rep, per_cell, flagged)
        if not short:
            start = robust.parameters if robust is not None else None
            out["chain_fit_with_steps"] = chain_fit_with_steps(flagged, start)
    out["_report"] = rep
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="fitting-out/wang2022_discovery")
    ap.add_argument("--short", action="store_true")
    ap.add_argument("--flagged-from", default=None, help="reproduction.json: its flagged cells")
    args = ap.parse_args(argv)
    flagged = None
    if args.flagged_from:
        flagged = json.loads(Path(args.flagged_from).read_text())["fit_measured"]["flagged_cells"]
    res = run(short=args.short, flagged=flagged)
    rep = res.pop("_report")
    out = Path(args.out)
    write_json_atomic(out / "wang2022_discovery.json", res)
    disc.plot_discovery(rep, out / "wang2022_discovery.png")
    print("wang2022 Tables 4-7 (measured) vs the published model (Table 3, alpha = 1)")
    print(rep.summary())
    print("per-load RMS of ln(measured/model): before -> after")
    for k, v in res["per_load_rms_log_residual"].items():
        print(f"  {k:>8}: {v['before']:.3f} -> {v['after']:.3f}")
    print("candidates (first round): name, score, p, delta_bic")
    for c in res["candidates"]:
        print(
            f"  {c['name']:>16}: S = {c['score']:.2f}, p = {c['p_value']:.2g}, "
            f"dBIC = {c['delta_bic']}"
        )
    for f in res.get("flagged_cells", []):
        print(
            f"flagged cell Table {f['table']} at {f['vacuum_kPa']:g} kPa: effect {f['effect']}; "
            f"measured {f['measured_nm']:.2f} nm, published model {f['baseline_nm']:.2f} nm, "
            f"with the effect {f['with_effect_nm']:.2f} nm"
        )
    if "chain_fit_with_steps" in res:
        c = res["chain_fit_with_steps"]
        print(
            f"full-chain fit with a step in each flagged cell: {c['parameters']}; rms rel. "
            f"residual over the other cells {c['rms_relative_residual_unflagged']:.3f} (paper "
            f"theory {c['paper_theory_rms_relative_residual_unflagged']:.3f})"
        )
    print(f"wrote {out / 'wang2022_discovery.json'}")
    return 0 if rep.converged else 3


if __name__ == "__main__":
    raise SystemExit(main())
