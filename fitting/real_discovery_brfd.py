"""Discovery on the brfd friction-damper records: what `tribojax discover FILE` names per test.

    python -m fitting.real_data --out DIR      # the "discovery" → "brfd" part of real_data.json

Each brfd test is run by `tribojax batch discover` (`tribojax.batch`: the command's own path,
one Dask worker process a core; `discover_brfd_test` is the same steps in this process):
`read_record`,
`decimate_record(..., whole_cycles=True)` to at most `DISCOVER_MAX_SAMPLES` samples (blocks of
≥ 4 samples, at least 256 per cycle; a loop whose cycles do not fit keeps its first whole
cycles), `loop_baseline` (the Jenkins element driven by the measured displacement; an
earthquake history is driven from its first sample) and `discover` with the default loop
effects. The full JSON files of `SRC/brfd/` (../shared/data/real) are used when present, else the
converted excerpts bundled in data/real/brfd (one sinusoidal test, the first 4096 samples of
one earthquake history).

Per test: the named effects (in order), the verdict, the excess misfit beyond the noise before
and after, the fitted backlash gap, where a misfit remains (flagged regions: branch and
displacement range) and a note on whether the named effects make physical sense for this rig (a
clearance at reversal is expected: the device has backlash).
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

import numpy as np

import tribojax as tj
from tribojax.discovery import discover, loop_baseline

BUNDLED = Path(__file__).resolve().parents[1] / "data" / "real"
INCH_M = 0.0254
BRANCH = {0: "unloading", 1: "loading"}

NOTES = {
    "backlash": "backlash: expected, the damper has a clearance at motion reversal",
    "force_offset": "force_offset: a zero offset of the force reading, or friction that differs "
    "between the two directions (both shift the loop as a whole); plausible for this rig",
    "microslip": "microslip: the gradual re-engagement at the end of the gap (a compliant stop) "
    "that a rigid clearance lacks; a weight w > 1 extrapolates the Mindlin law, so a shape term "
    "rather than partial slip of the band",
    "viscous_damping": "viscous_damping: a velocity-proportional force (hydraulic or rig "
    "damping); not expected in a dry friction band",
    "normal_load_variation": "normal_load_variation: band tension varying with rotation; "
    "possible in a banded device",
    "self_energizing": "self_energizing: the band's capstan rise towards slip, expected: the "
    "device is a self-energizing band brake",
    "direction_asymmetry": "direction_asymmetry: a band energized more in one direction, "
    "expected for a self-energizing band brake",
}
FIRST_EXPECTED = ("backlash", "self_energizing")  # the device's clearance or its band's rise
BAND_BRAKE_EFFECTS = ("self_energizing", "direction_asymmetry")
TRANSFER_TRAIN = "1Hz30lbtension1amplitude"
"""The sine test discovery is run on for `discovery_predicts` (chosen before any result: the
middle of the frequency and amplitude grid); every other record is scored, never fitted."""
WINDOWS_S = {
    "earthquake_ImperialValleyDBE_30lb": (3.0, 7.5),
    "earthquake_KocaeliDBE_30lb": (6.0, 14.0),
}
"""The dataset authors' scored windows (samples 3072–7679, 6144–14335 at 1024 Hz), in seconds."""


def brfd_files(src: Path) -> list[Path]:
    """The brfd tests: `src/brfd/*.json` when present, else the bundled CSV excerpts."""
    full = sorted((Path(src) / "brfd").glob("*.json"))
    return full if full else sorted((BUNDLED / "brfd").glob("*.csv"))


def _test_info(path: Path) -> dict:
    test = tj.brfd_test(path)  # from the file name (the bundled CSV keeps the JSON's stem)
    if test is None:
        return {"drive": "earthquake history"}
    return {
        "drive": "sinusoidal",
        "frequency_Hz": test["frequency_Hz"],
        "amplitude_in": round(test["amplitude_m"] / INCH_M, 6),
    }


def _where(misfit: dict, t) -> dict:
    """Where a misfit remains: the regions still flagged after the added effects (branch,
    displacement range in mm, time range in s, RMS over the noise sd), and the share of samples
    they cover."""
    regions = misfit.get("regions", [])
    rows = [
        {
            "branch": BRANCH.get(rg.get("branch"), rg.get("branch")),
            "u_min_mm": 1e3 * rg["u_min"],
            "u_max_mm": 1e3 * rg["u_max"],
            "t_s": [float(t[rg["i0"]]), float(t[rg["i1"] - 1])],
            "rms_over_noise": float(np.sqrt(rg["statistic"])),
            "p_value": rg["p_value"],
        }
        for rg in regions
    ]
    share = sum(rg["n"] for rg in regions) / max(len(t), 1)
    return {"share_of_samples": share, "regions": rows}


def physical_sense(effects) -> str:
    """A note on the named effects for a banded friction damper with backlash."""
    if not effects:
        return "nothing named: backlash was expected for this device"
    lines = [NOTES.get(e, e) for e in effects]
    if effects[0] not in FIRST_EXPECTED:
        lines.insert(
            0, "neither backlash nor the band's rise named first, though expected for this device"
        )
    return "; ".join(lines)


def discover_brfd_test(
    path: Path, *, record=None, factor=None, max_samples: int = tj.DISCOVER_MAX_SAMPLES
) -> dict:
    """One row of the table: `tribojax discover`'s steps on one brfd file in this process (or on
    `record`, e.g. an excerpt, named after `path`); `factor`: decimation blocks (None:
    automatic, as the CLI)."""
    t0 = time.perf_counter()
    record = tj.read_record(path) if record is None else record
    reduced, how = tj.decimate_record(record, factor, max_samples=max_samples, whole_cycles=True)
    baseline = loop_baseline(reduced)
    report = discover(baseline)
    t = np.asarray(baseline.t)
    return table_row(path, record, t, how, report.as_dict(), time.perf_counter() - t0)


def table_row(path, record, t, how, d: dict, seconds: float) -> dict:
    """A row of the table from a discovery's dictionary (discovery.json) on the record reduced
    by `decimate_record` (`how`); `t`: the times of its baseline's samples (what the flagged
    regions index)."""
    strengths = d.get("strengths", {})
    gap = strengths.get("backlash", {}).get("nuisance", {}).get("gap_m")
    depth = strengths.get("backlash", {}).get("depth", {}).get("value")
    return {
        "test": path.stem,
        "file": str(path),
        **_test_info(path),
        "samples_in_record": len(record.t),
        "samples": len(t),
        "decimation": how.as_dict(),
        "noise_sd_N": d.get("noise_std"),
        "effects": list(d["effects"]),
        "verdict": d["verdict"],
        "excess_rmse_before_N": d["excess_rmse_before"],
        "excess_rmse_after_N": d["excess_rmse_after"],
        "baseline_rmse_N": d["baseline_rmse"],
        "final_rmse_N": d["final_rmse"],
        "backlash_gap_mm": None if gap is None else 1e3 * gap,
        "first_round": [
            {k: c.get(k) for k in ("name", "p_value", "delta_bic")} for c in d["candidates"]
        ],
        "backlash_depth": depth,
        "strengths": strengths,
        "misfit": _where(d["misfit"], t),
        "physical_sense": physical_sense(d["effects"]),
        "converged": d["converged"],
        "seconds": seconds,
    }


def brfd_discovery(src, short: bool, log, out=None) -> list[dict]:
    """Discovery on every brfd test under `src` (the bundled excerpts without it); `short`: the
    tests at 1 Hz and above only. `tribojax batch discover` runs them (`tribojax.batch`, each
    test's discovery.json in `out`/discovery_brfd/<test>/, a temporary folder by default); one
    row per test (see the module docstring)."""
    files = [
        p
        for p in brfd_files(Path(src))
        if not (short and _test_info(p).get("frequency_Hz", 0.0) < 1.0)
    ]
    with tempfile.TemporaryDirectory() as tmp:
        runs = Path(out or tmp) / "discovery_brfd"
        table = tj.batch(files, "discover", out=runs)
        rows = []
        for path, result in zip(files, table):
            if result["status"] != "ok":
                raise RuntimeError(f"{path}: {result['message']}")
            d = json.loads((runs / path.stem / "discovery.json").read_text())
            record = tj.read_record(path)
            reduced, how = tj.decimate_record(
                record, None, max_samples=tj.DISCOVER_MAX_SAMPLES, whole_cycles=True
            )
            t = np.asarray(loop_baseline(reduced).t)  # (cheap: no fit)
            row = table_row(path, record, t, how, d, result["wall_s"])
            rows.append(row)
            gap = row["backlash_gap_mm"]
            log(
                f"discover {row['test']:34s} {'+'.join(row['effects']) or 'none':36s} "
                f"{row['verdict']:16s} excess {row['excess_rmse_before_N']:.3g} -> "
                f"{row['excess_rmse_after_N']:.3g} N"
                + ("" if gap is None else f", gap {gap:.3g} mm")
                + f" ({row['seconds']:.1f} s)"
            )
    return rows


def discovery_predicts(src, log, train: str = TRANSFER_TRAIN) -> dict:
    """Discovery on one sine test (`train`, the CLI's path), with the loop vocabulary without
    and with the band brake's effects (`BAND_BRAKE_EFFECTS`); each discovered model then
    predicts every other brfd record of `src` (`tribojax.predict`, nothing refitted; a loop
    model is compared from a record's first reversal on) and the earthquake windows
    (`WINDOWS_S`, on the predicted samples inside them), the histories from rest and from the
    state of their first measured force (`initial="measured"`). Returns {"train",
    "vocabularies": {name: {"effects", "excess_before/after", "heldout_excess_before/after",
    "records": {test: {"nrmse", "window_nrmse", "window_coverage", ..._measured_start}}}}}."""
    files = brfd_files(Path(src))
    path = next(p for p in files if p.stem == train)
    reduced, _ = tj.decimate_record(
        tj.read_record(path), None, whole_cycles=True, max_samples=tj.DISCOVER_MAX_SAMPLES
    )
    vocab = {
        "without band-brake effects": [
            e for e in tj.discovery.default_effects("loop") if e.name not in BAND_BRAKE_EFFECTS
        ],
        "with band-brake effects": None,
    }
    out = {"train": train, "vocabularies": {}}
    for name, effects in vocab.items():
        t0 = time.perf_counter()
        report = discover(loop_baseline(reduced), effects=effects)
        row = {
            "effects": list(report.effects),
            "verdict": report.verdict,
            "strengths": report.as_dict()["strengths"],
            "excess_before_N": report.excess_rmse_before,
            "excess_after_N": report.excess_rmse_after,
            "heldout_excess_before_N": report.heldout_excess_before,
            "heldout_excess_after_N": report.heldout_excess_after,
            "records": {},
        }
        for other in files:
            if other.stem == train:
                continue
            record = tj.read_record(other)
            pred = tj.predict(report.fitted, record)
            rec = {"nrmse": pred.nrmse}
            if other.stem in WINDOWS_S:  # a history: also from its first measured force
                rec.update(_window(pred, other.stem))
                loaded = tj.predict(report.fitted, record, initial="measured")
                rec["nrmse_measured_start"] = loaded.nrmse
                rec.update(
                    {f"{k}_measured_start": v for k, v in _window(loaded, other.stem).items()}
                )
            row["records"][other.stem] = rec
        row["seconds"] = time.perf_counter() - t0
        out["vocabularies"][name] = row
        log(
            f"discover {train} ({name}): {'+'.join(row['effects']) or 'none'}, excess "
            f"{row['excess_before_N']:.3g} -> {row['excess_after_N']:.3g} N (held out "
            f"{row['heldout_excess_before_N']:.3g} -> {row['heldout_excess_after_N']:.3g}); "
            "predicted: " + ", ".join(f"{k} {v['nrmse']:.3f}" for k, v in row["records"].items())
        )
    return out


def _window(pred, name) -> dict:
    """NRMSE of a prediction on the scored window of history `name` (the predicted samples in
    it) and the share of the window's samples predicted."""
    lo, hi = WINDOWS_S[name]
    inside = (pred.x >= lo) & (pred.x < hi)
    m, p = pred.measured[inside], pred.predicted[inside]
    return {
        "window_nrmse": float(np.sqrt(np.mean((p - m) ** 2)) / np.std(m)),
        "window_coverage": float(inside.sum() / round((hi - lo) * 1024)),
    }


def transfer_table(result) -> str:
    """Markdown table of `discovery_predicts`: NRMSE per record not fitted, per vocabulary."""
    names = list(result["vocabularies"])
    rows = ["| record (not fitted) | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
    first = result["vocabularies"][names[0]]["records"]
    for test in first:
        cells = []
        for n in names:
            r = result["vocabularies"][n]["records"][test]
            w = (
                f"; window {r['window_nrmse']:.3f}; from the first force: "
                f"{r['nrmse_measured_start']:.3f}, window {r['window_nrmse_measured_start']:.3f}"
                if "window_nrmse" in r
                else ""
            )
            cells.append(f"{r['nrmse']:.3f}{w}")
        rows.append(f"| {test} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def table(rows) -> str:
    """Markdown table of the rows (test, effects, verdict, excess before/after, gap)."""
    out = [
        "| test | named effects | verdict | excess before (N) | after (N) | gap (mm) |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        gap = "" if r["backlash_gap_mm"] is None else f"{r['backlash_gap_mm']:.3g}"
        out.append(
            f"| {r['test']} | {', '.join(r['effects']) or 'none'} | {r['verdict']} | "
            f"{r['excess_rmse_before_N']:.0f} | {r['excess_rmse_after_N']:.0f} | {gap} |"
        )
    return "\n".join(out)


if __name__ == "__main__":
    import json
    import sys

    shared = Path(__file__).resolve().parents[1].parent / "shared/data/real"
    t_start = time.perf_counter()

    def log(m):
        print(f"[{time.perf_counter() - t_start:7.1f} s] {m}", flush=True)

    if sys.argv[1:2] == ["--predicts"]:  # discovery on one sine, predictions of the others
        result = discovery_predicts(shared, log)
        if len(sys.argv) > 2:
            Path(sys.argv[2]).write_text(json.dumps(result, indent=1, default=float))
        print(transfer_table(result))
    else:
        result = brfd_discovery(shared, False, log)
        print(table(result))
        print(np.round([r["seconds"] for r in result], 1))
