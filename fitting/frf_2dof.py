"""Study: forced responses of the 2-DOF elastic dry-friction benchmark by MHB + continuation.

    python -m fitting.frf_2dof [--out DIR] [--short]

The benchmark of the harmonic-balance literature (tmdsimpy's and NLvib's examples): DOF 0
tangential, DOF 1 normal, both against ground; M = I₂, K = diag(12, 21),
C = diag(2·0.05·√12, 2·0.1·√100); contact f_n = max(21·u_n, 0), tangential elastic predictor
5·Δu_t clipped to ±0.85·f_n; static force (0, 100) N, cosine force (1, 0.1)·F for
F ∈ {0.5, 1, 10, 25, 50, 80, 100, 300} N; harmonics 0–8; ω from 0.01 to 6 rad/s
(`tribojax.frf_2dof_system`). Each curve is continued by pseudo-arclength with Hill stability,
and checked against time integration to steady state (`tribojax.integrate_steady`, from rest,
no harmonic balance) at three frequencies around its peak.

Writes DIR/frf_2dof.json (default fitting-out/frf_2dof): per F (key str(F)) "omega" (rad/s),
"amplitude" ([[dof0, dof1], ...], first-harmonic amplitude, m), "stable", "result", and
"time_check" (ω, MHB and time-integration amplitudes of DOF 0, relative difference); timings.
`--short`: F ∈ {1, 50, 300} and one check point each.
"""

import argparse
import time
from pathlib import Path

import numpy as np

import tribojax as tj


def time_check(system, fr, n_points=3, periods=150, steps=1024):
    """MHB vs time integration at points around the peak of DOF 0 (relative amplitude error)."""
    i_peak = int(np.argmax(fr.amplitude[:, 0]))
    picks = sorted({max(i_peak - 5, 0), i_peak, min(i_peak + 5, len(fr.omega) - 1)})
    picks = picks[:n_points] if n_points < 3 else picks
    if n_points == 1:
        picks = [i_peak]
    rows = []
    for i in picks:
        w = float(fr.omega[i])
        x = np.asarray(tj.integrate_steady(system, w, periods, steps))
        th = 2 * np.pi * np.arange(steps) / steps
        amp = np.hypot(2 * np.mean(x[:, 0] * np.cos(th)), 2 * np.mean(x[:, 0] * np.sin(th)))
        mhb = float(fr.amplitude[i, 0])
        rel = abs(mhb - amp) / amp
        rows.append({"omega": w, "mhb": mhb, "time_integration": amp, "rel_diff": rel})
    return rows


def run(forces=tj.FRF_2DOF["F"], n_check=3, ds_max=0.1) -> dict:
    w0, w1 = tj.FRF_2DOF["omega_range"]
    out, timings = {}, {}
    for F in forces:
        system = tj.frf_2dof_system(F)
        t0 = time.perf_counter()
        fr = tj.frequency_response(system, w0, w1, ds_max=ds_max, max_points=1000)
        timings[str(F)] = time.perf_counter() - t0
        entry = fr.to_dict()
        entry["amplitude"] = fr.amplitude.tolist()
        entry["peak_omega"], entry["peak_amplitude"] = fr.peak(0)
        entry["time_check"] = time_check(system, fr, n_check)
        out[str(F)] = entry
        print(
            f"F = {F:6g}: {len(fr.omega):4d} points, {entry['result']}, peak "
            f"{entry['peak_amplitude']:.4g} at {entry['peak_omega']:.4f} rad/s, unstable "
            f"{int((~fr.stable).sum())}, max |MHB − time| / time "
            f"{max(r['rel_diff'] for r in entry['time_check']):.2e}, {timings[str(F)]:.2f} s"
        )
    return {"curves": out, "timings_s": timings, "benchmark": dict(tj.FRF_2DOF)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="fitting-out/frf_2dof")
    ap.add_argument("--short", action="store_true")
    args = ap.parse_args(argv)
    res = run((1.0, 50.0, 300.0), n_check=1) if args.short else run()
    res_flat = dict(res["curves"])
    res_flat["_meta"] = {"timings_s": res["timings_s"], "benchmark": res["benchmark"]}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tj.write_json_atomic(out / "frf_2dof.json", res_flat)
    print(f"wrote {out / 'frf_2dof.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
