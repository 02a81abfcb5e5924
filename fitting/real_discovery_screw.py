"""Study: discovery on the two screw drives' steady friction curves (issue 15, point 5).

    python -m fitting.real_discovery_screw --out DIR [--src PATH/TO/real]

For each drive (driveNo1: simple lead screw; driveNo2: anti-backlash lead screw with a preload
spring), the steady friction curve (one point per EPOS steady-state export, both directions) goes
to `tribojax.discovery.discover_curve`: the Coulomb + viscous baseline, the named effects
`stribeck`, `asymmetry`, `viscous`, each point weighted by its standard error. Reads the EPOS
folders `<src>/screwdrive/driveNo*/steady_state/0.096kg` when they are there, else the converted
copies `data/real/screwdrive/driveNo*_steady_0.096kg.csv` of this repository.

Physical expectation for a lubricated lead screw: velocity weakening at low speed (Stribeck:
F_s > F_c, v_s inside the measured speeds) and different levels in the two directions
(asymmetry: a load or preload that adds to the friction torque in one direction). Each row says
whether the named effects agree with that (`physical_sense`).

Writes DIR/real_discovery_screw.json (the rows) and DIR/real_discovery_<drive>.png.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np

import tribojax as tj
from tribojax.discovery import discover_curve, plot_curve_discovery

REPO = Path(__file__).resolve().parents[1]
COPIES = REPO / "data" / "real" / "screwdrive"
DRIVES = ("driveNo1", "driveNo2")


def load_curves(src) -> dict:
    """{drive: FrictionCurve}: the EPOS folders under `src`/screwdrive when present, else the
    converted copies in data/real."""
    out = {}
    for drive in DRIVES:
        folder = Path(src) / "screwdrive" / drive / "steady_state" / "0.096kg"
        if folder.is_dir():
            out[drive] = tj.read_record(folder)
        else:
            out[drive] = tj.read_record(COPIES / f"{drive}_steady_0.096kg.csv")
    return out


def _sense(rep, curve) -> str:
    """Do the named effects make physical sense for a lubricated lead screw?"""
    notes = []
    st = rep.strengths
    F_c = rep.final_fit["parameters"]["F_c"]
    speeds = np.abs(curve.velocity)
    if "stribeck" in st:
        a = st["stribeck"]["F_s_minus_F_c"]["value"]
        vs = st["stribeck"]["nuisance"]["v_s"]
        inside = speeds.min() <= vs <= speeds.max()
        ok = a > 0 and inside
        where = "inside" if inside else "outside"
        sense = "velocity weakening, as expected" if ok else "not a plain weakening"
        notes.append(
            f"stribeck: F_s - F_c = {a:.3g} ({100 * a / F_c:.0f} % of F_c), v_s = {vs:.3g} "
            f"{where} the measured speeds: {sense}"
        )
    else:
        notes.append("no stribeck named: no velocity weakening beyond the point errors")
    if "asymmetry" in st:
        t0 = st["asymmetry"]["T0"]["value"]
        notes.append(
            f"asymmetry: T0 = {t0:.3g} ({100 * abs(t0) / F_c:.0f} % of F_c), the directions "
            "differ by 2 T0: a load or preload on one direction, as expected"
        )
    else:
        notes.append("no asymmetry named")
    if "viscous" in st:
        d = float(np.exp(st["viscous"]["log_delta"]["value"]))
        notes.append(f"viscous: exponent {d:.2f} (1 = linear)")
    if rep.verdict in ("partly_explained", "unexplained"):
        fc = rep.misfit.get("correction") or {}
        notes.append(
            f"left: excess {rep.excess_rmse_after:.3g} beyond the point errors; "
            f"a term in {fc.get('signal', '?')} could close "
            f"{100 * fc.get('gap_closed', 0.0):.0f} % of it"
        )
    return "; ".join(notes)


def screwdrive_discovery(src, log, out=None) -> list[dict]:
    """Discovery on both screw drives (module docstring); one row per drive with the named
    effects, the verdict, the excess misfit before/after (friction unit), the strengths, the
    first round's candidates and a physical-sense note. Figures to `out` when given."""
    rows = []
    for drive, curve in load_curves(src).items():
        t0 = time.perf_counter()
        rep = discover_curve(curve)
        seconds = time.perf_counter() - t0
        d = rep.as_dict()
        row = {
            "drive": drive,
            "source": str(curve.source),
            "points": len(curve.velocity),
            "units": curve.units,
            "effect": d["effect"],
            "effects": d["effects"],
            "verdict": d["verdict"],
            "excess_rmse_before": d["excess_rmse_before"],
            "excess_rmse_after": d["excess_rmse_after"],
            "noise_std": d["noise_std"],
            "strengths": d["strengths"],
            "baseline_fit": d["baseline_fit"],
            "candidates": [
                {k: c[k] for k in ("name", "p_value", "delta_bic") if k in c}
                for c in d["candidates"]
            ],
            "misfit": d["misfit"],
            "physical_sense": _sense(rep, curve),
            "seconds": seconds,
        }
        if out is not None:
            fig = Path(out) / f"real_discovery_{drive}.png"
            if plot_curve_discovery(rep, curve, fig):
                row["figure"] = fig.name
        unit = curve.units["friction_unit"]
        log(
            f"{drive}: {', '.join(rep.effects) or 'none'} -> {rep.verdict}; excess "
            f"{rep.excess_rmse_before:.3g} -> {rep.excess_rmse_after:.3g} {unit} ({seconds:.1f} s)"
        )
        rows.append(row)
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("fitting-out/real_discovery_screw"))
    parser.add_argument("--src", type=Path, default=REPO.parent / "shared/data/real")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()

    def log(msg):
        print(f"[{time.perf_counter() - t0:7.1f} s] {msg}", flush=True)

    rows = screwdrive_discovery(args.src, log, args.out)
    tj.write_json_atomic(args.out / "real_discovery_screw.json", {"screwdrive": rows})
    print(json.dumps({"wrote": str(args.out / "real_discovery_screw.json")}))


if __name__ == "__main__":
    main()
