"""A second batch of two-effect records from the frozen blind generator (issue 32's "two effects
at once"), for evidence the first batch cannot give: of its seven two-effect records three were
examined while changing discovery (s3027, s5013, s5014), so they are no longer blind.

    python benchmarks/blind_pairs.py --out DIR        # records + DIR/manifest.json
    python benchmarks/blind_study.py DIR --out OUT     # scored as the first batch

The records are made by `benchmarks/blind/build.py` (frozen, unchanged); only the specs are new:
every pair of the five loop effects once (but microslip with backlash, which the generator
does not make: its clearance is written for the single Jenkins element), and four pairs of slip
effects, each with its contact or load, drive, strengths and noise drawn by a seeded generator
from the ranges of the first batch's catalog (`benchmarks/blind/catalog.py`). The draws were
fixed, and this file committed, before discovery was run on any of them; no setting is tuned on
them. Rows: benchmarks/blind_pairs_before.jsonl (the stop-51 code, eb84d0e) and
benchmarks/blind_pairs_after.jsonl (stop 52: loops with the pair step and the microslip shape,
slip runs with the pair step; the shape does not touch them); docs/discovery.md tabulates both.
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys

import numpy as np

BLIND = os.path.join(os.path.dirname(os.path.abspath(__file__)), "blind")
sys.path.insert(0, BLIND)

from build import build_loop, build_slip, loop_label, slip_label  # noqa: E402
from catalog import DRIFT_POLY, DRIFT_THERM, DRIFT_WALK  # noqa: E402
from recio import write_json, write_record  # noqa: E402

LOOP_SEED0, SLIP_SEED0 = 5100, 3100
LOOP_EFFECTS = ("microslip", "viscous_damping", "normal_load_variation", "backlash", "force_offset")
SLIP_PAIRS = (
    ("sensor_drift", "load_coupling"),
    ("position_error", "stribeck"),
    ("vibration", "viscous_friction"),
    ("load_coupling", "viscous_friction"),
)


def _loop_effect(name, rng):
    sign = float(rng.choice([-1.0, 1.0]))
    if name == "microslip":
        return {"n_elements": 200, "spread": 1.0}
    if name == "viscous_damping":
        return {"c_omega_A_over_muN": rng.uniform(0.05, 0.09)}
    if name == "normal_load_variation":
        quad = bool(rng.integers(2))
        return {
            "beta": sign * rng.uniform(0.12, 0.25),
            "beta2": rng.uniform(0.0, 0.1) * quad,
            "gamma": 0.0 if quad else 0.76,
        }
    if name == "backlash":
        return {"gap_over_A": rng.uniform(0.15, 0.4)}
    return {"offset_over_muN": sign * rng.uniform(0.05, 0.08)}


def _slip_effect(name, rng):
    sign = float(rng.choice([-1.0, 1.0]))
    if name == "sensor_drift":
        return dict((DRIFT_POLY, DRIFT_THERM, DRIFT_WALK)[rng.integers(3)]["sensor_drift"])
    if name == "position_error":
        return {"eps": 1.0e-7, "eps2_per_m": -1.0e-7 * float(rng.integers(2))}
    if name == "vibration":
        mode = ("accel", "jerk")[rng.integers(2)]
        gain = rng.uniform(5e-4, 2.5e-3) if mode == "accel" else rng.uniform(1e-4, 2.5e-4)
        return {
            "mode": mode,
            "f_n_Hz": rng.uniform(50.0, 150.0),
            "zeta": rng.uniform(0.02, 0.05),
            "gain": gain,
        }
    if name == "load_coupling":
        return {"kappa": sign * rng.uniform(0.3, 0.5)}
    if name == "stribeck":
        return {"delta": rng.uniform(0.3, 0.5), "vs_factor": rng.uniform(0.2, 0.5)}
    return {"sigma2_over_C": rng.uniform(200.0, 600.0)}


def specs():
    """(loop specs, slip specs) of the batch, in a fixed order."""
    rng = np.random.default_rng(20261202)
    loops = []
    pairs = [p for p in itertools.combinations(LOOP_EFFECTS, 2) if p != ("microslip", "backlash")]
    for k, pair in enumerate(pairs):
        drive = ("sine", "sine3", "rtri")[rng.integers(3)]
        spec = {
            "contact": f"C{rng.integers(1, 6)}",
            "drive": drive,
            "effects": {e: _loop_effect(e, rng) for e in pair},
            "noise_frac": rng.uniform(0.005, 0.015),
            "seed": LOOP_SEED0 + k,
            "noise_stated": k % 2 == 1,
        }
        if drive == "sine3":
            spec["h"] = 0.25
        loops.append(spec)
    slips = []
    for k, pair in enumerate(SLIP_PAIRS):
        slips.append(
            {
                "drive": "trapezoid",
                "vac": float(rng.choice([0.6, 2, 4, 7, 10, 20])),
                "mass_factor": 1.0,
                "effects": {e: _slip_effect(e, rng) for e in pair},
                "noise_frac": 0.01,
                "seed": SLIP_SEED0 + k,
                "noise_stated": k % 2 == 0,
            }
        )
    return loops, slips


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--loops-only", action="store_true", help="the loop records only")
    args = ap.parse_args(argv)
    loops, slips = specs()
    os.makedirs(args.out, exist_ok=True)
    jobs = [(f"loop_{k:03d}", build_loop, s) for k, s in enumerate(loops)]
    if not args.loops_only:
        jobs += [(f"slip_{k:03d}", build_slip, s) for k, s in enumerate(slips)]
    manifest = []
    for stem, builder, spec in jobs:
        rec = builder(spec)
        manifest.append(write_record(args.out, stem, rec))
        label = (loop_label if rec["kind"] == "loop" else slip_label)(spec)
        vis = ", ".join(f"{k} {v:.1f}" for k, v in rec["visibility_sd"].items())
        print(f"{stem} {label} {vis}", flush=True)
    write_json(os.path.join(args.out, "manifest.json"), manifest)


if __name__ == "__main__":
    main()
