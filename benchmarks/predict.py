"""Benchmark: a saved model predicting a record it never saw (`tribojax predict`, issues 29/30).

    python benchmarks/predict.py            # prints the table
    (also run by benchmarks/run.py, which includes these entries in benchmarks.json)

Case: LuGre and Jenkins (+ a force offset) fitted through the first 10,000 samples of the brfd
sine test `0.5Hz30lbtension1amplitude` (as benchmarks/real_data.py), saved (`tj.fitted_model`),
and evaluated on the whole Kocaeli earthquake history (28 s, 28,672 samples; ../shared/data/real,
skipped with a note if absent). tribojax: `tj.predict` warm (median of 3 after one call) and the
first call in this process; end to end: `tribojax predict fit.json RECORD` in a fresh process,
with an empty and then a warm compilation cache. Baseline: what a NumPy user would write, the
same element stepped through the samples by a Python loop (benchmarks/real_data.py's
`_force_numpy`: exact increments, one RK4 step per sample); the NRMSE of both is recorded.
Target (issue 30): ≤ 5 s warm for a 28 s history.
"""

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import tribojax as tj

sys.path.insert(0, str(Path(__file__).resolve().parent))
from real_data import SRC, TEST, N, _force_numpy  # noqa: E402

QUAKE = "earthquake_KocaeliDBE_30lb"
MODELS = ("jenkins", "lugre")


def _cli(model_file, record, cache) -> float:
    out = tempfile.mkdtemp()
    env = {**os.environ, "TRIBOJAX_CACHE_DIR": cache}
    cmd = [
        shutil.which("tribojax") or "tribojax",
        "predict",
        str(model_file),
        str(record),
        "--out",
        out,
        "--force",
    ]
    t = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, env=env)
    return time.perf_counter() - t


def run(quick=False):
    if not (SRC / f"{TEST}.json").exists() or not (SRC / f"{QUAKE}.json").exists():
        return [
            {
                "name": "predict (skipped)",
                "tribojax_s": None,
                "baseline_s": None,
                "ratio": None,
                "meets_target": None,
                "baseline": None,
                "baseline_note": f"{SRC} absent",
            }
        ]
    sine = tj.read_record(SRC / f"{TEST}.json")
    sine = tj.HysteresisLoop(sine.t[:N], sine.u[:N], sine.f[:N], source=sine.source, periodic=False)
    quake = tj.read_record(SRC / f"{QUAKE}.json")
    results = []
    for model in MODELS:
        saved = tj.fitted_model(tj.fit_history(sine, model, throw=False), str(SRC / f"{TEST}.json"))
        t = time.perf_counter()
        pred = tj.predict(saved, quake)
        first_s = time.perf_counter() - t
        times = []
        for _ in range(1 if quick else 3):
            t = time.perf_counter()
            tj.predict(saved, quake)
            times.append(time.perf_counter() - t)
        warm_s = statistics.median(times)
        p = list(saved.parameters.values())
        t = time.perf_counter()
        f_np = _force_numpy(model, p, quake.t, quake.u) + p[-1]
        base_s = time.perf_counter() - t
        nrmse_np = float(np.sqrt(np.mean((f_np - quake.f) ** 2)) / np.std(quake.f))
        with tempfile.TemporaryDirectory() as tmp:
            model_file = Path(tmp) / "fit.json"
            model_file.write_text(json.dumps({"fitted_model": saved.as_dict()}))
            cache = str(Path(tmp) / "cache")
            cold_s, cached_s = _cli(model_file, SRC / f"{QUAKE}.json", cache), None
            if not quick:
                cached_s = _cli(model_file, SRC / f"{QUAKE}.json", cache)
        results.append(
            {
                "name": f"predict {model} 28 s history",
                "tribojax_s": warm_s,
                "baseline_s": base_s,
                "ratio": base_s / warm_s,
                "meets_target": warm_s <= 5.0,
                "baseline": "NumPy loop of the same element (exact increments / RK4 per sample)",
                "first_call_s": first_s,
                "cli_empty_cache_s": cold_s,
                "cli_warm_cache_s": cached_s,
                "nrmse": pred.nrmse,
                "nrmse_numpy": nrmse_np,
                "n_samples": int(quake.t.size),
            }
        )
    return results


if __name__ == "__main__":
    for r in run(quick="--quick" in sys.argv):
        print({k: v for k, v in r.items() if k != "environment"})
