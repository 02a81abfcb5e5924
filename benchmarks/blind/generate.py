"""Blind synthetic friction records (written from wang2022, wu2015 and a brief only).

usage: python benchmarks/blind/generate.py --out DIR [--only LABEL ...]
Writes slip_NNN.csv/.json and loop_NNN.csv/.json into DIR and DIR/manifest.json.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from build import build_loop, build_slip, loop_label, slip_label  # noqa: E402
from catalog import LOOP_SPECS, SLIP_SPECS  # noqa: E402
from recio import write_json, write_record  # noqa: E402


def all_jobs():
    """[(stem, label, builder, spec)] in a fixed order."""
    jobs = [(f"slip_{k:03d}", slip_label(s), build_slip, s) for k, s in enumerate(SLIP_SPECS)]
    jobs += [(f"loop_{k:03d}", loop_label(s), build_loop, s) for k, s in enumerate(LOOP_SPECS)]
    return jobs


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder")
    ap.add_argument("--only", nargs="+", metavar="LABEL", help="generate only these labels")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    jobs = all_jobs()
    labels = [j[1] for j in jobs]
    assert len(set(labels)) == len(labels), "labels must be unique"
    if args.only:
        unknown = set(args.only) - set(labels)
        if unknown:
            ap.error(f"unknown labels: {sorted(unknown)}")
        jobs = [j for j in jobs if j[1] in args.only]
    os.makedirs(args.out, exist_ok=True)
    manifest, t0 = [], time.time()
    for stem, label, builder, spec in jobs:
        rec = builder(spec)
        manifest.append(write_record(args.out, stem, rec))
        if not args.quiet:
            vis = ", ".join(f"{k} {v:.1f}" for k, v in rec["visibility_sd"].items())
            print(f"{time.time() - t0:6.1f}s {stem} {label} {vis}", flush=True)
    write_json(os.path.join(args.out, "manifest.json"), manifest)
    if not args.quiet:
        print(f"{len(manifest)} records in {time.time() - t0:.1f} s -> {args.out}")


if __name__ == "__main__":
    main()
