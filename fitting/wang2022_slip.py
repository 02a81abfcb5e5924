"""Study: the full-chain fit (D, G, μ_t → F_s, K_τ, C_τ → slips) to wang2022's measured Tables 4–7.

    python -m fitting.wang2022_slip [--out DIR] [--short] [--free D,G_m,mu_t]

Fits the free parameters from several distinct starts (optimistix Levenberg–Marquardt through
diffrax, forward mode), and records per start the optimum, standard errors, steps, wall time
(the first start includes compilation; the others run warm), plus the comparison the acceptance
asks for: RMS relative residual over the 24 measured cells for the fit, for the paper's own
theoretical values, and the bound that any model symmetric under a → −a can reach.
Writes DIR/wang2022_slip_fit.json (default folder: fitting-out/wang2022_slip). Progress is
printed per residual evaluation.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

import tribojax as tj

# (D, G m, μ_t): Table 1's D with the Table 3 calibration, and two distinct starts. Every start
# keeps F_s > m·a_max = 0.321 N at all six loads (no gross sliding, Eq 27's pre-sliding regime).
STARTS = (
    {k: tj.CHAIN_DEFAULTS[k] for k in ("D", "G_m", "mu_t")},  # the calibrated point
    {"D": 2.8, "G_m": 2e-8, "mu_t": 0.1},
    {"D": 2.75, "G_m": 3e-8, "mu_t": 0.11},
    # failed with the Kvaerno5 slip solver (a diverging stage Newton iteration under forward
    # mode); converges with Rodas4. A start that raises is recorded as an error, not dropped
    {"D": 2.95, "G_m": 1e-8, "mu_t": 0.12},
)
# short form (CI): two loads (0.6 and 7 kPa), G and μ_t free
SHORT_FREE = ("G_m", "mu_t")


def agreement(fits) -> dict:
    """Largest spread of the converged optima, in units of the best fit's standard errors."""
    ok = [f for f in fits if f.converged]
    if len(ok) < 2:
        return {"n_converged": len(ok), "max_spread_over_std_error": None}
    best = min(ok, key=lambda f: float(f.fit.residuals @ f.fit.residuals))
    values = np.array([f.fit.values for f in ok])
    spread = np.ptp(values, axis=0) / best.fit.std_errors
    return {
        "n_converged": len(ok),
        "max_spread_over_std_error": float(np.max(spread)),
        "spread_over_std_error": dict(zip(best.free, spread.tolist())),
        "rms_relative_residuals": [f.rms_relative_residual for f in ok],
    }


def run(starts=STARTS, free=tj.CHAIN_DEFAULT_FREE, loads=None, target=None, progress=True) -> dict:
    fits, records = [], []
    for i, start in enumerate(starts):
        print(f"start {i + 1}/{len(starts)}: {start}", file=sys.stderr, flush=True)
        try:
            f = tj.fit_measured_slips(
                start, free=free, loads=loads, target=target, progress=progress
            )
        except tj.ChainFitError as err:
            print(f"  -> FAILED: {err}", file=sys.stderr, flush=True)
            records.append({"start": start, "converged": False, "error": str(err)})
            continue
        fits.append(f)
        records.append(
            {
                "start": f.start,
                "end": f.parameters,
                "std_errors": dict(zip(f.free, f.fit.std_errors.tolist())),
                "rms_relative_residual": f.rms_relative_residual,
                "converged": f.converged,
                "message": f.fit.message,
                "steps": f.fit.steps,
                "residual_evaluations": f.evaluations,
                "gauss_newton_step_over_std_error": f.gauss_newton_step,
                "wall_s": f.wall_s,
            }
        )
        print(
            f"  -> {', '.join(f'{k} = {v:.5g}' for k, v in zip(f.free, f.fit.values))}; "
            f"RMS rel. {f.rms_relative_residual:.4f}; converged {f.converged}; "
            f"{f.fit.steps} steps; {f.wall_s:.1f} s",
            file=sys.stderr,
            flush=True,
        )
    if not fits:
        return {"starts": records, "agreement": agreement(fits)}
    best = min(fits, key=lambda f: float(f.fit.residuals @ f.fit.residuals))
    measured = tj.wang2022_measured_slips() if target is None else np.asarray(target)
    out = {
        "study": "wang2022 Tables 4-7 (measured): full-chain fit from several starts",
        "uncertainty_model": (
            "equal relative uncertainty per cell, estimated from the fit; residual = "
            "model/measured - 1"
        ),
        "best": best.as_dict(),
        "starts": records,
        "agreement": agreement(fits),
    }
    if target is None:
        out["paper_theory_rms_relative_residual"] = tj.rms_relative(
            tj.wang2022_theory_slips(), measured
        )
        out["symmetric_model_bound"] = tj.symmetric_bound(measured)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="fitting-out/wang2022_slip")
    parser.add_argument("--short", action="store_true", help="two loads, two parameters (CI)")
    parser.add_argument("--free", default=",".join(tj.CHAIN_DEFAULT_FREE))
    args = parser.parse_args(argv)
    out = Path(args.out)
    path = out / "wang2022_slip_fit.json"
    if path.exists():
        print(f"{path} exists: refusing to overwrite it (choose another --out)", file=sys.stderr)
        return 2
    if args.short:
        # two loads (0.6 and 7 kPa), measured cells, (G, μ_t) free: same code path, less cost
        loads = tj.wang2022_loads()[np.array([0, 3])]
        target = tj.wang2022_measured_slips()[[0, 3]]
        starts = [{**start, "D": STARTS[0]["D"]} for start in STARTS[:3]]  # same fixed D
        result = run(starts=starts, free=SHORT_FREE, loads=loads, target=target)
    else:
        result = run(free=tuple(args.free.split(",")))
    out.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=2))
    if "best" not in result:
        print("no start converged", file=sys.stderr)
        return 1
    best, agree = result["best"], result["agreement"]
    print(f"best: {best['parameters']} (converged {best['converged']})")
    print(f"std errors: {best['std_errors']}")
    print(f"RMS relative residual: {best['rms_relative_residual']:.4f}")
    if "paper_theory_rms_relative_residual" in result:
        print(f"paper theory:          {result['paper_theory_rms_relative_residual']:.4f}")
        print(
            f"any symmetric model >= {result['symmetric_model_bound']['rms_relative_residual']:.4f}"
        )
    print(f"starts agree: {agree}")
    print(f"wrote {path}")
    n_ok = result["agreement"]["n_converged"]
    return 0 if n_ok >= 3 or (args.short and n_ok >= 2) else 1


if __name__ == "__main__":
    raise SystemExit(main())
