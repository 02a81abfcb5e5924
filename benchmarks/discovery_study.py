"""Confusion study of `discover` on independent hidden-effect slip and loop records (issue 14).

    python benchmarks/discovery_study.py [--out DIR] [--subset ci] [--labels FILE]
        [--workers N | --scheduler-file F] [--force]

Records: `benchmarks.discovery_records.study_specs()` (slip runs, SciPy-generated) and
`benchmarks.discovery_loop_records.loop_study_specs()` (loops, own NumPy hysteresis models);
seeds in the specs.
Each record is written as a user's file (DIR/discovery_records/, CSV + sidecar) and discovered
by `tribojax.batch(files, "discover")` — `tribojax discover`'s defaults, one Dask worker process
a core (or an existing cluster), DIR/discovery_runs/<record>/discovery.json as the command writes
it; a rerun skips the records already discovered. Writes DIR/discovery_study.json (rows +
summary) and DIR/discovery_study.md (the confusion table).
Default DIR: benchmarks/ (the stored table that notebooks/05_discovery.ipynb reads).

Scoring (issue 14 targets):
- in-vocabulary: success when the effect is named first (`effect` equal to the hidden name,
  verdict explained or partly_explained) and the excess misfit at least halved;
  (also over the records whose baseline residual is not noise-consistent: "visible");
- clean: success when the verdict is "none";
- out-of-vocabulary: success when the verdict is neither "explained" nor "none".
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path

import numpy as np

import tribojax as tj
import tribojax.discovery as disc

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from benchmarks import discovery_loop_records as dlr  # noqa: E402
from benchmarks import discovery_records as dr  # noqa: E402

OUT_OF_VOCAB = (*dr.OUT_OF_VOCAB, *dlr.OUT_OF_VOCAB)

# the CI subset (records that pass in the stored study; the study itself is the measurement):
# CI_SHORT is the CI form of tests/test_discovery_verdict.py (slip: clean, a physics effect that
# the baseline cannot absorb, Stribeck, out of vocabulary; loops: a quadratic load variation at
# constant stiffness and a lag between the channels), TRIBOJAX_FULL=1 runs CI_LABELS. The slip
# record out of vocabulary is mains pickup (8 s); a readout step (96 s: every candidate refitted)
# runs in CI_LABELS and in notebook 05
CI_SHORT = (
    "clean/- 0.6kPa paper low s1066",
    "load_coupling/exponents_0.8_1.2 2kPa paper high est s1032",
    "stribeck/exponential 0.6kPa paper low s1036",
    "mains_pickup/- 0.6kPa",
    "loop:normal_load_variation/quadratic high est s2024",
    "loop:channel_lag/- low s2035",
    "vibration/accel_driven 2kPa fast low est s1020",
)
CI_LABELS = (
    *CI_SHORT,
    "readout_step/- 2kPa paper high est s1085",
    "loop:clean/- high est s2032",
    "loop:microslip/iwan_power high est s2006",
    "vibration/accel_driven 0.6kPa paper low s1016",
    "position_error/linear 2kPa fast low est s1060",
    "sensor_drift/thermal 0.6kPa paper low s1006",
)


def all_specs() -> list:
    """Every record of the study: the slip runs, then the loops."""
    return [*dr.study_specs(), *dlr.loop_study_specs()]


def score(spec, verdict, effect, e0, e1) -> bool:
    if spec.effect == "clean":
        return verdict == "none"
    if spec.effect in OUT_OF_VOCAB:
        return verdict not in ("explained", "none")
    return effect == spec.effect and e1 <= 0.5 * e0


def spec_noise(spec) -> float | None:
    """The noise sd a slip record was made with, m (loops: None, their sd scales with a drawn
    F_s)."""
    return None if getattr(spec, "kind", "slip") == "loop" else float(dr.NOISE[spec.noise])


def safe_name(label: str) -> str:
    """A record's file stem from its study label."""
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in label)


def write_record(spec, folder: Path) -> Path:
    """The spec's record as a user's file (CSV + sidecar, 17 digits: read back bit for bit)."""
    path = folder / f"{safe_name(spec.label)}.csv"
    if not path.exists():
        if getattr(spec, "kind", "slip") == "loop":
            tj.write_loop(dlr.make_loop_record(spec), path)
        else:
            tj.write_slip_run(dr.make_record(spec), path)
    return path


def run_one(spec) -> dict:
    """One record discovered in this process (`tribojax.discover` on its baseline, as the
    command does): its study row (the tests' form; the study itself runs `tribojax.batch`)."""
    loop = getattr(spec, "kind", "slip") == "loop"
    rec = dlr.make_loop_record(spec) if loop else dr.make_record(spec)
    t0 = time.perf_counter()
    rep = disc.discover_loop(rec) if loop else disc.discover(disc.slip_baseline(rec))
    return study_row(spec, rep.as_dict(), time.perf_counter() - t0)


def study_row(spec, rep: dict, wall: float) -> dict:
    """A study row from the record's discovery.json (`tribojax discover`'s answer)."""
    loop = getattr(spec, "kind", "slip") == "loop"
    sd = rep["noise_std"]
    row = {
        "label": spec.label,
        "kind": "loop" if loop else "slip",
        "effect_true": spec.effect,
        "shape": spec.shape,
        "load_kPa": None if loop else spec.load,
        "drive": "sine" if loop else spec.drive,
        "noise": spec.noise,
        "sidecar": spec.sidecar,
        "seed": spec.seed,
        "verdict": rep["verdict"],
        "effect": rep["effect"],
        "effects": list(rep["effects"]),
        "excess_before_sd": rep["excess_rmse_before"] / sd,
        "excess_after_sd": rep["excess_rmse_after"] / sd,
        "F_s": rep["baseline_fit"]["parameters"].get("F_s"),
        "converged": rep["converged"],
        "noise_std": sd,
        "noise_std_true": spec_noise(spec),
        "seconds": wall,
    }
    h0, h1 = rep["heldout_excess_before"], rep["heldout_excess_after"]
    row["heldout_before_sd"] = None if h0 is None else h0 / sd
    row["heldout_after_sd"] = None if h1 is None else h1 / sd
    misfit = rep["misfit"] or {}
    row["final_consistent"] = misfit.get("final_consistent")
    row["effects_dropped"] = list((rep["settings"] or {}).get("effects_dropped") or [])
    row["misfit_signals"] = [c["signal"] for c in misfit.get("correlations") or []]
    fix = misfit.get("correction") or {}
    row["correction"] = {k: fix.get(k) for k in ("signal", "gap_closed")} if fix else None
    row["ok"] = score(
        spec, rep["verdict"], rep["effect"], rep["excess_rmse_before"], rep["excess_rmse_after"]
    )
    return row


def summarise(rows) -> tuple[dict, str]:
    groups = collections.defaultdict(list)
    for r in rows:
        kind = (
            "clean"
            if r["effect_true"] == "clean"
            else "out_of_vocabulary"
            if r["effect_true"] in OUT_OF_VOCAB
            else "in_vocabulary"
        )
        groups[kind].append(r)
    # an in-vocabulary effect the baseline absorbs (baseline residual consistent with the noise:
    # e.g. the quasi-static part of a stiff mode, q ≈ −a/ω², is a slip ∝ a, taken up by K_τ)
    # has nothing left to find: counted apart as well. Re-run at 98df673 (a partial run of
    # the 35 stored failures): 9 in-vocabulary records are of this kind, baseline excess
    # 0.00-0.65 sd and verdict "none" (the same noise test that gives clean records 14/14
    # "none"): viscous linear s1047, s1049, power s1054; vibration s1017, s1018; Stribeck s1037,
    # s1038, s1042, s1043. Their hidden strength is drawn without regard to the load (e.g.
    # σ2 ≈ 12-20 C_τ at 2-10 kPa, where the slip is ≈ m·a/K_τ and ż ≈ v): the record holds
    # no misfit a method could name, so no method can pass them without failing clean records
    # too; likewise out-of-vocabulary s1083, s1095, s1099 ("none", excess 0.00-0.13 sd)
    groups["in_vocabulary_visible"] = [r for r in groups["in_vocabulary"] if r["verdict"] != "none"]
    # the same for effects outside the vocabulary: "none" says the baseline at its best optimum
    # passes the noise test (e.g. a 10 ms lag of the slip reading at 0.6 kPa, s1080: the plain
    # baseline at other F_s, K_τ, C_τ leaves 0.2 sd, p = 0.62), which no residual test can
    # tell from a clean record
    groups["out_of_vocabulary_visible"] = [
        r for r in groups.get("out_of_vocabulary", []) if r["verdict"] != "none"
    ]
    summary = {
        k: {
            "n": len(v),
            "success": sum(r["ok"] for r in v),
            "rate": sum(r["ok"] for r in v) / max(len(v), 1),
        }
        for k, v in groups.items()
    }
    # an "explained" verdict means the final residual passes the noise test: an excess left
    # there (e.g. 0.6 -> 0.3 sd) is at the noise floor of the excess estimate (≈ (2/n)^¼ σ ≈ 0.26σ
    # at n = 461); counted apart, the strict rule above stays the headline
    for k in ("in_vocabulary", "in_vocabulary_visible"):
        ok = [
            r["ok"] or (r["verdict"] == "explained" and r["effect"] == r["effect_true"])
            for r in groups[k]
        ]
        summary[k + "_explained_counts"] = {
            "n": len(ok),
            "success": sum(ok),
            "rate": sum(ok) / max(len(ok), 1),
        }
    verdicts = ("none", "explained", "partly_explained", "unexplained")
    lines = [
        "| hidden effect | n | first name (count) | none | explained | partly | unexpl. | "
        "success |",
        "|---|---|---|---|---|---|---|---|",
    ]
    by_effect = collections.defaultdict(list)
    for r in rows:
        prefix = "loop:" if r.get("kind") == "loop" else ""
        by_effect[
            prefix + r["effect_true"] + ("" if r["shape"] == "-" else "/" + r["shape"])
        ].append(r)
    for name, rs in by_effect.items():
        names = collections.Counter(r["effect"] for r in rs)
        cells = [str(sum(r["verdict"] == v for r in rs)) for v in verdicts]
        top = ", ".join(f"{k} ({c})" for k, c in names.most_common(3))
        lines.append(
            f"| {name} | {len(rs)} | {top} | "
            + " | ".join(cells)
            + f" | {sum(r['ok'] for r in rs)}/{len(rs)} |"
        )
    lines.append("")
    for k, v in summary.items():
        lines.append(f"- {k}: {v['success']}/{v['n']} ({100 * v['rate']:.0f} %)")
    fails = [r for r in rows if not r["ok"]]
    lines.append("")
    lines.append("Failing records:")
    for r in fails:
        lines.append(
            f"- {r['label']}: verdict {r['verdict']}, effect {r['effect']}, excess "
            f"{r['excess_before_sd']:.2f} -> {r['excess_after_sd']:.2f} sd"
        )
    return summary, "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent))
    ap.add_argument("--subset", choices=["all", "ci"], default="all")
    ap.add_argument(
        "--labels",
        help="file of record labels, one a line: run those (a re-run of chosen records; write "
        "it to another --out)",
    )
    ap.add_argument(
        "--workers", type=int, default=None, help="Dask worker processes (default: one a core)"
    )
    ap.add_argument(
        "--scheduler-file", default=None, help="run on an existing Dask cluster instead"
    )
    ap.add_argument("--force", action="store_true", help="discover every record again")
    args = ap.parse_args(argv)
    out = Path(args.out)
    specs = all_specs()
    if args.subset == "ci":
        specs = [s for s in specs if any(s.label.startswith(c) for c in CI_LABELS)]
    if args.labels:
        by_label = {s.label: s for s in specs}
        wanted = [x.strip() for x in Path(args.labels).read_text().splitlines() if x.strip()]
        missing = [x for x in wanted if x not in by_label]
        if missing:
            raise SystemExit(f"{args.labels}: labels not in study_specs(): {missing}")
        specs = [by_label[x] for x in wanted]
    # the records as a user's files, discovered by `tribojax batch discover` (one run per
    # record in DIR/discovery_runs/<stem>/; a rerun skips the records already complete)
    folder = out / "discovery_records"
    folder.mkdir(parents=True, exist_ok=True)
    files = [write_record(spec, folder) for spec in specs]
    client = None
    if args.scheduler_file:
        from distributed import Client

        client = Client(scheduler_file=args.scheduler_file)
    table = tj.batch(
        files,
        "discover",
        out=out / "discovery_runs",
        client=client,
        workers=args.workers,
        force=args.force,
    )
    rows = []
    for spec, result in zip(specs, table):
        if result["status"] != "ok":
            print(f"{spec.label}: {result['message']}", flush=True)
            continue
        rep = json.loads(
            (out / "discovery_runs" / safe_name(spec.label) / "discovery.json").read_text()
        )
        row = study_row(spec, rep, result["wall_s"])
        rows.append(row)
        print(
            f"{row['label']:55s} {row['verdict']:17s} {row['effect']:17s} "
            f"{row['excess_before_sd']:.2f}->{row['excess_after_sd']:.2f} "
            f"{'ok' if row['ok'] else 'FAIL'} {row['seconds']:.0f}s",
            flush=True,
        )
    summary, table = summarise(rows)
    total_s = float(np.sum([r["seconds"] for r in rows]))
    res = {
        "summary": summary,
        "rows": rows,
        "discover_seconds_total": total_s,
        "records_planned": len(all_specs()),
        "records_run": len(rows),
    }
    (out / "discovery_study.json").write_text(json.dumps(res, indent=1))
    (out / "discovery_study.md").write_text(table + "\n")
    print(table)
    return res


if __name__ == "__main__":
    main()
