"""Issue 68, deliverable 3: are discovery's answers stable under statistically invisible changes?

    python benchmarks/stability_study.py --out DIR [--variants perturbed lapack]
        [--subset ci] [--workers N]

The project study's records (`benchmarks/discovery_study.py`) discovered again by `tribojax
batch discover` in two variants, each compared with the reference run (`--reference`, default
the stored benchmarks/discovery_study.json, this machine, one-kernel arithmetic):

* perturbed: every measured column of every record moved by Gaussian noise of 1e-3 of its noise
  sd (the sidecar's stated noise for the output column, else a second-difference estimate of the
  column's noise: MAD/0.6745/√6), seed fixed per record; time is not touched;
* lapack: the records as they are, the workers' arithmetic switched to LAPACK's LU and XLA's
  default loops (`TRIBOJAX_XLA_HOIST=off`, the command line's other setting).

Writes DIR/stability_study.json: per variant the records whose verdict or effects differ from the
reference, the share identical, and the study scores of both; the table for docs/ and the note.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import zlib
from pathlib import Path

import numpy as np

import tribojax as tj
import tribojax.discovery as disc

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks import discovery_study as ds  # noqa: E402

HERE = Path(__file__).resolve().parent
SCALE = 1e-3  # of a column's noise sd
STATED = {"slip_m": "noise_std_m", "force_N": "noise_std_N"}  # output column: sidecar key


def column_noise(x: np.ndarray) -> float:
    """A column's noise sd from its second differences (a smooth signal drops out)."""
    d2 = np.diff(x, 2)
    return float(np.median(np.abs(d2 - np.median(d2))) / 0.6745 / np.sqrt(6.0))


def perturbed_copy(src: Path, dst: Path) -> None:
    """`src` (CSV + sidecar) copied to `dst` with its measured columns moved by `SCALE` of their
    noise sd; comment and header lines kept."""
    lines = src.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    body = [ln for ln in lines if not ln.startswith("#")]
    names = body[0].split(",")
    data = np.loadtxt(body[1:], delimiter=",", ndmin=2)
    side = json.loads(src.with_suffix(".json").read_text())
    rng = np.random.default_rng(zlib.crc32(src.stem.encode()))
    for j, name in enumerate(names[1:], start=1):
        sd = side.get(STATED.get(name, ""), None) or column_noise(data[:, j])
        data[:, j] += rng.normal(0.0, SCALE * sd, size=data.shape[0])
    rows = [",".join(f"{v:.17g}" for v in row) for row in data]
    dst.write_text("\n".join([*head, body[0], *rows]) + "\n")
    shutil.copyfile(src.with_suffix(".json"), dst.with_suffix(".json"))


def discovered_copies(label_end: str, folder: Path) -> list:
    """The study's slip record whose label ends with `label_end` (folder/a) and its perturbed
    copy (folder/b), each discovered as `tribojax discover` does (its baseline, the defaults):
    the two reports (the tests' form of one record's row of this study)."""
    spec = next(s for s in ds.all_specs() if s.label.endswith(label_end))
    src = ds.write_record(spec, folder / "a")
    (folder / "b").mkdir(exist_ok=True)
    perturbed_copy(src, folder / "b" / src.name)
    return [
        disc.discover(disc.slip_baseline(tj.read_record(p))) for p in (src, folder / "b" / src.name)
    ]


def compare(reference: list, rows: list) -> dict:
    """Records whose verdict or effects differ from the reference, and the share identical."""
    ref = {r["label"]: r for r in reference}
    same, differ = 0, []
    for r in rows:
        o = ref[r["label"]]
        if o["verdict"] == r["verdict"] and o["effects"] == r["effects"]:
            same += 1
        else:
            differ.append(
                {
                    "label": r["label"],
                    "reference": [o["verdict"], o["effects"], o["ok"]],
                    "variant": [r["verdict"], r["effects"], r["ok"]],
                }
            )
    return {"records": len(rows), "identical": same, "share": same / len(rows), "differ": differ}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--variants", nargs="+", default=["perturbed", "lapack"])
    ap.add_argument("--subset", choices=["all", "ci"], default="all")
    ap.add_argument("--reference", type=Path, default=HERE / "discovery_study.json")
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)
    reference = json.loads(args.reference.read_text())
    subset = ["--subset", args.subset]
    base = args.out / "records"
    base.mkdir(parents=True, exist_ok=True)
    specs = ds.all_specs()
    if args.subset == "ci":
        specs = [s for s in specs if any(s.label.startswith(c) for c in ds.CI_LABELS)]
    result = {"reference": str(args.reference), "scale": SCALE, "variants": {}}
    for variant in args.variants:
        out = args.out / variant
        folder = out / "discovery_records"
        folder.mkdir(parents=True, exist_ok=True)
        for spec in specs:
            src = ds.write_record(spec, base)
            dst = folder / src.name
            if variant == "perturbed" and not dst.exists():
                perturbed_copy(src, dst)
            elif variant != "perturbed" and not dst.exists():
                shutil.copyfile(src, dst)
                shutil.copyfile(src.with_suffix(".json"), dst.with_suffix(".json"))
        saved = os.environ.get("TRIBOJAX_XLA_HOIST")
        if variant == "lapack":  # the workers' arithmetic (`tribojax._cli._main.configure_process`)
            os.environ["TRIBOJAX_XLA_HOIST"] = "off"
        try:
            extra = [] if args.workers is None else ["--workers", str(args.workers)]
            res = ds.main(["--out", str(out), *subset, *extra])
        finally:
            if saved is None:
                os.environ.pop("TRIBOJAX_XLA_HOIST", None)
            else:
                os.environ["TRIBOJAX_XLA_HOIST"] = saved
        cmp = compare(reference["rows"], res["rows"])
        cmp["summary"] = res["summary"]
        result["variants"][variant] = cmp
        print(f"{variant}: {cmp['identical']}/{cmp['records']} identical", flush=True)
        for d in cmp["differ"]:
            print(f"  {d['label']}: {d['reference']} -> {d['variant']}", flush=True)
    result["reference_summary"] = reference["summary"]
    (args.out / "stability_study.json").write_text(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    main()
