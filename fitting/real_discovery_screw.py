"""Study: discovery on the two screw drives' steady friction curves (issue 15, point 5).

    python -m fitting.real_discovery_screw --out DIR [--src PATH/TO/real]

For each drive (driveNo1: simple lead screw; driveNo2: anti-backlash lead screw with a preload
spring), the steady friction curve (one point per EPOS steady-state export, both directions) goes
to `tribojax batch discover` (the command's own curve discovery in a worker process,
`tribojax.batch`): the Coulomb + viscous baseline, the named effects
`stribeck`, `asymmetry`, `viscous`, each point weighted by its standard error. Reads the EPOS
folders `<src>/screwdrive/driveNo*/steady_state/0.096kg` when they are there, else the converted
copies `data/real/screwdrive/driveNo*_steady_0.096kg.csv` of this repository.

Physical expectation for a lubricated lead screw: velocity weakening at low speed (Stribeck:
F_s > F_c, v_s inside the measured speeds) and different levels in the two directions
(asymmetry: a load or preload that adds to the friction torque in one direction). Each row says
whether the named effects agree with that (`physical_sense`).

Writes DIR/real_discovery_screw.json (the rows) and DIR/discovery_screwdrive/<record>/ (the
command's discovery.json and discovery.png per drive).
"""

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import tribojax as tj

REPO = Path(__file__).resolve().parents[1]
COPIES = REPO / "data" / "real" / "screwdrive"
DRIVES = ("driveNo1", "driveNo2")


def curve_paths(src) -> dict:
    """{drive: path}: the EPOS folders under `src`/screwdrive when present, else the converted
    copies in data/real."""
    out = {}
    for drive in DRIVES:
        folder = Path(src) / "screwdrive" / drive / "steady_state" / "0.096kg"
        out[drive] = folder if folder.is_dir() else COPIES / f"{drive}_steady_0.096kg.csv"
    return out


def load_curves(src) -> dict:
    """{drive: FrictionCurve} read from `curve_paths`."""
    return {drive: tj.read_record(path) for drive, path in curve_paths(src).items()}


def _sense(d, curve) -> str:
    """Do the named effects make physical sense for a lubricated lead screw? (`d`: the run's
    discovery.json)"""
    notes = []
    st = d["strengths"]
    F_c = d["final_fit"]["parameters"]["F_c"]
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
    if d["verdict"] in ("partly_explained", "unexplained"):
        fc = d["misfit"].get("correction") or {}
        notes.append(
            f"left: excess {d['excess_rmse_after']:.3g} beyond the point errors; "
            f"a term in {fc.get('signal', '?')} could close "
            f"{100 * fc.get('gap_closed', 0.0):.0f} % of it"
        )
    return "; ".join(notes)


def screwdrive_discovery(src, log, out=None) -> list[dict]:
    """Discovery on both screw drives (module docstring) by `tribojax batch discover`
    (`tribojax.batch`), read back from each drive's discovery.json; one row per drive with the
    named effects, the verdict, the excess misfit before/after (friction unit), the strengths, the
    first round's candidates and a physical-sense note. The command's figures under `out`."""
    paths = curve_paths(src)
    with tempfile.TemporaryDirectory() as tmp:
        runs = Path(out or tmp) / "discovery_screwdrive"
        table = tj.batch(list(paths.values()), "discover", out=runs)
        rows = []
        for (drive, path), result in zip(paths.items(), table):
            if result["status"] != "ok":
                raise RuntimeError(f"{path}: {result['message']}")
            folder = runs / result["stem"]
            d = json.loads((folder / "discovery.json").read_text())
            curve = tj.read_record(path)
            row = {
                "drive": drive,
                "source": str(curve.source),
                "points": len(curve.velocity),
                "units": curve.units,
                **{k: d[k] for k in ("effect", "effects", "verdict", "excess_rmse_before")},
                **{k: d[k] for k in ("excess_rmse_after", "noise_std", "strengths")},
                "baseline_fit": d["baseline_fit"],
                "candidates": [
                    {k: c[k] for k in ("name", "p_value", "delta_bic") if k in c}
                    for c in d["candidates"]
                ],
                "misfit": d["misfit"],
                "physical_sense": _sense(d, curve),
                "seconds": result["wall_s"],
            }
            if out is not None and (folder / "discovery.png").is_file():
                row["figure"] = str((folder / "discovery.png").relative_to(out))
            unit = curve.units["friction_unit"]
            log(
                f"{drive}: {', '.join(d['effects']) or 'none'} -> {d['verdict']}; excess "
                f"{d['excess_rmse_before']:.3g} -> {d['excess_rmse_after']:.3g} {unit} "
                f"({result['wall_s']:.1f} s)"
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
